// reference + raster + compare in one process; the reference is cached on disk by content hash.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>

#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/compare/classify.h"
#include "shadowlab/compare/frame_check.h"
#include "shadowlab/compare/interrupt_cleanup.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab {

ReferenceCache::ReferenceCache(std::string dir) : dir_(std::move(dir)) {
  if (dir_.empty()) {
    const char* env = std::getenv("SHADOWLAB_CACHE");
    dir_ = env && *env ? env : ".shadowlab-cache";
  }
}

namespace {

// The cached frame at `path` when it reads back, names `scene` and holds the Compare channels (the
// hash names the content, so a mismatch means a foreign or damaged file: the caller traces again
// and replaces it rather than compare against the wrong truth); else nothing.
std::optional<Frame> loadEntry(const std::string& path, const Scene& scene) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  try {
    // A cached frame is read through compare's door like any other (a NaN in a damaged entry is
    // traced again, never compared).
    Frame cached = readFrameToCompare(path);
    auto it = cached.meta.find("scene_hash");
    if (it == cached.meta.end() || !it->is_string() || it->get<std::string>() != scene.hash) return std::nullopt;
    for (const std::string& name : referenceChannelNames(scene, ReferenceChannels::Compare))
      if (!cached.has(name)) return std::nullopt;
    return cached;
  } catch (const InputError&) {
    // unreadable entry (e.g. written by an older build, or truncated): trace it again
  }
  return std::nullopt;
}

// An exclusive flock on DIR/<entry>.lock while one process traces a missing entry, so that the
// shards of a sweep that need the same reference at once trace it once: the others wait, then read
// it. Only an optimisation: entries are written atomically, so where locking does not work (a
// filesystem without flock) every process simply traces, as before. The lock file is removed when
// the entry is written; a waiter that then gets the lock on the removed file finds the entry.
class EntryLock {
 public:
  explicit EntryLock(std::string path) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) return;
    int rc;
    do rc = ::flock(fd_, LOCK_EX);
    while (rc != 0 && errno == EINTR);
    if (rc != 0) {
      ::close(fd_);
      fd_ = -1;
      return;
    }
    // Held: this process's file to remove if a signal ends it mid-trace (interrupt_cleanup.h). A
    // process killed outright (SIGKILL) leaves the file, but not the lock: the kernel releases a
    // dead process's flock, so the next run takes it at once, traces and removes the file.
    registerInterruptPath(path_);
  }
  ~EntryLock() {
    if (fd_ < 0) return;
    ::unlink(path_.c_str());  // before the unlock: a newcomer then makes a fresh file, and finds the entry
    unregisterInterruptPath(path_);
    ::close(fd_);
  }
  EntryLock(const EntryLock&) = delete;
  EntryLock& operator=(const EntryLock&) = delete;

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace

namespace {

// A camera whose every pixel misses the geometry has nothing to compare, whatever the method: bad
// input, the same exit 2 and message from every command that compares a scene through the cache
// (run, sweep, tune, stability), before any raster work. (A comparison that scores no pixel because
// the renderers disagree on every surface is a result, not this: the row says nothing_compared.)
void checkCameraSeesSurface(const Scene& scene, const Frame& reference) {
  if (!reference.has("hit")) return;
  for (float hit : reference.get("hit"))
    if (hit > 0.0f) return;
  throw InputError(formatError(scene.path, "/camera",
                               "scene \"" + scene.name + "\": the camera sees no surface (all " +
                                   std::to_string(reference.pixelCount()) +
                                   " pixels of the reference miss the geometry: sky, or only zero-area triangles); "
                                   "expected a camera that sees part of the scene"));
}

}  // namespace

Frame ReferenceCache::get(const Scene& scene, const ReferenceOptions& requested, bool* traced, ReferenceStats* stats) {
  Frame frame = getUnchecked(scene, requested, traced, stats);
  checkCameraSeesSurface(scene, frame);
  return frame;
}

Frame ReferenceCache::getUnchecked(const Scene& scene, const ReferenceOptions& requested, bool* traced,
                                   ReferenceStats* stats) {
  ReferenceOptions options = requested;
  options.channels = ReferenceChannels::Compare;  // what compare and stability read (reference/README.md)
  const std::string path = dir_ + "/" + referenceHash(scene, options) + ".exr";
  if (auto cached = loadEntry(path, scene)) {
    if (traced) *traced = false;
    return std::move(*cached);
  }
  makeDirs(dir_);
  EntryLock lock(path + ".lock");
  if (auto cached = loadEntry(path, scene)) {  // another process traced it while this one waited
    if (traced) *traced = false;
    return std::move(*cached);
  }
  Frame frame = renderReference(scene, options, stats);
  writeFrameExr(frame, path);  // atomic: concurrent runs never see a truncated entry
  if (traced) *traced = true;
  return frame;
}

namespace {

// A sized light's truth (soft mode, classify.h): a pixel needs evidence where softDecision may say
// Error, which may be where the decisions agree (a raster 1 over a truth of 0.5). The byte is the
// raster's visibility to within 1.5 / 255 (resolve.frag), so every pixel whose byte lies farther
// than the tolerance less 2 / 255 from the truth is listed: every evidence channel where the raster
// may be too lit (leak and bleed read the depths), the map texel's alone elsewhere (coverage, acne).
EvidenceSelector softSelector(const std::vector<float>& refVis, const std::vector<float>& refSigma) {
  constexpr float kMargin = 2.0f / 255.0f;
  auto truth = std::make_shared<std::vector<std::pair<float, float>>>(refVis.size());
  for (size_t i = 0; i < refVis.size(); ++i)
    (*truth)[i] = {clampVisibility(refVis[i]), kSoftTolerance + kSoftSigmaK * sanitizeSigma(refSigma[i]) - kMargin};
  return [truth](const uint8_t* vis8, int width, int height, EvidenceRequest& request) {
    const size_t n = truth->size();
    if (size_t(width) * size_t(height) != n) return;
    for (size_t i = 0; i < n; ++i) {
      const auto [r, limit] = (*truth)[i];
      const float s = float(vis8[i]) / 255.0f;
      if (!(std::fabs(s - r) > limit)) continue;
      (s > r - kMargin ? request.full : request.occluder).push_back(uint32_t(i));
    }
  };
}

}  // namespace

EvidenceSelector disagreementSelector(const Frame& reference, const std::string& light) {
  const std::string name = "light." + light + ".vis";
  if (light.empty() || !reference.has(name) || reference.get(name).size() != reference.pixelCount()) return {};
  // The reference's decisions as bytes (1 lit, 0 shadowed), made once: a byte's decision is its
  // top bit, so 32 pixels at a time are checked for any disagreement before any is listed.
  const std::vector<float>& refVis = reference.get(name);
  const std::string sigmaName = "light." + light + ".vis_sigma";
  if (reference.has(sigmaName) && reference.get(sigmaName).size() == refVis.size())
    return softSelector(refVis, reference.get(sigmaName));
  auto lit = std::make_shared<std::vector<uint8_t>>(refVis.size());
  for (size_t i = 0; i < refVis.size(); ++i) (*lit)[i] = litDecision(refVis[i]) ? 1 : 0;
  // Where the reference is lit the raster shadowed the pixel, and only the map texel decides its
  // class (classifyDisagreement: coverage by in_map, acne by the occluder; the depth and bias
  // evidence counts only where the reference is shadowed): those get the occluder's evidence alone.
  return [lit](const uint8_t* vis8, int width, int height, EvidenceRequest& request) {
    const size_t n = lit->size();
    if (size_t(width) * size_t(height) != n) return;  // another frame: the rasterizer's own pixels only
    const uint8_t* ref = lit->data();
    constexpr size_t kBlock = 32;
    for (size_t b = 0; b < n; b += kBlock) {
      const size_t e = std::min(n, b + kBlock);
      uint8_t any = 0;
      for (size_t i = b; i < e; ++i) any |= uint8_t((vis8[i] >> 7) ^ ref[i]);
      if (!any) continue;
      for (size_t i = b; i < e; ++i)
        if ((vis8[i] >> 7) != ref[i]) (ref[i] ? request.occluder : request.full).push_back(uint32_t(i));
    }
  };
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
