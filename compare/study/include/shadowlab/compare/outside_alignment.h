#pragma once
// No confident answer from a misaligned outside frame (scenes/FRAME-CONTRACT.md "What is
// refused"): before an outside frame is scored, its size is checked against the scene's camera and
// its pattern (coverage where given, else lit/shadowed where the truth sees a surface) against the
// truth traced under candidate transforms of the camera. A frame that one of them explains clearly
// better than the camera itself is refused, naming what it looks like.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/declared_renderer.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// InputError naming `file` unless width x height is the camera's: "another size" (same aspect) or
// "another aspect" (the aspect differs, with both ratios).
void checkOutsideSize(int width, int height, const Camera& camera, const std::string& file);

// The rule's constants (FRAME-CONTRACT.md states them):
// - below kMinEdgePixels edge pixels in the truth's pattern nothing can be told (a featureless
//   frame is accepted, "cannot tell");
// - a candidate is refused for when its disagreements are at most kExplainedShare of the
//   camera's own and it removes at least max(kMinGainPixels, edge pixels / kGainEdgeDivisor) of them.
constexpr uint64_t kMinEdgePixels = 64;
constexpr double kExplainedShare = 0.5;
constexpr uint64_t kMinGainPixels = 16;
constexpr uint64_t kGainEdgeDivisor = 20;
// The field-of-view candidates: the camera's vertical fov (orthographic: its height) times 1 +- this.
constexpr float kFovScale = 0.05f;

struct AlignmentCandidate {
  std::string name;            // "identity", "flip", "shift_x-0.5", ..., "fov+5%", "fov-5%"
  uint64_t disagreements = 0;  // pixels whose pattern differs from the outside frame's
};

struct AlignmentCheck {
  std::string verdict;      // "aligned" or "cannot tell" (a refused frame throws)
  uint64_t edgePixels = 0;  // of the truth's pattern
  uint64_t comparedPixels = 0;
  std::vector<AlignmentCandidate> candidates;  // identity first
  nlohmann::json toJson() const;
};

// `truth` is the scene's reference (hit, light.LIGHT.vis), `outside` the frame built by
// makeOutsideFrame; `coverageGiven` says whether its hit came from the renderer. Traces the
// candidates (options as the truth's, spp 1) and throws InputError "FILE: error: the frame looks
// upside down ..." (or shifted, or of another field of view) when one explains it (the rule above).
AlignmentCheck checkOutsideAlignment(const Scene& scene, const Frame& truth, const Frame& outside, bool coverageGiven,
                                     const std::string& light, const std::string& file,
                                     const ReferenceOptions& traceOptions);

// The configuration name of an outside frame's row (the gate matches rows by it): "renderer=NAME"
// then the declared settings, "key=value" sorted by key, comma-separated (canonicalValueText);
// "outside" when nothing is declared.
std::string outsideConfigName(const DeclaredRenderer& declared);

// The row's "method" object for an outside frame: {"frame": "outside", "renderer", "coverage"
// ("given" | "assumed"), "boundary_band": "pixels", "alignment", and what was declared}.
nlohmann::json outsideMethodJson(const DeclaredRenderer& declared, const Frame& outside,
                                 const AlignmentCheck& alignment);

}  // namespace shadowlab
