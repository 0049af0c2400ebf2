#version 460
// Moments pass, part 1 (filterable maps: filter=vsm, evsm2, evsm4, msm): per texel of one light
// layer, the moments of the map depths along its row, weighted by the Gaussian of filter.blur
// (radius r texels, sigma r / 2; r = 0: the texel's own moments). Part 2 (moments_cols.frag) blurs
// the result along the columns: the two make the separable 2D Gaussian of the moments.
// The moments of a depth z in [0, 1] (raster/METHODS.md "Filterable maps"):
//   vsm (z, z^2)  evsm2 (e^(c+ z'), e^(2 c+ z'))  evsm4 (those, -e^(-c- z'), e^(-2 c- z'))
//   msm (z, z^2, z^3, z^4), with z' = 2 z - 1 and c+, c- the clamped EVSM exponents.
#extension GL_GOOGLE_include_directive : require
#include "shadowlab/raster/resolve_abi.h"

layout(constant_id = kSpecFilter) const int kFilter = kFilterVsm;
layout(set = 0, binding = kBindingMapDepth) uniform sampler2DArray mapDepth;  // NEAREST, raw depth
// The layer this draw fills (the shadow pass's push block: a mat4, then the layer).
layout(push_constant) uniform Push { layout(offset = 64) uint layer; } pc;
layout(location = 0) out vec4 outMoments;

vec4 momentsOf(float z) {
  if (kFilter == kFilterVsm) return vec4(z, z * z, 0.0, 0.0);
  if (kFilter == kFilterMsm) {
    float z2 = z * z;
    return vec4(z, z2, z2 * z, z2 * z2);
  }
  float zw = 2.0 * clamp(z, 0.0, 1.0) - 1.0;
  float pos = exp(P.moments.z * zw);
  if (kFilter == kFilterEvsm2) return vec4(pos, pos * pos, 0.0, 0.0);
  float neg = -exp(-P.moments.w * zw);
  return vec4(pos, pos * pos, neg, neg * neg);
}

void main() {
  ivec2 t = ivec2(gl_FragCoord.xy);
  int radius = int(PLoops.moments2.y), last = P.sizes.x - 1;
  vec4 sum = vec4(0.0);
  float weights = 0.0;
  for (int k = -radius; k <= radius; ++k) {
    float w = radius > 0 ? exp(-2.0 * float(k * k) / float(radius * radius)) : 1.0;  // sigma = radius / 2
    float z = texelFetch(mapDepth, ivec3(clamp(t.x + k, 0, last), t.y, int(pc.layer)), 0).r;
    sum += w * momentsOf(z);
    weights += w;
  }
  outMoments = sum / weights;
}
