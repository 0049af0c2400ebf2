// The production sweep runner: what runPipeline does per configuration, with the reference kept
// in memory between configurations of the same scene. runPipeline asks the ReferenceCache for
// every call, which reads a 1080p multi-channel EXR from disk each time (hundreds of ms); a sweep
// of a hundred configurations cannot afford that. The metrics are the same: the same cached
// reference frame, the same Rasterizer::render, the same compareFrames with the same light, through
// a CompareContext kept per evidence group (compareRow below; the same bits)
// (SweepCli.SmallSweepRowsMatchShadowlabRunExactly in tests/sweep_cli_test.cpp checks the numbers
// against `shadowlab run`).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <future>
#include <list>
#include <map>
#include <memory>

#include "shadowlab/compare/adapter_session.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/config_name.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/adapter_manifest.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

class PipelineRunner final : public SweepRunner {
 public:
  void setGpuTimeout(double seconds) { deviceOptions_.gpuTimeoutS = seconds; }
  PipelineRunner(const std::string& cacheDir, int spp, const std::string& device, size_t keepReferences,
                 bool fullEvidence, bool keepTriptychs, int lightSamples)
      : cache_(cacheDir),
        keep_(keepReferences < 1 ? 1 : keepReferences),
        fullEvidence_(fullEvidence),
        keepTriptychs_(keepTriptychs) {
    referenceOptions_.spp = spp;
    referenceOptions_.lightSamples = lightSamples;
    deviceOptions_.device = device;
    // The first reference read needs the image library: where that is a module loaded on first
    // use (~0.2 s; a build without OpenEXR and libpng), it loads from now on beside the plan's
    // checks and the report's Python start, so that the first row's read finds it loaded. (The
    // device's own libraries load after it: two loads of shared libraries never overlap.)
    preloadImageLibrary();
  }

  SweepRunOutput run(const Scene& scene, const Method& method, const std::string& light,
                     const std::string& imagesDir) override {
    if (!method.renderer.empty()) return runAdapter(scene, method, light, imagesDir);
    RasterTimings t;
    CompareOptions options;
    options.light = scene.lightOrDefault(light);
    const bool keep = !imagesDir.empty();
    // A scene's first row reads (or traces) its reference on a thread of its own while the
    // rasterizer draws: the reference is first needed once the row's visibility is read back (the
    // selector below), so the read overlaps the shadow and camera passes and, on the sweep's first
    // row, the pipelines' compiles. Declared before anything that can throw: leaving run() through
    // an exception waits for the read, which holds `scene`, to end.
    const std::string referenceKey = referenceHash(scene, referenceOptions_);
    std::future<Loaded> loading;
    const Frame* held = heldReference(referenceKey);
    if (!held) {
      freeReferencesFor(1);  // before reading the next one, as referenceFor
      loading = std::async(std::launch::async, [this, &scene] { return loadReference(scene); });
    }
    // A row that keeps no pictures needs the metrics only: evidence on demand (raster.h), the
    // same metrics (tests/compare_on_demand_test.cpp). Pictures and --full-evidence: every channel.
    // While the reference is being read, a selector that waits for it and then asks the same
    // selector; a failed read lists nothing here and is thrown once the frame is back.
    const bool evidenceOnDemand = !keep && !fullEvidence_ && !options.light.empty();
    EvidenceSelector waiting;
    std::exception_ptr readFailed;
    if (evidenceOnDemand && !held)
      waiting = [&](const uint8_t* vis8, int width, int height, EvidenceRequest& request) {
        try {
          held = &adoptReference(referenceKey, loading);
        } catch (...) {
          readFailed = std::current_exception();
          return;
        }
        if (const EvidenceSelector* s = onDemand(referenceKey, *held, options.light)) (*s)(vis8, width, height, request);
      };
    const EvidenceSelector* select = !evidenceOnDemand ? nullptr
                                     : held            ? onDemand(referenceKey, *held, options.light)
                                                       : &waiting;
    // The row's method time is this render's single sample (a pipeline's first use compiles in an
    // untimed run of its own inside render); runSweep times again the rows where it decides
    // something (retime below; compare/TIMINGS.md, "Timed repetitions").
    Frame raster = rasterizer().render(scene, method, light, &t, nullptr, select);
    if (readFailed) std::rethrow_exception(readFailed);
    if (!held) held = &adoptReference(referenceKey, loading);
    const Frame& reference = *held;
    Classification classification;
    SweepRunOutput out;
    const auto c0 = Clock::now();
    Metrics m = compareRow(referenceKey, reference, raster, options, keep ? &classification : nullptr);
    const double compareMs = msSince(c0);
    out.metrics = m.toJson();
    if (evidenceOnDemand && keepTriptychs_)
      keepForTriptych(method, light, referenceKey, reference, raster, options, out.metrics);
    if (keep) {
      writeFrameExr(raster, imagesDir + "/raster.exr");
      writeErrorsPng(imagesDir + "/errors.png", classification);
    }
    rasterizer().recycle(std::move(raster));  // the next row's planes, without fresh memory
    out.timings = {
        {timing::kShadowGpuMs, t.shadowGpuMs},         {timing::kCameraGpuMs, t.cameraGpuMs},
        {timing::kVisibilityGpuMs, t.visibilityGpuMs}, {timing::kLookupGpuMs, t.lookupGpuMs},
        {timing::kMethodGpuMs, t.methodGpuMs()},       {timing::kMomentsGpuMs, t.momentsGpuMs},
        {timing::kEvidenceGpuMs, t.evidenceGpuMs},     {timing::kReadbackMs, t.readbackMs},
        {timing::kRenderWallMs, t.renderWallMs},       {timing::kCompareMs, compareMs},
    };
    if (t.sdsmSampled) {
      out.timings[timing::kSdsmGpuMs] = t.sdsmGpuMs;
      out.timings[timing::kSdsmReduceMs] = t.sdsmReduceMs;
    }
    return out;
  }

  // More samples of the method's time (the row's own render in the loop is the first): the
  // configuration rendered again, its method's timestamps a sample (its pipelines are the loop's,
  // compiled; the maps of its size touched before), then `runs - 1` runs of the method's passes
  // alone (Rasterizer::retimeMethod), each submitted and timed on its own. The render resolves no
  // evidence (a selector that lists no pixel): only the method's passes matter here.
  std::vector<MethodSample> timeAgain(const Scene& scene, const Method& method, const std::string& light,
                                      int runs) override {
    std::vector<MethodSample> out;
    if (runs < 1 || !method.renderer.empty()) return out;  // an adapter's rows: the renderer's own time
    const EvidenceSelector none = [](const uint8_t*, int, int, EvidenceRequest&) {};
    RasterTimings t;
    Frame raster = rasterizer().render(scene, method, light, &t, nullptr, fullEvidence_ ? nullptr : &none);
    out.push_back({t.shadowGpuMs, t.lookupGpuMs, t.momentsGpuMs, t.sdsmGpuMs});
    if (runs > 1)
      for (const Rasterizer::MethodTiming& m : rasterizer().retimeMethod(runs - 1))
        out.push_back({m.shadowGpuMs, m.lookupGpuMs, m.momentsGpuMs, m.sdsmGpuMs});
    rasterizer().recycle(std::move(raster));
    return out;
  }

  bool writeTriptych(const Scene& scene, const Method& method, const std::string& light,
                     const std::string& pngPath) override {
    if (!method.renderer.empty()) return false;  // an adapter's frames are not kept for pictures
    std::string referenceKey;
    const Frame& reference = referenceFor(scene, &referenceKey);
    // A configuration the loop kept as its scene's best or worst: drawn from what it kept.
    if (const KeptPicture* k = keptPicture(referenceKey, method, light)) {
      Frame raster = *k->geometry;
      raster.meta = k->meta;
      if (!k->vis.empty()) raster.add(k->visName) = k->vis;
      writeTriptychPng(pngPath, reference, raster, k->classification);
      ++triptychsKept_;
      return true;
    }
    CompareOptions options;
    options.light = scene.lightOrDefault(light);
    // Evidence on demand, as the rows: the triptych draws the raster's visibility, hit and ids
    // (whole planes in such a frame too) and the classification, which is the full frame's (the
    // agreeing pixels are correct either way); the same picture, bit for bit
    // (SweepCli.ReportTriptychsOnDemandEqualFullFrameOnes). It also runs on the pipelines the
    // loop compiled, where a full frame would compile its own full-evidence pipelines.
    RasterTimings t;  // for partialEvidence (a full frame with --full-evidence or projectors)
    Frame raster =
        rasterizer().render(scene, method, light, &t, nullptr, onDemand(referenceKey, reference, options.light));
    triptychsOnDemand_ += t.partialEvidence ? 1 : 0;
    Classification classification;
    compareFrames(reference, raster, options, &classification);
    writeTriptychPng(pngPath, reference, raster, classification);
    // Its planes, and the kept ones it lends (hit, ids, m: raster.h), go back to the rasterizer:
    // the next triptych's full frame then needs neither fresh memory nor those planes again.
    rasterizer().recycle(std::move(raster));
    return true;
  }

  void prefetch(const Scene& scene, const std::vector<std::pair<std::string, Method>>& configs,
                const std::string& light, const std::string& workDir) override {
    std::vector<AdapterFrame> frames;
    for (const auto& [config, method] : configs) frames.push_back({config, method});
    if (!frames.empty()) adapterBatch(scene, scene.lightOrDefault(light), frames, workDir);
  }

  void checkMethod(const Method& method, const std::string& origin) override {
    if (!method.renderer.empty()) return checkAdapterMayRun(method, origin);  // its own limits: its frame says
    const int maxSize = rasterizer().maxMapSize();
    if (method.mapSize > maxSize)
      throw InputError(formatError(origin, "map.size",
                                   "got " + std::to_string(method.mapSize) + "; expected at most " +
                                       std::to_string(maxSize) + " (the largest image " + rasterizer().deviceName() +
                                       " allows)"));
  }

  std::string deviceName() override { return rasterizer().deviceName(); }

  nlohmann::json info() const override {
    nlohmann::json j = nlohmann::json::object();
    j["device"] = rasterizer_ ? rasterizer_->deviceName() : std::string("(not started: every row was resumed)");
    j["reference_cache"] = cache_.dir();
    j["references_traced"] = traced_;
    j["references_loaded"] = loaded_;
    j["reference_wall_seconds"] = referenceWallSeconds_;  // references traced or loaded, summed
    j["reference_spp"] = referenceOptions_.spp;
    j["reference_light_samples"] = referenceOptions_.lightSamples;
    // Rows compared through a group's CompareContext, and contexts built (compareRow).
    j["compare_context_rows"] = contextRows_;
    j["compare_contexts_built"] = contextsBuilt_;
    j["compare_contexts_shared"] = contextsShared_;  // built sharing another group's decisions
    j["triptychs_on_demand"] = triptychsOnDemand_;  // triptychs rendered from a partial frame (writeTriptych)
    j["triptychs_kept"] = triptychsKept_;  // triptychs drawn from what the loop kept (keepForTriptych)
    return j;
  }

 private:
  // An outside renderer's rows (adapter_session.h): scored from the scene's batch where prefetch
  // rendered one, else rendered as a batch of one. A failed frame throws its AdapterError (exit 3).
  static std::string adapterKey(const Scene& scene, const std::string& light, const Method& method) {
    return scene.hash + "\n" + light + "\n" + dumpJson(methodToJson(method));
  }

  void adapterBatch(const Scene& scene, const std::string& light, const std::vector<AdapterFrame>& frames,
                    const std::string& workDir) {
    if (!adapter_ || adapterDir_ != workDir) {
      adapter_ = std::make_unique<AdapterSession>(workDir, cache_.dir());
      adapterDir_ = workDir;
    }
    // One renderer a batch: a sweep over renderer= holds several, of either frame kind.
    std::map<std::string, std::vector<AdapterFrame>> byRenderer;
    for (const AdapterFrame& f : frames) byRenderer[rendererManifest(f.method)->path].push_back(f);
    adapterOutcomes_.clear();
    const Frame none;
    for (const auto& [path, group] : byRenderer) {
      // A shadowlab frame is compared against the reference the built-in rows use; a png frame
      // against the truth the session traces with every channel.
      const bool ownFrame = rendererManifest(group.front().method)->frame == AdapterManifest::FrameKind::Shadowlab;
      std::vector<AdapterOutcome> outcomes = adapter_->render(scene, light, group, ownFrame ? referenceFor(scene) : none);
      for (size_t i = 0; i < group.size(); ++i)
        adapterOutcomes_[adapterKey(scene, light, group[i].method)] = std::move(outcomes[i]);
    }
  }

  SweepRunOutput runAdapter(const Scene& scene, const Method& method, const std::string& light,
                            const std::string& imagesDir) {
    const std::string l = scene.lightOrDefault(light);
    const std::string key = adapterKey(scene, l, method);
    auto it = adapterOutcomes_.find(key);
    if (it == adapterOutcomes_.end()) {
      adapterBatch(scene, l, {{configName(method, {}), method}}, cache_.dir() + "/adapter-work/" + std::to_string(::getpid()));
      it = adapterOutcomes_.find(key);
    }
    const AdapterOutcome o = std::move(it->second);
    adapterOutcomes_.erase(it);
    o.throwIfFailed();
    SweepRunOutput out;
    out.metrics = o.metrics.toJson();
    out.timings = o.timings;
    if (!imagesDir.empty()) {
      writeFrameExr(o.frame, imagesDir + "/raster.exr");
      writeErrorsPng(imagesDir + "/errors.png", o.classification);
    }
    return out;
  }

  std::unique_ptr<AdapterSession> adapter_;
  std::string adapterDir_;
  std::map<std::string, AdapterOutcome> adapterOutcomes_;

  // The selector for evidence on demand (null with --full-evidence, or where the reference gives
  // none): the disagreement selector of the reference and light, kept while they stay, as it holds
  // the reference's decisions as bytes, made once rather than per row.
  const EvidenceSelector* onDemand(const std::string& referenceKey, const Frame& reference, const std::string& light) {
    if (fullEvidence_) return nullptr;
    const std::string key = referenceKey + "\n" + light;
    if (key != selectorKey_) {
      selector_ = disagreementSelector(reference, light);
      selectorKey_ = key;
    }
    return selector_ ? &selector_ : nullptr;
  }

  Rasterizer& rasterizer() {
    if (!rasterizer_) rasterizer_ = std::make_unique<Rasterizer>(deviceOptions_);
    return *rasterizer_;
  }

  // Only the last `keep_` scenes' references are held (1 for a sweep): a 1080p reference frame
  // with all its channels is well over 100 MB, and the plan visits scenes one after another.
  // shadowlab tune alternates scenes per configuration and keeps one per scene.
  const Frame& referenceFor(const Scene& scene, std::string* key = nullptr) {
    const std::string hash = referenceHash(scene, referenceOptions_);
    if (key) *key = hash;
    if (const Frame* held = heldReference(hash)) return *held;
    freeReferencesFor(1);  // free before reading the next one
    return keepReference(hash, loadReference(scene));
  }

  // A reference read or traced, with what it cost (on the thread that read it).
  struct Loaded {
    Frame frame;
    bool traced = false;
    double seconds = 0;
  };
  Loaded loadReference(const Scene& scene) {
    const auto t0 = Clock::now();
    Loaded l;
    l.frame = cache_.get(scene, referenceOptions_, &l.traced);
    l.seconds = msSince(t0) / 1000.0;
    return l;
  }
  // The held reference of `hash`, made the most recently used; nullptr when none is held.
  const Frame* heldReference(const std::string& hash) {
    for (auto it = held_.begin(); it != held_.end(); ++it)
      if (it->first == hash) {
        held_.splice(held_.begin(), held_, it);  // most recently used first
        return &held_.front().second;
      }
    return nullptr;
  }
  // Drops the least recently used references until `more` fit within keep_.
  void freeReferencesFor(size_t more) {
    while (!held_.empty() && held_.size() + more > keep_) held_.pop_back();
  }
  // Holds a reference read after freeReferencesFor(1) made room for it.
  const Frame& keepReference(const std::string& hash, Loaded&& l) {
    referenceWallSeconds_ += l.seconds;
    (l.traced ? traced_ : loaded_) += 1;
    held_.emplace_front(hash, std::move(l.frame));
    return held_.front().second;
  }
  // The reference `loading` reads, held from now on (once: later calls find it held); rethrows
  // what the read threw.
  const Frame& adoptReference(const std::string& hash, std::future<Loaded>& loading) {
    if (const Frame* held = heldReference(hash)) return *held;
    return keepReference(hash, loading.get());
  }

  // compareFrames for one row. A frame rendered on demand names its evidence group (the
  // configurations sharing hit, ids, m and cascade: map size, fit, light); from a group's second
  // row on, a CompareContext (compare.h) of that reference, light and group holds what does not
  // change and the row reads only its vis and the disagreeing pixels' evidence: the same metrics.
  // The context is built on the second row, not the first, so that a plan whose every row is a new
  // group (map.size the fastest axis, more sizes than are kept) pays nothing for it. Where a context
  // of the same reference and light is kept (another group of the same camera: another map size),
  // the group's first row builds its context at once, sharing that one's per-pixel decisions
  // (compare.h: checked to apply) for about the price of the full compare it returns.
  // A row's context key: its reference, light and evidence group ("" for a frame without a group).
  // The key up to the group names the camera (contextCamera): the groups that may share decisions.
  static std::string contextCamera(const std::string& referenceKey, const CompareOptions& options) {
    return referenceKey + "\n" + options.light + "\n";
  }
  static std::string contextKey(const std::string& referenceKey, const CompareOptions& options, const Frame& raster) {
    auto group = raster.meta.find("evidence_group");
    if (group == raster.meta.end() || !group->is_string()) return "";
    return contextCamera(referenceKey, options) + group->get<std::string>();
  }
  Metrics compareRow(const std::string& referenceKey, const Frame& reference, const Frame& raster,
                     const CompareOptions& options, Classification* classification) {
    const std::string key = contextKey(referenceKey, options, raster);
    if (key.empty()) return compareFrames(reference, raster, options, classification);
    bool again = false;  // a context of this key, made from a reference since read again
    for (auto it = contexts_.begin(); it != contexts_.end(); ++it)
      if (it->first == key) {
        if (!it->second.appliesTo(reference, raster)) {
          contexts_.erase(it);
          again = true;
          break;
        }
        contexts_.splice(contexts_.begin(), contexts_, it);  // most recently used first
        ++contextRows_;
        return compareFrames(it->second, reference, raster, classification);
      }
    const std::string camera = contextCamera(referenceKey, options);
    auto sameCamera = std::find_if(contexts_.begin(), contexts_.end(),
                                   [&](const auto& c) { return c.first.compare(0, camera.size(), camera) == 0; });
    if (!again && sameCamera != contexts_.end()) {
      Metrics m;
      CompareContext context(reference, raster, options, &sameCamera->second, &m);
      const bool shared = context.sharesPixelsWith(sameCamera->second);  // else built whole: kept all the same
      while (contexts_.size() >= kKeptContexts) contexts_.pop_back();
      contexts_.emplace_front(key, std::move(context));
      ++contextsBuilt_;
      contextsShared_ += shared;
      if (classification) return compareFrames(contexts_.front().second, reference, raster, classification);
      return m;
    }
    auto seen = std::find(seen_.begin(), seen_.end(), key);
    if (again) {
      if (seen != seen_.end()) seen_.erase(seen);
    } else if (seen == seen_.end()) {
      seen_.push_front(key);
      if (seen_.size() > 2 * kKeptContexts) seen_.pop_back();
      return compareFrames(reference, raster, options, classification);
    } else {
      seen_.erase(seen);
    }
    while (contexts_.size() >= kKeptContexts) contexts_.pop_back();
    contexts_.emplace_front(key, CompareContext(reference, raster, options));
    ++contextsBuilt_;
    contextRows_ += contexts_.front().second.appliesTo(reference, raster);
    return compareFrames(contexts_.front().second, reference, raster, classification);
  }

  // The report draws a triptych of each scene's best and worst row (lowest and highest finite
  // error_rate, the first of equals, in row order: sweep_report.cpp). The loop runs the rows in that
  // order, so the runner keeps, per scene variant (reference), the two rows that are best and worst
  // so far: the raster planes the triptych draws (hit, object_id, the light's vis) and the row's
  // classification. writeTriptych then draws a kept row instead of rendering it again (about 0.35 s
  // of a 100-row sweep's report: compare/SWEEPS.md, "The report's time"); a row it does not hold (resumed, or
  // a variant dropped for memory) is rendered as before. The same picture, byte for byte
  // (SweepCli.ReportTriptychsOnDemandEqualFullFrameOnes).
  struct KeptPicture {
    std::string key;  // keptKey
    double errorRate = 0;
    std::shared_ptr<const Frame> geometry;  // hit and object_id: the camera's, shared by a variant's rows
    nlohmann::json meta;
    std::string visName;
    std::vector<float> vis;
    Classification classification;
  };
  struct KeptPair {
    std::string reference;
    std::shared_ptr<KeptPicture> best, worst;
    std::shared_ptr<const Frame> geometry;
  };
  static std::string keptKey(const std::string& referenceKey, const Method& method, const std::string& light) {
    return referenceKey + "\n" + methodToJson(method).dump() + "\n" + light;
  }
  // About 3 ms a kept row at 1080p (the first: 30 ms), on the loop's main thread: the vis plane
  // copied into the memory of the row it displaces (fresh pages would cost more than the copy), and
  // the classification. The camera's hit and object_id planes are copied once a variant: they depend
  // on the scene and the camera alone, which the reference key names.
  void keepForTriptych(const Method& method, const std::string& light, const std::string& referenceKey,
                       const Frame& reference, const Frame& raster, const CompareOptions& options,
                       const nlohmann::json& metrics) {
    auto it = metrics.find("error_rate");
    if (it == metrics.end() || !it->is_number()) return;
    const double e = it->get<double>();
    if (!std::isfinite(e)) return;
    auto pair = std::find_if(kept_.begin(), kept_.end(), [&](const KeptPair& p) { return p.reference == referenceKey; });
    if (pair == kept_.end()) {
      // The oldest variants' rows go first (rendered again if asked) once the kept rows would pass
      // kKeptBytes: ~45 MB a variant at 1920x1080, ~11 MB at 960x540.
      const size_t pixels = size_t(raster.width) * size_t(raster.height);
      if (keptBytesPerVariant(pixels) > kKeptBytes) return;  // a frame this large: rendered again if asked
      while (!kept_.empty() && (kept_.size() + 1) * keptBytesPerVariant(pixels) > kKeptBytes) kept_.pop_front();
      kept_.push_back({referenceKey, nullptr, nullptr, nullptr});
      pair = std::prev(kept_.end());
    }
    const bool best = !pair->best || e < pair->best->errorRate;
    const bool worst = !pair->worst || e > pair->worst->errorRate;
    if (!best && !worst) return;
    std::shared_ptr<KeptPicture> k;
    if (best && pair->best && pair->best != pair->worst) k = pair->best;  // displaced: its memory reused
    if (!k && worst && pair->worst && pair->worst != pair->best) k = pair->worst;
    if (!k) k = std::make_shared<KeptPicture>();
    k->key = keptKey(referenceKey, method, light);
    k->errorRate = e;
    if (!pair->geometry) {
      auto g = std::make_shared<Frame>();
      g->width = raster.width;
      g->height = raster.height;
      for (const char* name : {"hit", "object_id"})
        if (raster.has(name)) g->add(name) = raster.get(name);
      pair->geometry = std::move(g);
    }
    k->geometry = pair->geometry;
    k->meta = raster.meta;
    k->visName = "light." + options.light + ".vis";
    if (raster.has(k->visName)) {
      const std::vector<float>& vis = raster.get(k->visName);
      k->vis.assign(vis.begin(), vis.end());
    } else {
      k->vis.clear();
    }
    // The row's classification, through its group's context where it has one (the same classes as
    // the full compare's), without counting the row twice.
    const CompareContext* context = nullptr;
    const std::string key = contextKey(referenceKey, options, raster);
    for (const auto& c : contexts_)
      if (!key.empty() && c.first == key && c.second.appliesTo(reference, raster)) context = &c.second;
    if (context)
      compareFrames(*context, reference, raster, &k->classification);
    else
      compareFrames(reference, raster, options, &k->classification);
    if (best) pair->best = k;
    if (worst) pair->worst = k;
  }
  const KeptPicture* keptPicture(const std::string& referenceKey, const Method& method, const std::string& light) const {
    const std::string key = keptKey(referenceKey, method, light);
    for (const KeptPair& p : kept_)
      for (const auto* k : {p.best.get(), p.worst.get()})
        if (k && k->key == key) return k;
    return nullptr;
  }
  // A variant's kept memory at most: its hit and object_id planes, and two rows' vis, classes and
  // reference decisions.
  static size_t keptBytesPerVariant(size_t pixels) { return pixels * (2 * sizeof(float) + 2 * (sizeof(float) + 2)); }
  static constexpr size_t kKeptBytes = size_t(256) << 20;
  std::list<KeptPair> kept_;
  int triptychsKept_ = 0;

  // As many as the rasterizer keeps groups (raster/METHODS.md): a plan whose fastest axis
  // alternates up to 4 groups keeps each one's context. ~22 MB each at 1920x1080.
  static constexpr size_t kKeptContexts = 4;
  std::list<std::pair<std::string, CompareContext>> contexts_;  // key -> context, most recently used first
  int contextRows_ = 0, contextsBuilt_ = 0, contextsShared_ = 0;
  int triptychsOnDemand_ = 0;
  std::string selectorKey_;  // onDemand: the reference hash and light of selector_
  EvidenceSelector selector_;
  std::list<std::string> seen_;  // keys seen once, without a context yet

  ReferenceCache cache_;
  ReferenceOptions referenceOptions_;
  RasterDeviceOptions deviceOptions_;
  std::unique_ptr<Rasterizer> rasterizer_;
  size_t keep_ = 1;
  bool fullEvidence_ = false;                      // --full-evidence: every row renders the full frame
  bool keepTriptychs_ = true;                      // keepForTriptych (off without a report)
  std::list<std::pair<std::string, Frame>> held_;  // reference hash -> frame, most recently used first
  int traced_ = 0, loaded_ = 0;
  double referenceWallSeconds_ = 0;
};

}  // namespace

std::unique_ptr<SweepRunner> makePipelineRunner(const std::string& cacheDir, int spp, const std::string& device,
                                                size_t keepReferences, bool fullEvidence, bool keepTriptychs,
                                                int lightSamples, double gpuTimeoutS) {
  auto runner = std::make_unique<PipelineRunner>(cacheDir, spp, device, keepReferences, fullEvidence, keepTriptychs,
                                                 lightSamples);
  runner->setGpuTimeout(gpuTimeoutS);
  return runner;
}

}  // namespace shadowlab
