#pragma once
// Temporal stability of a shadow-mapping method, two ways (compare/METRICS.md, "Temporal stability"):
//
// - a moving fit camera (shimmer measured exactly): the evaluation camera (scene.camera) stays
//   fixed while the camera the light's fit follows moves along a path (Rasterizer::render's
//   fitCamera), so every pixel shows the same surface point in every frame and one reference frame
//   serves them all: any change of the raster's decision between frames is the fit's doing
//   (crawling / shimmering shadow edges);
// - a moving light (a light path, e.g. the sun going down): the camera stays fixed, each frame is
//   its own scene with its own reference, and the error rate is followed from frame to frame
//   (error_jump_max: a method that breaks inside the path jumps).
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/compare.h"
#include "shadowlab/scenes/camera_path.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// Camera paths (dollyPath, orbitPath, keyframePath, scene-file paths) are in
// shadowlab/scenes/camera_path.h, light paths (--light-path) in shadowlab/scenes/light_path.h.

// ---- metrics -----------------------------------------------------------------------------------
struct StabilityMetrics {
  int frames = 0;
  // Per consecutive pair (frames - 1 entries): of the pixels compared in both frames (the
  // reference and both raster frames hit the same object), the fraction whose raster decision
  // (vis >= 0.5 lit) differs between the two frames; 0 for a pair with no compared pixel.
  std::vector<double> flipRatePerPair;
  std::vector<uint64_t> pixelsComparedPerPair;
  double shimmerRate = 0;  // mean of flipRatePerPair
  // Per frame: compareFrames(reference, frame).errorRate against the frame's reference (the one
  // fixed reference of a camera path; each frame's own for a light path).
  std::vector<double> errorRatePerFrame;
  double errorRateMean = 0, errorRateMax = 0, errorRateStd = 0;  // std: population (divide by N)
  // max over k of |errorRatePerFrame[k + 1] - errorRatePerFrame[k]|: the largest change of the error
  // rate between consecutive frames (a fraction of compared pixels, like error_rate).
  double errorJumpMax = 0;

  // Camera paths have shimmer (flipRatePerPair filled); light paths do not (the true shadow moves,
  // so a flipped decision is not an error there): their JSON has no shimmer keys.
  bool hasShimmer() const { return !flipRatePerPair.empty(); }
  // Everything: frames, shimmer_rate, flip_rate_per_pair, pixels_compared_per_pair (camera paths),
  // error_rate_per_frame, error_rate_mean/max/std, error_jump_max.
  nlohmann::json toJson() const;
  // The scalar metrics a gate checks (the `metrics` of stability.json's result row): frames,
  // shimmer_rate (camera paths), error_rate_mean, error_rate_max, error_rate_std, error_jump_max.
  nlohmann::json gateMetrics() const;
};

// Fills frames, errorRatePerFrame and its statistics (mean, max, population std, errorJumpMax) from
// per-frame error rates (>= 1; InputError otherwise or on a non-finite rate).
void setErrorStatistics(StabilityMetrics& s, const std::vector<double>& errorRatePerFrame);

// The flip fraction of one pair of raster frames against the reference (see flipRatePerPair).
// `light`: the light channel (light.LIGHT.vis). Throws InputError on size mismatch or missing
// channels. `pixelsCompared` (optional) receives the denominator.
double decisionFlipRate(const Frame& reference, const Frame& rasterA, const Frame& rasterB, const std::string& light,
                        uint64_t* pixelsCompared = nullptr);

// All metrics of a raster sequence rendered from the reference's camera. Needs >= 2 frames;
// throws InputError otherwise or on frames compareFrames rejects.
StabilityMetrics measureStability(const Frame& reference, const std::vector<Frame>& rasters,
                                  const CompareOptions& options = {});

// The same metrics, one frame at a time: holds the previous frame only, so a long path needs the
// memory of two frames, not of all of them. measureStability is this over a vector.
class StabilityStream {
 public:
  StabilityStream(const Frame& reference, CompareOptions options = {});
  // Measures `raster` against the previous frame (flip rate) and the reference (error rate),
  // then keeps it as the previous frame and returns the one it replaces (empty at first), so
  // the caller can recycle its planes. Throws as measureStability does.
  Frame add(Frame raster);
  StabilityMetrics result() const;  // throws InputError with fewer than 2 frames

 private:
  const Frame& reference_;
  CompareOptions options_;
  std::string light_;
  Frame previous_;
  int frames_ = 0;
  StabilityMetrics metrics_;
  std::vector<double> errors_;
};

}  // namespace shadowlab
