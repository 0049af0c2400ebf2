// Temporal stability: camera paths and the shimmer / per-frame error metrics (stability.h).
#include "shadowlab/compare/stability.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "shadowlab/scenes/error.h"

namespace shadowlab {

namespace {

void requireFrames(int frames, const char* what) {
  if (frames < 2)
    throw InputError(std::string(what) + ": error: frames is " + std::to_string(frames) +
                     "; expected at least 2 (a path needs a start and an end)");
}

const float* plane(const Frame& f, const std::string& name, const char* which) {
  if (!f.has(name))
    throw InputError(std::string("stability: error: the ") + which + " frame has no channel " + name);
  const std::vector<float>& p = f.get(name);
  if (p.size() != f.pixelCount())
    throw InputError(std::string("stability: error: channel ") + name + " of the " + which +
                     " frame has the wrong size");
  return p.data();
}

}  // namespace

std::vector<Camera> dollyPath(const Camera& start, float distanceWorld, int frames) {
  requireFrames(frames, "dolly");
  glm::vec3 view = start.lookAt - start.position;
  float len = glm::length(view);
  if (!(len > 0.0f) || !std::isfinite(distanceWorld))
    throw InputError("dolly: error: the camera has no view direction (position == look_at) or the distance is "
                     "not finite; expected a camera that looks somewhere and a finite distance");
  glm::vec3 forward = view / len;
  std::vector<Camera> path;
  for (int k = 0; k < frames; ++k) {
    // Computed from the start each time (not accumulated), so the last frame lands on the end.
    float t = float(k) / float(frames - 1);
    Camera c = start;
    glm::vec3 offset = forward * (distanceWorld * t);
    c.position = start.position + offset;
    c.lookAt = start.lookAt + offset;
    path.push_back(c);
  }
  return path;
}

std::vector<Camera> orbitPath(const Camera& start, float angleDeg, int frames) {
  requireFrames(frames, "orbit");
  float upLen = glm::length(start.up);
  if (!(upLen > 0.0f) || !std::isfinite(angleDeg))
    throw InputError("orbit: error: the camera's up vector is zero or the angle is not finite; expected a "
                     "non-zero up and a finite angle");
  glm::vec3 axis = start.up / upLen;
  std::vector<Camera> path;
  for (int k = 0; k < frames; ++k) {
    float t = float(k) / float(frames - 1);
    glm::mat4 rot = glm::rotate(glm::mat4(1.0f), glm::radians(angleDeg * t), axis);
    Camera c = start;
    c.position = start.lookAt + glm::vec3(rot * glm::vec4(start.position - start.lookAt, 0.0f));
    path.push_back(c);
  }
  return path;
}

double decisionFlipRate(const Frame& reference, const Frame& rasterA, const Frame& rasterB,
                        const std::string& light, uint64_t* pixelsCompared) {
  if (reference.width != rasterA.width || reference.height != rasterA.height || rasterA.width != rasterB.width ||
      rasterA.height != rasterB.height)
    throw InputError("stability: error: frame sizes differ; expected every frame from the same camera");
  const std::string vis = "light." + light + ".vis";
  const float* refHit = plane(reference, "hit", "reference");
  const float* refObj = plane(reference, "object_id", "reference");
  const float* aHit = plane(rasterA, "hit", "raster");
  const float* aObj = plane(rasterA, "object_id", "raster");
  const float* aVis = plane(rasterA, vis, "raster");
  const float* bHit = plane(rasterB, "hit", "raster");
  const float* bObj = plane(rasterB, "object_id", "raster");
  const float* bVis = plane(rasterB, vis, "raster");
  uint64_t compared = 0, flips = 0;
  for (size_t i = 0, n = reference.pixelCount(); i < n; ++i) {
    // Compared as in compareFrames, in both frames: the same surface in all three.
    if (!(refHit[i] >= 0.5f && aHit[i] >= 0.5f && bHit[i] >= 0.5f)) continue;
    if (refObj[i] != aObj[i] || refObj[i] != bObj[i]) continue;
    ++compared;
    // The same decision threshold as compare (vis >= 0.5 is lit); NaN counts as shadowed in both.
    if ((aVis[i] >= 0.5f) != (bVis[i] >= 0.5f)) ++flips;
  }
  if (pixelsCompared) *pixelsCompared = compared;
  return compared ? double(flips) / double(compared) : 0.0;  // no pixel: nothing flipped, no NaN
}

StabilityMetrics measureStability(const Frame& reference, const std::vector<Frame>& rasters,
                                  const CompareOptions& options) {
  if (rasters.size() < 2)
    throw InputError("stability: error: got " + std::to_string(rasters.size()) +
                     " raster frame(s); expected at least 2 to measure change between frames");
  StabilityMetrics s;
  s.frames = int(rasters.size());
  for (const Frame& f : rasters) s.errorRatePerFrame.push_back(compareFrames(reference, f, options).errorRate);
  const std::string light = resolveCompareLight(reference, rasters.front(), options);
  double sum = 0;
  for (size_t k = 0; k + 1 < rasters.size(); ++k) {
    uint64_t px = 0;
    double r = decisionFlipRate(reference, rasters[k], rasters[k + 1], light, &px);
    s.flipRatePerPair.push_back(r);
    s.pixelsComparedPerPair.push_back(px);
    sum += r;
  }
  s.shimmerRate = sum / double(s.flipRatePerPair.size());
  double esum = 0, emax = 0;
  for (double e : s.errorRatePerFrame) {
    esum += e;
    emax = std::max(emax, e);
  }
  s.errorRateMean = esum / double(s.frames);
  double var = 0;
  for (double e : s.errorRatePerFrame) var += (e - s.errorRateMean) * (e - s.errorRateMean);
  s.errorRateStd = std::sqrt(var / double(s.frames));
  s.errorRateMax = emax;
  return s;
}

nlohmann::json StabilityMetrics::toJson() const {
  return {{"frames", frames},
          {"shimmer_rate", shimmerRate},
          {"flip_rate_per_pair", flipRatePerPair},
          {"pixels_compared_per_pair", pixelsComparedPerPair},
          {"error_rate_per_frame", errorRatePerFrame},
          {"error_rate_mean", errorRateMean},
          {"error_rate_max", errorRateMax},
          {"error_rate_std", errorRateStd}};
}

}  // namespace shadowlab
