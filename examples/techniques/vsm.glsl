// Variance shadow mapping (Donnelly & Lauritzen 2006): the built-in filter=vsm, written as a
// technique file. The moments line has the harness render and blur (filter.blur) the map's (z, z^2)
// as for filter=vsm; the file bounds the lit fraction from them with Chebyshev's one-sided
// inequality and cuts the bleeding like vsm.bleed_reduction. It gives filter=vsm bit for bit
// (tests/raster_technique_test.cpp compares every channel).
//
// shadowlab: moments vsm
float shadowVisibility(ShadowQuery q) {
  float mean = q.moments.x, meanSq = q.moments.y, t = q.depth;
  float variance = max(meanSq - mean * mean, q.momentKeys.x);  // vsm.min_variance: the floor
  float d = t - mean;
  float bound = t <= mean ? 1.0 : variance / (variance + d * d);
  float cut = q.momentKeys.y;  // vsm.bleed_reduction
  return clamp((bound - cut) / (1.0 - cut), 0.0, 1.0);
}
