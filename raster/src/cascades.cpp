#include "shadowlab/raster/cascades.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace shadowlab::raster {

ViewDepthRange cascadeDepthRange(const Camera& camera, glm::vec3 boundsMin, glm::vec3 boundsMax) {
  glm::dvec3 forward = glm::normalize(glm::dvec3(camera.lookAt) - glm::dvec3(camera.position));
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int i = 0; i < 8; ++i) {
    glm::dvec3 c((i & 1) ? boundsMax.x : boundsMin.x, (i & 2) ? boundsMax.y : boundsMin.y,
                 (i & 4) ? boundsMax.z : boundsMin.z);
    double d = glm::dot(c - glm::dvec3(camera.position), forward);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  const double kMinNear = 1e-4;
  double cameraNear = std::max(double(camera.nearPlane), kMinNear);
  double cameraFar = std::max(double(camera.farPlane), cameraNear * 1.001 + kMinNear);
  double n = std::max(cameraNear, lo), f = std::min(cameraFar, hi);
  // Empty scene box in view (or NaN bounds of an empty scene): the camera's own range.
  if (!(f > n)) n = cameraNear, f = cameraFar;
  return {float(n), float(std::max(f, n * 1.001 + kMinNear))};
}

std::vector<double> cascadeSplits(double n, double f, int count, double lambda) {
  std::vector<double> c(size_t(count) + 1);
  for (int i = 0; i <= count; ++i) {
    double s = double(i) / double(count);
    c[size_t(i)] = lambda * n * std::pow(f / n, s) + (1.0 - lambda) * (n + (f - n) * s);
  }
  // The ends are the range itself, not the formula's rounding of it.
  c.front() = n;
  c.back() = f;
  return c;
}

}  // namespace shadowlab::raster
