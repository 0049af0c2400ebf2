// Percentage-closer filtering over a size x size grid of map texels around the lookup texel: the
// built-in filter=pcf, written as a technique file. With technique.size = N it gives filter=pcf
// filter.size=N bit for bit (tests/raster_technique_test.cpp compares every channel).
//
// shadowlab: key size int 3 range 3..15

float shadowVisibility(ShadowQuery q) {
  int h = technique_size / 2;  // an odd size: the grid is centred on the lookup texel
  ivec2 center = ivec2(floor(q.st));
  int last = int(q.mapSize) - 1;
  float sum = 0.0;
  for (int dy = -h; dy <= h; ++dy)
    for (int dx = -h; dx <= h; ++dx) {
      ivec2 t = center + ivec2(dx, dy);
      // The receiver's depth at the tap's centre (the configured receiver-plane slope, 0 when off),
      // compared with the stored depth of the texel clamped to the map.
      float ref = q.depth + dot(q.depthSlope, vec2(t) + 0.5 - q.st);
      float stored = texelFetch(mapDepth, ivec3(clamp(t, ivec2(0), ivec2(last)), q.layer), 0).r;
      sum += stored >= ref ? 1.0 : 0.0;
    }
  float n = float(2 * h + 1);
  return sum / (n * n);
}
