#pragma once
// Temporal stability of a shadow-mapping method: shimmer measured exactly.
//
// The evaluation camera (scene.camera) stays fixed while the camera the light's fit follows moves
// along a path (Rasterizer::render's fitCamera), so every pixel shows the same surface point in
// every frame and one reference frame serves them all: any change of the raster's decision
// between frames is the fit's doing (crawling / shimmering shadow edges). Documented in
// compare/METRICS.md ("Temporal stability").
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/compare.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// ---- camera paths (pure functions) -------------------------------------------------------------
// Both return `frames` cameras (frames >= 2); frame 0 is `start` exactly, frame frames-1 the end of
// the path, the steps in between equal. Everything but position and lookAt is copied from start.
//
// dolly: position and lookAt both move by distanceWorld * k / (frames - 1) along the unit view
// direction normalize(lookAt - position) (negative: backwards), so the view direction is constant.
std::vector<Camera> dollyPath(const Camera& start, float distanceWorld, int frames);
// orbit: position rotates about the axis through lookAt along start.up (normalized) by
// angleDeg * k / (frames - 1) degrees (right-handed: positive is counter-clockwise seen from
// above); lookAt stays, so the camera keeps looking at the same point.
std::vector<Camera> orbitPath(const Camera& start, float angleDeg, int frames);

// ---- metrics -----------------------------------------------------------------------------------
struct StabilityMetrics {
  int frames = 0;
  // Per consecutive pair (frames - 1 entries): of the pixels compared in both frames (the
  // reference and both raster frames hit the same object), the fraction whose raster decision
  // (vis >= 0.5 lit) differs between the two frames; 0 for a pair with no compared pixel.
  std::vector<double> flipRatePerPair;
  std::vector<uint64_t> pixelsComparedPerPair;
  double shimmerRate = 0;  // mean of flipRatePerPair
  // Per frame: compareFrames(reference, frame).errorRate against the one fixed reference.
  std::vector<double> errorRatePerFrame;
  double errorRateMean = 0, errorRateMax = 0, errorRateStd = 0;  // std: population (divide by N)

  nlohmann::json toJson() const;  // keys: frames, shimmer_rate, flip_rate_per_pair, error_rate_*
};

// The flip fraction of one pair of raster frames against the reference (see flipRatePerPair).
// `light`: the light channel (light.LIGHT.vis). Throws InputError on size mismatch or missing
// channels. `pixelsCompared` (optional) receives the denominator.
double decisionFlipRate(const Frame& reference, const Frame& rasterA, const Frame& rasterB,
                        const std::string& light, uint64_t* pixelsCompared = nullptr);

// All metrics of a raster sequence rendered from the reference's camera. Needs >= 2 frames;
// throws InputError otherwise or on frames compareFrames rejects.
StabilityMetrics measureStability(const Frame& reference, const std::vector<Frame>& rasters,
                                  const CompareOptions& options = {});

}  // namespace shadowlab
