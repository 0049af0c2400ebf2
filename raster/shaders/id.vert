#version 460
// Shared by the shadow pass (clipFromWorld = the light's layer) and the camera visibility pass.
layout(location = 0) in vec3 inPositionWorld;
layout(location = 1) in vec2 inUv;

layout(push_constant) uniform Draw {
  mat4 clipFromWorld;
  uint objectIndex;   // index into the scene's objects
  uint triangleBase;  // first triangle of this object in the global triangle tables
  uint pad0;
  uint pad1;
} draw;

layout(location = 0) out vec2 outUv;

void main() {
  gl_Position = draw.clipFromWorld * vec4(inPositionWorld, 1.0);
  outUv = inUv;
}
