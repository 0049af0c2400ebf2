#version 460
// id.vert without the uv varying, for draws that need no alpha test (id_plain.frag): lavapipe sets
// up every varying of every triangle, read or not.
layout(location = 0) in vec3 inPositionWorld;

layout(push_constant) uniform Draw {
  mat4 clipFromWorld;
  uint objectIndex;
  uint triangleBase;
  uint pad0;
  uint pad1;
} draw;

void main() { gl_Position = draw.clipFromWorld * vec4(inPositionWorld, 1.0); }
