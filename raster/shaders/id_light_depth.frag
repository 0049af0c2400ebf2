#version 460
#extension GL_GOOGLE_include_directive : require
#define SHADOWLAB_ABI_NO_PARAMS
#include "shadowlab/raster/resolve_abi.h"
// id.frag for light layers whose depth is the light's own
// (id_light_depth.vert): the fragment's depth is the interpolated light depth plus the depth bias.
// Writing the depth replaces the rasterizer's depth bias (Vulkan applies it to the rasterized
// depth, which the written value replaces), so the bias is Vulkan's formula here:
// o = constant * r + slope * m, m = max(|d depth / dx|, |d depth / dy|) per texel, clamped as
// depthBiasClamp clamps; r of a float format from the depth's exponent (2^(e - 23)).
// As id.frag's: false for draws that need no material test (the tests' buffer reads cost about
// as much as the rest of this shader on lavapipe).
layout(constant_id = 0) const bool kMaterialTests = true;

layout(location = 0) in vec2 uv;
layout(location = 1) in float lightDepth;
layout(location = 0) out uint outId;

layout(push_constant) uniform Draw {
  mat4 clipFromWorld;
  uint objectIndex;
  uint triangleBase;
  uint pad0;
  uint pad1;
  vec4 depthRow;
  vec4 depthBias;
} draw;

#include "id_material.glsl"

void main() {
  uint triangle = draw.triangleBase + uint(gl_PrimitiveID);
  if (kMaterialTests && failsMaterialTests(triangle, uv)) discard;
  float constantTerm = draw.depthBias.w > 0.5 ? draw.depthBias.x * exp2(floor(log2(max(abs(lightDepth), 1e-30))) - 23.0)
                                              : draw.depthBias.x;
  float o = constantTerm + draw.depthBias.y * max(abs(dFdx(lightDepth)), abs(dFdy(lightDepth)));
  if (draw.depthBias.z > 0.0) o = min(o, draw.depthBias.z);
  if (draw.depthBias.z < 0.0) o = max(o, draw.depthBias.z);
  gl_FragDepth = lightDepth + o;
  outId = triangle + 1u;
}
