// Percentage-closer filtering over a size x size grid of map texels around the lookup texel: the
// built-in filter=pcf, written as a technique file. With technique.size = N it gives filter=pcf
// filter.size=N bit for bit (tests/raster_technique_test.cpp compares every channel).
//
// shadowlab: key size int 3 range 3..15

// Lit (1) where the stored depth is not in front of the receiver's depth at the texel's centre
// (the configured receiver-plane slope; 0 when bias.receiver_plane is off).
float lit(ShadowQuery q, float stored, ivec2 texel) {
  return stored >= q.depth + dot(q.depthSlope, vec2(texel) + 0.5 - q.st) ? 1.0 : 0.0;
}

float shadowVisibility(ShadowQuery q) {
  int h = technique_size / 2;  // an odd size: the grid is centred on the lookup texel
  ivec2 center = ivec2(floor(q.st));
  float sum = 0.0;
  // The taps as 2x2 gathers: textureGather at the corner that texels t .. t + (1, 1) share returns
  // them as (w, z, x, y) = (t, t + (1, 0), t + (0, 1), t + (1, 1)), clamped at the map's edge. The
  // last row and column of gathers use half their texels. The sum counts whole taps: its order
  // does not change it.
  for (int by = -h; by <= h; by += 2)
    for (int bx = -h; bx <= h; bx += 2) {
      ivec2 t = center + ivec2(bx, by);
      vec4 g = textureGather(mapDepth, vec3((vec2(t) + 1.0) / q.mapSize, float(q.layer)));
      bool right = bx < h, down = by < h;
      sum += lit(q, g.w, t);
      sum += right ? lit(q, g.z, t + ivec2(1, 0)) : 0.0;
      sum += down ? lit(q, g.x, t + ivec2(0, 1)) : 0.0;
      sum += right && down ? lit(q, g.y, t + ivec2(1, 1)) : 0.0;
    }
  float n = float(2 * h + 1);
  return sum / (n * n);
}
