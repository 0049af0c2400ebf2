#version 460
#extension GL_GOOGLE_include_directive : require
#define SHADOWLAB_ABI_NO_PARAMS
#include "shadowlab/raster/resolve_abi.h"
// Writes the global triangle index + 1 (0: nothing drawn) beside the depth, one uint: the global
// index (the object's triangle base + its primitive id) lets the resolve pass find the triangle's
// plane with one fetch; the readback turns it back into the object and its primitive id. One
// 32-bit channel rather than (object, triangle): half the bytes to clear, write and fetch. Alpha-tested materials discard
// below their cutoff, sampling the alpha texture exactly like scenes' sampleAlphaNearest
// (nearest texel, repeat addressing, texel (0,0) top-left) so both renderers agree on holes.
// One-sided materials discard back faces (as seen from the camera or the light).
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

struct MaterialGpu {
  uint alphaOffset;  // first texel in alphaTexels
  uint width;
  uint height;
  uint flags;        // bit 0: two-sided, bit 1: alpha-tested
  float cutoff;
  float pad0;
  float pad1;
  float pad2;
};

layout(std430, set = 0, binding = kBindingTriangleMaterials) readonly buffer TriangleMaterials { uint triangleMaterial[]; };
layout(std430, set = 0, binding = kBindingMaterials) readonly buffer Materials { MaterialGpu materials[]; };
layout(std430, set = 0, binding = kBindingAlphaTexels) readonly buffer AlphaTexels { float alphaTexels[]; };

void main() {
  if (!kMaterialTests) {
    outId = draw.triangleBase + uint(gl_PrimitiveID) + 1u;
    return;
  }
  MaterialGpu m = materials[triangleMaterial[draw.triangleBase + uint(gl_PrimitiveID)]];
  if ((m.flags & 1u) == 0u && !gl_FrontFacing) discard;
  if ((m.flags & 2u) != 0u) {
    int w = int(m.width), h = int(m.height);
    int x = clamp(int(floor(fract(uv.x) * float(w))), 0, w - 1);
    int y = clamp(int(floor(fract(uv.y) * float(h))), 0, h - 1);
    if (alphaTexels[m.alphaOffset + uint(y * w + x)] < m.cutoff) discard;
  }
  outId = draw.triangleBase + uint(gl_PrimitiveID) + 1u;
}
