// A small PCSS-style contact-hardening filter (Fernando 2005): a blocker search over a disc of
// `search` texels averages the depths in front of the receiver, the penumbra widens with the
// receiver-blocker distance, and a PCF over that width gives the visibility. Shadows are hard where
// the occluder touches the receiver and soften away from it.
//
// shadowlab: key search float 4 range 1..16
// shadowlab: key light_size float 40 range 0..400
// shadowlab: key max_radius float 6 range 0.5..16

const vec2 kRing[8] = vec2[](vec2(1.0, 0.0), vec2(0.707, 0.707), vec2(0.0, 1.0), vec2(-0.707, 0.707),
                             vec2(-1.0, 0.0), vec2(-0.707, -0.707), vec2(0.0, -1.0), vec2(0.707, -0.707));

float storedAt(ShadowQuery q, vec2 st) {
  int last = int(q.mapSize) - 1;
  return texelFetch(mapDepth, ivec3(clamp(ivec2(floor(st)), ivec2(0), ivec2(last)), q.layer), 0).r;
}

float shadowVisibility(ShadowQuery q) {
  // Blocker search: the centre and two rings.
  float blockers = 0.0, blockerDepth = 0.0;
  for (int ring = 0; ring <= 2; ++ring)
    for (int i = 0; i < (ring == 0 ? 1 : 8); ++i) {
      vec2 st = q.st + kRing[i] * (technique_search * float(ring) * 0.5);
      float z = storedAt(q, st);
      if (z < q.depth) blockers += 1.0, blockerDepth += z;
    }
  if (blockers == 0.0) return 1.0;
  blockerDepth /= blockers;
  // Penumbra width in texels from similar triangles, in map depth.
  float radius = clamp(technique_light_size * (q.depth - blockerDepth) / max(blockerDepth, 1e-4), 0.5,
                       technique_max_radius);
  // PCF over a 5x5 grid scaled to the penumbra.
  float sum = 0.0;
  for (int y = -2; y <= 2; ++y)
    for (int x = -2; x <= 2; ++x) {
      vec2 st = q.st + vec2(x, y) * (radius * 0.5);
      sum += storedAt(q, st) >= q.depth + dot(q.depthSlope, floor(st) + 0.5 - q.st) ? 1.0 : 0.0;
    }
  return sum / 25.0;
}
