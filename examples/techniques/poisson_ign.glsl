// Rotated Poisson-disc PCF: `taps` comparisons on a disc of `radius` texels, the disc rotated per
// pixel by interleaved gradient noise (Jimenez 2014), which turns the banding of a fixed disc into
// fine noise. Not a built-in filter.
//
// shadowlab: key radius float 1.5 range 0.25..8
// shadowlab: key taps int 12 range 1..16

// A Poisson disc of 16 points in the unit disc (any prefix is well spread).
const vec2 kDisc[16] = vec2[](
    vec2(-0.942, -0.399), vec2(0.946, -0.769), vec2(-0.094, -0.929), vec2(0.345, 0.294),
    vec2(-0.916, 0.458), vec2(-0.815, -0.879), vec2(-0.383, 0.277), vec2(0.975, 0.756),
    vec2(0.443, -0.975), vec2(0.537, -0.474), vec2(-0.265, -0.419), vec2(0.792, 0.191),
    vec2(-0.242, 0.997), vec2(-0.814, 0.914), vec2(0.200, 0.786), vec2(0.144, -0.141));

// Interleaved gradient noise of a pixel, in [0, 1).
float interleavedGradientNoise(vec2 pixel) {
  return fract(52.9829189 * fract(dot(pixel, vec2(0.06711056, 0.00583715))));
}

float shadowVisibility(ShadowQuery q) {
  float angle = 6.28318530718 * interleavedGradientNoise(vec2(q.pixel));
  mat2 rotation = mat2(cos(angle), sin(angle), -sin(angle), cos(angle));
  int last = int(q.mapSize) - 1;
  float sum = 0.0;
  for (int i = 0; i < technique_taps; ++i) {
    vec2 st = q.st + rotation * kDisc[i] * technique_radius;
    ivec2 t = ivec2(floor(st));
    float ref = q.depth + dot(q.depthSlope, vec2(t) + 0.5 - q.st);
    float stored = texelFetch(mapDepth, ivec3(clamp(t, ivec2(0), ivec2(last)), q.layer), 0).r;
    sum += stored >= ref ? 1.0 : 0.0;
  }
  return sum / float(technique_taps);
}
