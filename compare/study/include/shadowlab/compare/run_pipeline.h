#pragma once
// reference + raster + compare in one process, with the reference cached on disk by content hash.
// Used by `shadowlab run` and `shadowlab sweep`.
#include <string>

#include "shadowlab/compare/compare.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// Reference frames stored as DIR/<referenceHash>.exr, with the Compare channel set (hit, object_id,
// light.L.vis, light.L.occluder_dist, proj.P.coverage/R/G/B; reference/README.md) whatever
// ReferenceOptions::channels says. Default DIR: $SHADOWLAB_CACHE, else
// ".shadowlab-cache" in the current folder. Writes are atomic, so concurrent or interrupted runs
// never leave a truncated entry; processes that miss the same entry at once trace it once (the
// others wait on DIR/<referenceHash>.exr.lock, then read it).
class ReferenceCache {
 public:
  explicit ReferenceCache(std::string dir = "");
  const std::string& dir() const { return dir_; }
  // Loads the cached frame or traces it (and stores it). `traced` tells which happened. A frame
  // whose every pixel misses the geometry (the camera sees no surface) is an InputError naming the
  // scene file and /camera: one rule for every command that compares a scene.
  Frame get(const Scene& scene, const ReferenceOptions& options, bool* traced = nullptr,
            ReferenceStats* stats = nullptr);

 private:
  Frame getUnchecked(const Scene& scene, const ReferenceOptions& options, bool* traced, ReferenceStats* stats);
  std::string dir_;
};

struct RunResult {
  Frame reference;
  Frame raster;
  Classification classification;
  Metrics metrics;
  RasterTimings timings;
  double compareMs = 0;           // compare_ms: CPU wall time of compareFrames
  double referenceMs = 0;         // reference_ms: CPU wall time to trace the reference or read it from the cache
  bool referenceTraced = false;   // false: the reference came from the cache
  ReferenceStats referenceStats;  // filled only when traced
};

// Evidence on demand (raster.h, EvidenceSelector): lists the pixels whose lit decision in the
// lookup's bytes (>= 128) differs from the reference's (`light.<light>.vis` >= 0.5): the only
// pixels where compareFrames reads the raster frame's evidence channels (classify.h; it reads hit,
// object_id, vis, m and cascade everywhere, which the rasterizer fills everywhere). Those the
// reference lights for the occluder's evidence alone (in_map and occluder_id decide them), the
// others for every channel. A sized light's reference (`light.<light>.vis_sigma`, soft mode:
// compare/METRICS.md "Soft shadows") lists instead the pixels whose byte may lie beyond the soft
// tolerance from the truth, whatever the decisions. An empty function when the reference has no
// such channel (then the rasterizer renders the full frame).
EvidenceSelector disagreementSelector(const Frame& reference, const std::string& light);

RunResult runPipeline(const Scene& scene, const Method& method, Rasterizer& rasterizer, ReferenceCache& cache,
                      const std::string& light = "", const ReferenceOptions& referenceOptions = {});

}  // namespace shadowlab
