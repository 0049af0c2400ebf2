#include "shadowlab/raster/sdsm.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace shadowlab::raster {

bool visiblePoint(const CameraRays& rays, glm::vec3 origin, int x, int y, glm::vec3 v0, glm::vec3 v1, glm::vec3 v2,
                  glm::vec3& point) {
  glm::dvec3 d(rays.direction(float(x) + 0.5f, float(y) + 0.5f));
  glm::dvec3 o(origin), a(v0);
  glm::dvec3 n = glm::cross(glm::dvec3(v1) - a, glm::dvec3(v2) - a);
  double denominator = glm::dot(n, d);
  if (denominator == 0.0) return false;
  double t = glm::dot(n, a - o) / denominator;
  if (!(std::isfinite(t) && t > 0.0)) return false;
  point = glm::vec3(o + d * t);
  return true;
}

std::vector<SdsmSample> sdsmSamples(const std::vector<glm::vec3>& worldPoints, const Camera& camera,
                                    const glm::mat4& lightFromWorld) {
  const glm::dvec3 eye(camera.position);
  const glm::dvec3 forward = glm::normalize(glm::dvec3(camera.lookAt) - eye);
  const glm::dmat4 light(lightFromWorld);
  std::vector<SdsmSample> out;
  out.reserve(worldPoints.size());
  for (const glm::vec3& p : worldPoints) {
    const glm::dvec3 q(p);
    const glm::dvec4 l = light * glm::dvec4(q, 1.0);
    out.push_back({float(glm::dot(q - eye, forward)), glm::vec2(float(l.x), float(l.y))});
  }
  return out;
}

bool sdsmDepthRange(const std::vector<SdsmSample>& samples, ViewDepthRange& range) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const SdsmSample& s : samples) {
    if (!std::isfinite(s.viewDepth)) continue;
    lo = std::min(lo, double(s.viewDepth));
    hi = std::max(hi, double(s.viewDepth));
  }
  if (!(lo <= hi)) return false;
  const double kMinNear = 1e-4;
  const double n = std::max(lo, kMinNear);
  range = {float(n), float(std::max(hi, n * 1.001 + kMinNear))};
  return true;
}

std::vector<SdsmBounds> sdsmPartitionBounds(const std::vector<SdsmSample>& samples, const std::vector<double>& splits,
                                            double blend) {
  const int count = std::max(int(splits.size()) - 1, 0);
  std::vector<SdsmBounds> out(static_cast<size_t>(count));
  if (count == 0) return out;
  const float inf = std::numeric_limits<float>::infinity();
  for (SdsmBounds& b : out) b.minLight = glm::vec2(inf), b.maxLight = glm::vec2(-inf);
  const double tolerance = 1e-5 * std::abs(splits.back()) + 1e-7;
  auto add = [&](int k, glm::vec2 l) {
    SdsmBounds& b = out[size_t(k)];
    b.minLight = glm::min(b.minLight, l);
    b.maxLight = glm::max(b.maxLight, l);
    ++b.samples;
  };
  for (const SdsmSample& s : samples) {
    const double d = s.viewDepth;
    if (!std::isfinite(d)) continue;
    // pickCascade: the partition is the number of inner splits C_1..C_(N-1) the depth lies beyond;
    // within the tolerance of a split, both sides.
    int first = 0, last = 0;
    for (int j = 1; j < count; ++j) {
      first += d > splits[size_t(j)] + tolerance;
      last += d > splits[size_t(j)] - tolerance;
    }
    uint32_t reads = 0;  // bit k: the sample's lookups read partition k
    for (int k = first; k <= last; ++k) {
      reads |= 1u << k;
      // The blend band at partition k's far end reads partition k + 1 as well.
      if (blend > 0.0 && k + 1 < count) {
        const double farSplit = splits[size_t(k) + 1], band = blend * (farSplit - splits[size_t(k)]);
        if (band > 0.0 && d >= farSplit - band - tolerance) reads |= 1u << (k + 1);
      }
    }
    for (int k = 0; k < count; ++k)
      if (reads & (1u << k)) add(k, s.light);
  }
  for (SdsmBounds& b : out)
    if (b.samples == 0) b.minLight = b.maxLight = glm::vec2(0.0f);
  return out;
}

CascadeCrop sdsmCrop(const SdsmBounds& bounds, int mapSize, bool snap) {
  const double size = double(std::max(mapSize, 8));
  glm::dvec2 lo(bounds.minLight), hi(bounds.maxLight);
  glm::dvec2 extent = hi - lo;
  const double least = std::max(1e-4 * std::max(extent.x, extent.y), 1e-5);
  CascadeCrop crop;
  glm::dvec2 texel(0.0);
  for (int a = 0; a < 2; ++a) {
    if (!(extent[a] >= least)) {
      const double center = 0.5 * (lo[a] + hi[a]);
      lo[a] = center - 0.5 * least;
      hi[a] = center + 0.5 * least;
      extent[a] = least;
    }
    double minA = 0, maxA = 0;
    if (snap) {
      texel[a] = std::exp2(std::ceil(std::log2(extent[a] / (size - 4.0))));
      minA = std::floor((lo[a] - texel[a]) / texel[a]) * texel[a];
      maxA = minA + size * texel[a];
    } else {
      texel[a] = extent[a] / (size - 2.0);
      minA = lo[a] - texel[a];
      maxA = hi[a] + texel[a];
    }
    crop.minLight[a] = float(minA);
    crop.maxLight[a] = float(maxA);
  }
  crop.texelWorld = float(std::max(texel.x, texel.y));
  return crop;
}

}  // namespace shadowlab::raster
