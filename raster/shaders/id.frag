#version 460
#extension GL_GOOGLE_include_directive : require
#define SHADOWLAB_ABI_NO_PARAMS
#include "shadowlab/raster/resolve_abi.h"
// Writes the global triangle index + 1 (0: nothing drawn) beside the depth, one uint: the global
// index (the object's triangle base + its primitive id) lets the resolve pass find the triangle's
// plane with one fetch; the readback turns it back into the object and its primitive id. One
// 32-bit channel rather than (object, triangle): half the bytes to clear, write and fetch. The
// material tests (alpha cutoff, one-sided back faces): id_material.glsl.
// false: a plain id writer (no discard, so early depth testing stays on); the rasterizer picks
// it for draws that need no alpha test and whose back faces the hardware cull already removes.
layout(constant_id = 0) const bool kMaterialTests = true;

layout(location = 0) in vec2 uv;
layout(location = 0) out uint outId;

layout(push_constant) uniform Draw {
  mat4 clipFromWorld;
  uint objectIndex;
  uint triangleBase;
  uint pad0;
  uint pad1;
} draw;

#include "id_material.glsl"

void main() {
  uint triangle = draw.triangleBase + uint(gl_PrimitiveID);
  if (kMaterialTests && failsMaterialTests(triangle, uv)) discard;
  outId = triangle + 1u;
}
