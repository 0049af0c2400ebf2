// reference + raster + compare in one process; the reference is cached on disk by content hash.
#include <chrono>
#include <cstdlib>
#include <filesystem>

#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab {

ReferenceCache::ReferenceCache(std::string dir) : dir_(std::move(dir)) {
  if (dir_.empty()) {
    const char* env = std::getenv("SHADOWLAB_CACHE");
    dir_ = env && *env ? env : ".shadowlab-cache";
  }
}

Frame ReferenceCache::get(const Scene& scene, const ReferenceOptions& options, bool* traced, ReferenceStats* stats) {
  const std::string path = dir_ + "/" + referenceHash(scene, options) + ".exr";
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec)) {
    try {
      Frame cached = readFrameExr(path);
      // The hash names the content, so a mismatch means a foreign or damaged file: trace again
      // and replace it rather than compare against the wrong truth.
      auto it = cached.meta.find("scene_hash");
      if (it != cached.meta.end() && it->is_string() && it->get<std::string>() == scene.hash) {
        if (traced) *traced = false;
        return cached;
      }
    } catch (const InputError&) {
      // unreadable entry (e.g. written by an older build): fall through and replace it
    }
  }
  Frame frame = renderReference(scene, options, stats);
  makeDirs(dir_);
  writeFrameExr(frame, path);  // atomic: concurrent runs never see a truncated entry
  if (traced) *traced = true;
  return frame;
}

RunResult runPipeline(const Scene& scene, const Method& method, Rasterizer& rasterizer, ReferenceCache& cache,
                      const std::string& light, const ReferenceOptions& referenceOptions) {
  if (!light.empty() && !scene.findLight(light)) {
    std::string names;
    for (const auto& l : scene.lights) names += (names.empty() ? "" : ", ") + l.name;
    throw InputError(scene.path + ": error: no light named \"" + light +
                     "\"; expected one of: " + (names.empty() ? "(the scene has no lights)" : names));
  }
  RunResult r;
  const auto r0 = std::chrono::steady_clock::now();
  r.reference = cache.get(scene, referenceOptions, &r.referenceTraced, &r.referenceStats);
  r.referenceMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - r0).count();
  r.raster = rasterizer.render(scene, method, light, &r.timings);
  CompareOptions options;
  options.light = scene.lightOrDefault(light);
  const auto t0 = std::chrono::steady_clock::now();
  r.metrics = compareFrames(r.reference, r.raster, options, &r.classification);
  r.compareMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace shadowlab
