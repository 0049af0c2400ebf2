#pragma once
// What a shadow-mapping method costs an engine, as a deterministic model (compare/TUNE.md, "The
// cost model"). `shadowlab tune` ranks configurations by it: measured GPU times jitter from run to
// run (and on a shared machine by tens of percent), so a search that ranked by them would choose
// differently each time. The measured shadow_gpu_ms / camera_gpu_ms stay in every row beside it.
//
// This is the one place the model lives: a ranking by the measured method time (method_gpu_ms,
// the shadow pass plus the lookup pass) would replace estimateMethodCost and nothing else.
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

struct MethodCost {
  double shadowMs = 0;     // the depth-only shadow pass: map texels written and triangles drawn, per layer
  double lookupMs = 0;     // one visibility lookup (and its filter) per camera pixel
  double estimatedMs = 0;  // shadowMs + lookupMs: what tune ranks by and --budget-ms limits
  double mapBytes = 0;     // depth texels * bytes per texel * layers: the tie-break
  int layers = 0;          // map layers rendered (cascades, cube faces, projector maps)
  double texelsWritten = 0;
  double tapsPerPixel = 0;  // depth comparisons per camera pixel
  double pixels = 0;        // camera pixels
  nlohmann::json toJson() const;
};

// The model for `method` on `scene` rendering `light` (empty: the scene's first light). Pure
// arithmetic on the scene's camera, light type, triangle count and the method's keys. A method of an
// outside renderer (renderer=) has no model: every field 0 (its rows measure renderer_frame_ms).
MethodCost estimateMethodCost(const Scene& scene, const Method& method, const std::string& light);

}  // namespace shadowlab
