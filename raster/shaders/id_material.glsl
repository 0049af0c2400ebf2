// The material tests of the id writers (id.frag, id_light_depth.frag): alpha-tested materials
// discard below their cutoff, sampling the alpha texture exactly like scenes' sampleAlphaNearest
// (nearest texel, repeat addressing, texel (0,0) top-left) so both renderers agree on holes;
// one-sided materials discard back faces (as seen from the camera or the light).
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

// Whether the fragment of global triangle `triangle` at texture coordinate uv fails its material.
bool failsMaterialTests(uint triangle, vec2 uv) {
  MaterialGpu m = materials[triangleMaterial[triangle]];
  if ((m.flags & 1u) == 0u && !gl_FrontFacing) return true;
  if ((m.flags & 2u) != 0u) {
    int w = int(m.width), h = int(m.height);
    int x = clamp(int(floor(fract(uv.x) * float(w))), 0, w - 1);
    int y = clamp(int(floor(fract(uv.y) * float(h))), 0, h - 1);
    if (alphaTexels[m.alphaOffset + uint(y * w + x)] < m.cutoff) return true;
  }
  return false;
}
