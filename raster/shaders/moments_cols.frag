#version 460
// Moments pass, part 2: the rows-blurred moments of part 1 (moments_rows.frag) blurred along the
// columns with the same Gaussian, into the layer of the moments map the resolve samples.
#extension GL_GOOGLE_include_directive : require
#include "shadowlab/raster/resolve_abi.h"

layout(set = 0, binding = kBindingMomentsRows) uniform sampler2DArray momentsRows;  // NEAREST
layout(push_constant) uniform Push { layout(offset = 64) uint layer; } pc;
layout(location = 0) out vec4 outMoments;

void main() {
  ivec2 t = ivec2(gl_FragCoord.xy);
  int radius = int(PLoops.moments2.y), last = P.sizes.x - 1;
  vec4 sum = vec4(0.0);
  float weights = 0.0;
  for (int k = -radius; k <= radius; ++k) {
    float w = radius > 0 ? exp(-2.0 * float(k * k) / float(radius * radius)) : 1.0;
    sum += w * texelFetch(momentsRows, ivec3(t.x, clamp(t.y + k, 0, last), int(pc.layer)), 0);
    weights += w;
  }
  outMoments = sum / weights;
}
