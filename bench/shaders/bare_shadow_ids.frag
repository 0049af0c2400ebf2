#version 460
// The shadow pass with the id attachment shadowlab's evidence needs beside the depth: what writing which primitive
// made each texel costs over depth only (shadowlab writes the global triangle + 1 the same way).
layout(location = 0) out uint outId;
void main() { outId = uint(gl_PrimitiveID) + 1u; }
