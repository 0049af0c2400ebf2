// `shadowlab run SCENE [--method M.json] [--set key=value|scene:/pointer=value ...] -o DIR`: reference (cached by
// content hash), raster and compare in one process; writes metrics.json, errors.png, triptych.png.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>

#include <unistd.h>

#include "command.h"
#include "interrupt.h"
#include "job_limits.h"
#include "shadowlab/compare/adapter_session.h"
#include "shadowlab/compare/interrupt_cleanup.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/compare/results.h"
#include "shadowlab/compare/set_arguments.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/adapter_manifest.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace cmd_run {
namespace {

namespace fs = std::filesystem;
using namespace shadowlab;

struct Options {
  std::string scene;
  std::string methodFile;
  std::vector<std::string> sets;
  std::string light;
  int spp = 1;
  int lightSamples = kDefaultLightSamples;
  std::string outDir;
  std::string cacheDir;
  std::string device;
  double gpuTimeoutS = 0;
  bool keepImages = false;
  double maxMemoryGiB = 0;
};

// metrics.json's row of one configuration, its timings still to come.
ResultRow resultRow(const Scene& scene, const std::string& config, const std::string& light, const Method& method,
                    const Metrics& metrics) {
  ResultRow row;
  row.scene = scene.name;
  row.config = config;
  row.light = light;
  row.method = methodToJson(method);
  row.metrics = metrics.toJson();
  return row;
}

// renderer=: the frame comes from an outside renderer's adapter (adapters/README.md), scored as
// `compare SCENE FRAME` scores one (or, for a `shadowlab` frame, as the built-in path compares).
// The adapter's output is kept as adapter.log beside metrics.json; a failure (exit 3) names the log.
int runWithAdapter(const Options& o, const Scene& scene, const std::string& light, const std::string& config,
                   const Method& method) {
  checkAdapterMayRun(method, "shadowlab run");
  const AdapterManifest& a = *rendererManifest(method);
  const std::string created = app::firstMissingFolder(o.outDir);
  OutputFolder out(o.outDir);
  if (!created.empty()) registerInterruptPath(created);  // until out.keep()
  ReferenceCache cache(o.cacheDir);
  OutputFolder cacheFolder(cache.dir(), "--cache");
  cacheFolder.keep();
  ReferenceOptions referenceOptions;
  referenceOptions.spp = o.spp;
  referenceOptions.lightSamples = o.lightSamples;
  referenceOptions.progress = app::terminalProgress("run: tracing the reference");
  const auto configStart = std::chrono::steady_clock::now();
  Frame reference;
  double referenceMs = 0;
  if (a.frame == AdapterManifest::FrameKind::Shadowlab) {
    const auto r0 = std::chrono::steady_clock::now();
    reference = cache.get(scene, referenceOptions);
    referenceMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - r0).count();
  }
  const std::string work = cache.dir() + "/adapter-work/run-" + std::to_string(long(::getpid()));
  AdapterSession session(work, cache.dir());
  std::vector<AdapterOutcome> outcomes = session.render(scene, light, {{config, method}}, reference);
  const AdapterOutcome& r = outcomes.front();
  r.throwIfFailed();  // exit 3: its folder, with the log, stays for the user to read
  const double configWallMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - configStart).count();
  const Frame& truth = a.frame == AdapterManifest::FrameKind::Shadowlab ? reference : session.truth();

  ResultRow row = resultRow(scene, config, light, method, r.metrics);
  row.timings = r.timings;
  if (referenceMs > 0) row.timings[timing::kReferenceMs] = referenceMs;
  row.timings[timing::kConfigWallMs] = configWallMs;
  const fs::path dir(o.outDir);
  std::error_code ec;
  fs::copy_file(session.lastBatchDir() + "/adapter.log", dir / "adapter.log", fs::copy_options::overwrite_existing, ec);
  fs::copy_file(r.frameDir + "/renderer.json", dir / "renderer.json", fs::copy_options::overwrite_existing, ec);
  if (o.keepImages) {
    writeFrameExr(truth, (dir / "reference.exr").string());
    writeFrameExr(r.frame, (dir / "raster.exr").string());
  }
  writeErrorsPng((dir / "errors.png").string(), r.classification, &truth);
  writeTriptychPng((dir / "triptych.png").string(), truth, r.frame, r.classification);
  writeMetricsJson((dir / "metrics.json").string(), row);
  out.keep();
  if (!created.empty()) unregisterInterruptPath(created);
  fs::remove_all(work, ec);
  const Metrics& m = r.metrics;
  std::printf("renderer: %s (%s): frame %.2f ms (its own), %.0f ms with start-up\n", a.name.c_str(), a.path.c_str(),
              r.timings.value(timing::kRendererFrameMs, 0.0), r.timings.value(timing::kAdapterMs, 0.0));
  if (m.nothingCompared()) {
    std::printf("wrote %s/metrics.json, errors.png, triptych.png, adapter.log\n", o.outDir.c_str());
    std::fflush(stdout);
    std::fprintf(stderr, "%s: /camera: error: %s\n", scene.path.c_str(), nothingComparedMessage(m).c_str());
    return 2;
  }
  std::printf("compare: %llu pixels: error_rate %.4f (%s), shadow_iou %.4f\n", (unsigned long long)m.pixelsCompared,
              m.errorRate, errorClassSummary(m, true).c_str(), m.shadowIou);
  std::printf("wrote %s/metrics.json, errors.png, triptych.png, adapter.log\n", o.outDir.c_str());
  return 0;
}

int run(const Options& o) {
  app::cleanUpOnSignal("run");
  // ---- inputs: every error surfaces before anything is traced or written -------------------
  const SetArguments set = applySetArguments(o.methodFile, o.sets);  // method keys and scene: values
  const Method& method = set.method;
  const Scene scene = loadScene(resolveScenePath(o.scene), set.sceneOverrides);
  if (!o.light.empty() && !scene.findLight(o.light)) {
    std::string names;
    for (const auto& l : scene.lights) names += (names.empty() ? "" : ", ") + l.name;
    throw InputError("--light " + o.light + ": error: scene " + scene.path + " has no light \"" + o.light +
                     "\"; expected one of: " + (names.empty() ? "(none)" : names));
  }
  if (scene.lights.empty() && scene.projectors.empty()) {
    throw InputError(formatError(scene.path, "/lights",
                                 "the scene has no light and no projector; expected at least one to compare"));
  }
  checkSpp(o.spp, "--spp");
  checkLightSamples(o.lightSamples, "--light-samples");
  const std::string light = scene.lightOrDefault(o.light);

  // The one name of the configuration (config_name.h), as sweep, tune and stability name it: the
  // gate matches this row with theirs.
  const std::string& config = set.config;

  checkGpuTimeout(o.gpuTimeoutS, "--gpu-timeout-s");
  if (!method.renderer.empty()) return runWithAdapter(o, scene, light, config, method);
  precompileTechnique(method);  // a technique that does not compile: exit 2 before any output
  app::checkMemory("run", app::compareJobMemory(scene, method), o.maxMemoryGiB);
  // Every output location, before any work: a bad -o or --cache must not cost a trace first.
  const std::string created = app::firstMissingFolder(o.outDir);
  OutputFolder out(o.outDir);
  if (!created.empty()) registerInterruptPath(created);  // until out.keep()
  ReferenceCache cache(o.cacheDir);
  OutputFolder cacheFolder(cache.dir(), "--cache");
  cacheFolder.keep();  // a cache outlives the command

  // ---- work ----------------------------------------------------------------------------------
  RasterDeviceOptions deviceOptions;
  deviceOptions.device = o.device;
  deviceOptions.gpuTimeoutS = o.gpuTimeoutS;
  Rasterizer rasterizer(deviceOptions);
  app::checkDeviceMemory("run", rasterizer, scene, method, light);  // before the reference is traced
  ReferenceOptions referenceOptions;
  referenceOptions.spp = o.spp;
  referenceOptions.lightSamples = o.lightSamples;
  referenceOptions.progress = app::terminalProgress("run: tracing the reference");
  // config_wall_ms: this configuration end to end (reference traced or loaded, render, compare),
  // as a sweep row measures it; the device start above is the command's, not the configuration's.
  const auto configStart = std::chrono::steady_clock::now();
  const RunResult r = runPipeline(scene, method, rasterizer, cache, light, referenceOptions);
  const double configWallMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - configStart).count();
  if (r.referenceTraced) {
    std::printf("reference: traced (%.3f s, %.1f Mrays/s) -> %s\n", r.referenceStats.traceSeconds,
                r.referenceStats.mraysPerS(), cache.dir().c_str());
  } else {
    std::printf("reference: cached (%s)\n", cache.dir().c_str());
  }
  std::printf("raster: %s, shadow %.2f ms, camera %.2f ms, readback %.2f ms\n", rasterizer.deviceName().c_str(),
              r.timings.shadowGpuMs, r.timings.cameraGpuMs, r.timings.readbackMs);

  ResultRow row = resultRow(scene, config, light, method, r.metrics);
  row.timings = {{timing::kShadowGpuMs, r.timings.shadowGpuMs},
                 {timing::kCameraGpuMs, r.timings.cameraGpuMs},
                 {timing::kVisibilityGpuMs, r.timings.visibilityGpuMs},
                 {timing::kLookupGpuMs, r.timings.lookupGpuMs},
                 {timing::kMethodGpuMs, r.timings.methodGpuMs()},
                 {timing::kMomentsGpuMs, r.timings.momentsGpuMs},
                 {timing::kEvidenceGpuMs, r.timings.evidenceGpuMs},
                 {timing::kReadbackMs, r.timings.readbackMs},
                 {timing::kRenderWallMs, r.timings.renderWallMs},
                 {timing::kCompareMs, r.compareMs},
                 {timing::kReferenceMs, r.referenceMs},
                 {timing::kConfigWallMs, configWallMs}};
  if (r.timings.sdsmSampled) {
    row.timings[timing::kSdsmGpuMs] = r.timings.sdsmGpuMs;
    row.timings[timing::kSdsmReduceMs] = r.timings.sdsmReduceMs;
  }

  const fs::path dir(o.outDir);
  if (o.keepImages) {
    writeFrameExr(r.reference, (dir / "reference.exr").string());
    writeFrameExr(r.raster, (dir / "raster.exr").string());
  }
  writeErrorsPng((dir / "errors.png").string(), r.classification, &r.reference);
  writeTriptychPng((dir / "triptych.png").string(), r.reference, r.raster, r.classification);
  // metrics.json last: its presence means the run finished.
  writeMetricsJson((dir / "metrics.json").string(), row);
  out.keep();
  if (!created.empty()) unregisterInterruptPath(created);
  const Metrics& m = r.metrics;
  const char* written = o.keepImages ? ", reference.exr, raster.exr" : "";
  if (m.nothingCompared()) {
    // The outputs are written (errors.png shows what each renderer saw), but a comparison of no
    // pixel is no result: exit 2, so that a script stops here rather than at the gate.
    std::printf("compare: %.1f ms, 0 pixels compared (%llu geometry mismatch)\n", r.compareMs,
                (unsigned long long)m.count(PixelClass::GeometryMismatch));
    std::printf("wrote %s/metrics.json, errors.png, triptych.png%s\n", o.outDir.c_str(), written);
    std::fflush(stdout);
    std::fprintf(stderr, "%s: /camera: error: %s\n", scene.path.c_str(), nothingComparedMessage(m).c_str());
    return 2;
  }
  std::printf("compare: %.1f ms, %llu pixels: error_rate %.4f (%s), shadow_iou %.4f, m_median %.2f\n", r.compareMs,
              (unsigned long long)m.pixelsCompared, m.errorRate, errorClassSummary(m, true).c_str(), m.shadowIou,
              m.mMedian);
  if (m.hasProjector) std::printf("%s\n", projectorSummary(m).c_str());
  if (m.mCapped > 0) std::printf("%s\n", footprintCapNote(m).c_str());
  std::printf("wrote %s/metrics.json, errors.png, triptych.png%s\n", o.outDir.c_str(), written);
  return 0;
}

app::Registrar reg{"run", [](CLI::App& app) {
                     auto opts = std::make_shared<Options>();
                     auto* sub = app.add_subcommand("run", "Reference (cached), raster and compare in one process");
                     sub->add_option("SCENE", opts->scene, "Bundled scene name or path to a scene file")->required();
                     sub->add_option("--method", opts->methodFile, "Method file (JSON, see raster/METHODS.md)");
                     sub->add_option("--set", opts->sets,
                                     "Method setting or scene value key=value, repeatable (e.g. --set map.size=4096, "
                                     "--set scene:/lights/0/elevation_deg=10)");
                     sub->add_option("--light", opts->light,
                                     "Light to render and compare (default: the scene's first)");
                     sub->add_option("--spp", opts->spp, "Reference samples per pixel, 1..1024")
                         ->check(app::integerRange(kMinSpp, kMaxSpp, "reference samples per pixel"))
                         ->capture_default_str();
                     sub->add_option("--light-samples", opts->lightSamples,
                                     "Reference samples of a sized light per pixel sample, 1..4096")
                         ->check(app::integerRange(kMinLightSamples, kMaxLightSamples,
                                                   "samples of a sized light per pixel sample"))
                         ->capture_default_str();
                     sub->add_option("-o,--out", opts->outDir, "Output folder")->required();
                     app::addMaxMemoryOption(sub, &opts->maxMemoryGiB);
                     sub->add_option("--cache", opts->cacheDir,
                                     "Reference cache folder (default: $SHADOWLAB_CACHE, else .shadowlab-cache)");
                     sub->add_option("--device", opts->device, "Vulkan device name substring (default: lavapipe)");
                     app::addGpuTimeoutOption(sub, &opts->gpuTimeoutS);
                     sub->add_flag("--keep-images", opts->keepImages,
                                   "Also write reference.exr (the cached reference: the Compare channel set; "
                                   "`shadowlab reference --all-channels` gives every channel) and raster.exr");
                     return std::function<int()>([opts] { return run(*opts); });
                   }};

}  // namespace
}  // namespace cmd_run
