#version 460
// id.vert for light layers whose depth is the light's own, not the layer matrix's z / w
// (fit=tsm, raster/METHODS.md): x, y, w from the warped clipFromWorld, and the light's depth
// dot(depthRow, p) as a varying. It is affine in p, so the perspective-correct interpolation
// gives each fragment its exact value; id_light_depth.frag writes it as the fragment's depth.
layout(location = 0) in vec3 inPositionWorld;
layout(location = 1) in vec2 inUv;

layout(push_constant) uniform Draw {
  mat4 clipFromWorld;
  uint objectIndex;
  uint triangleBase;
  uint pad0;
  uint pad1;
  vec4 depthRow;   // the light's depth = dot(depthRow, (p, 1))
  vec4 depthBias;  // x bias.constant * r (0 for a float format: y, z as Vulkan), y bias.slope, z bias.clamp, w float format
} draw;

layout(location = 0) out vec2 outUv;
layout(location = 1) out float outLightDepth;

void main() {
  gl_Position = draw.clipFromWorld * vec4(inPositionWorld, 1.0);
  outUv = inUv;
  outLightDepth = dot(draw.depthRow, vec4(inPositionWorld, 1.0));
}
