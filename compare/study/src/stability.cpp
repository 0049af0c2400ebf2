// Temporal stability: the shimmer and per-frame error metrics (stability.h).
#include "shadowlab/compare/stability.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "shadowlab/scenes/error.h"

namespace shadowlab {

namespace {

const float* plane(const Frame& f, const std::string& name, const char* which) {
  if (!f.has(name)) throw InputError(std::string("stability: error: the ") + which + " frame has no channel " + name);
  const std::vector<float>& p = f.get(name);
  if (p.size() != f.pixelCount())
    throw InputError(std::string("stability: error: channel ") + name + " of the " + which +
                     " frame has the wrong size");
  return p.data();
}

}  // namespace

double decisionFlipRate(const Frame& reference, const Frame& rasterA, const Frame& rasterB, const std::string& light,
                        uint64_t* pixelsCompared) {
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

StabilityStream::StabilityStream(const Frame& reference, CompareOptions options)
    : reference_(reference), options_(std::move(options)) {}

Frame StabilityStream::add(Frame raster) {
  if (frames_ == 0) light_ = resolveCompareLight(reference_, raster, options_);
  if (frames_ > 0) {
    uint64_t px = 0;
    metrics_.flipRatePerPair.push_back(decisionFlipRate(reference_, previous_, raster, light_, &px));
    metrics_.pixelsComparedPerPair.push_back(px);
  }
  errors_.push_back(compareFrames(reference_, raster, options_).errorRate);
  ++frames_;
  std::swap(previous_, raster);
  return raster;
}

StabilityMetrics StabilityStream::result() const {
  if (frames_ < 2)
    throw InputError("stability: error: got " + std::to_string(frames_) +
                     " raster frame(s); expected at least 2 to measure change between frames");
  StabilityMetrics s = metrics_;
  double sum = 0;
  for (double r : s.flipRatePerPair) sum += r;
  s.shimmerRate = sum / double(s.flipRatePerPair.size());
  setErrorStatistics(s, errors_);
  return s;
}

StabilityMetrics measureStability(const Frame& reference, const std::vector<Frame>& rasters,
                                  const CompareOptions& options) {
  StabilityStream stream(reference, options);
  for (const Frame& f : rasters) stream.add(f);
  return stream.result();
}

void setErrorStatistics(StabilityMetrics& s, const std::vector<double>& e) {
  if (e.empty()) throw InputError("stability: error: no frames; expected at least one error rate");
  for (double v : e)
    if (!std::isfinite(v)) throw InputError("stability: error: a frame's error rate is not finite; expected a rate");
  s.frames = int(e.size());
  s.errorRatePerFrame = e;
  double sum = 0, emax = e.front(), jump = 0;
  for (size_t k = 0; k < e.size(); ++k) {
    sum += e[k];
    emax = std::max(emax, e[k]);
    if (k + 1 < e.size()) jump = std::max(jump, std::fabs(e[k + 1] - e[k]));
  }
  s.errorRateMean = sum / double(e.size());
  double var = 0;
  for (double v : e) var += (v - s.errorRateMean) * (v - s.errorRateMean);
  s.errorRateStd = std::sqrt(var / double(e.size()));
  s.errorRateMax = emax;
  s.errorJumpMax = jump;
}

nlohmann::json StabilityMetrics::toJson() const {
  nlohmann::json j = gateMetrics();
  if (hasShimmer()) {
    j["flip_rate_per_pair"] = flipRatePerPair;
    j["pixels_compared_per_pair"] = pixelsComparedPerPair;
  }
  j["error_rate_per_frame"] = errorRatePerFrame;
  return j;
}

nlohmann::json StabilityMetrics::gateMetrics() const {
  nlohmann::json j = {{"frames", frames},
                      {"error_rate_mean", errorRateMean},
                      {"error_rate_max", errorRateMax},
                      {"error_rate_std", errorRateStd},
                      {"error_jump_max", errorJumpMax}};
  if (hasShimmer()) j["shimmer_rate"] = shimmerRate;
  return j;
}

}  // namespace shadowlab
