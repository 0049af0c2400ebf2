#version 460
// id.frag for draws without alpha-tested or one-sided materials (or whose back faces the hardware
// cull removes): the global triangle index + 1, no discard, so early depth testing stays on.
layout(location = 0) out uint outId;

layout(push_constant) uniform Draw {
  mat4 clipFromWorld;
  uint objectIndex;
  uint triangleBase;
  uint pad0;
  uint pad1;
} draw;

void main() { outId = draw.triangleBase + uint(gl_PrimitiveID) + 1u; }
