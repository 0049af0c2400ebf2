#include "shadowlab/raster/cascades.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace shadowlab::raster {

ViewDepthRange cameraDepthRange(const Camera& camera) {
  const double kMinNear = 1e-4;
  double n = std::max(double(camera.nearPlane), kMinNear);
  double f = std::max(double(camera.farPlane), n * 1.001 + kMinNear);
  return {float(n), float(f)};
}

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
  const ViewDepthRange own = cameraDepthRange(camera);
  double cameraNear = own.nearView, cameraFar = own.farView;
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

CascadeCrop cascadeCrop(const Camera& camera, const glm::mat4& lightFromWorld, double nearView, double farView,
                        int mapSize, bool stabilize, glm::vec2 sceneMinLight, glm::vec2 sceneMaxLight) {
  glm::mat4 worldFromCamera = glm::inverse(camera.viewFromWorld());
  float tanY = std::tan(0.5f * glm::radians(camera.vfovDeg));
  float tanX = tanY * float(camera.width) / float(std::max(camera.height, 1));
  glm::vec3 cornersCamera[8];
  glm::vec3 centroidCamera(0);
  for (int k = 0; k < 8; ++k) {
    float d = float((k & 4) ? farView : nearView);
    cornersCamera[k] = glm::vec3((k & 1) ? tanX * d : -tanX * d, (k & 2) ? tanY * d : -tanY * d, -d);
    centroidCamera += cornersCamera[k] / 8.0f;
  }
  CascadeCrop crop;
  if (stabilize) {
    float r = 0;
    for (const glm::vec3& c : cornersCamera) r = std::max(r, glm::length(c - centroidCamera));
    r = std::max(r, 1e-4f);
    int size = std::max(mapSize, 4);
    crop.texelWorld = 2.0f * r / float(size - 2);
    float half = 0.5f * crop.texelWorld * float(size);
    glm::vec3 c = glm::vec3(lightFromWorld * (worldFromCamera * glm::vec4(centroidCamera, 1.0f)));
    glm::vec2 snapped(std::floor(c.x / crop.texelWorld) * crop.texelWorld,
                      std::floor(c.y / crop.texelWorld) * crop.texelWorld);
    crop.minLight = snapped - half;
    crop.maxLight = snapped + half;
    return crop;
  }
  float inf = std::numeric_limits<float>::infinity();
  glm::vec2 bmin(inf), bmax(-inf);
  for (const glm::vec3& c : cornersCamera) {
    glm::vec2 l = glm::vec2(lightFromWorld * (worldFromCamera * glm::vec4(c, 1.0f)));
    bmin = glm::min(bmin, l);
    bmax = glm::max(bmax, l);
  }
  glm::vec2 cmin = glm::max(bmin, sceneMinLight), cmax = glm::min(bmax, sceneMaxLight);
  if (cmin.x < cmax.x && cmin.y < cmax.y) bmin = cmin, bmax = cmax;
  glm::vec2 pad = glm::max((bmax - bmin) * 1e-4f, glm::vec2(1e-5f));
  crop.minLight = bmin - pad;
  crop.maxLight = bmax + pad;
  crop.texelWorld = std::max(crop.maxLight.x - crop.minLight.x, crop.maxLight.y - crop.minLight.y) / float(mapSize);
  return crop;
}

}  // namespace shadowlab::raster
