// `shadowlab reference SCENE -o DIR [--spp N] [--threads N] [--all-channels] [--set scene:/pointer=value ...]`: traces
// the Embree ground truth and writes DIR/reference.exr (the Compare channel set, the reference cache's; every channel
// with --all-channels: reference/README.md), DIR/reference.png (a readable picture) and DIR/reference.json (ray
// counts, timings, hashes).
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "command.h"
#include "interrupt.h"
#include "job_limits.h"
#include "shadowlab/compare/interrupt_cleanup.h"
#include "shadowlab/compare/set_arguments.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace cmd_reference {
namespace {

struct Options {
  std::string scene;
  std::string outDir;
  int spp = 1;
  int lightSamples = shadowlab::kDefaultLightSamples;
  int threads = 0;
  bool allChannels = false;
  std::vector<std::string> sets;
  double maxMemoryGiB = 0;
};

int run(const Options& options) {
  shadowlab::app::cleanUpOnSignal("reference");
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  // Every argument is checked before anything is traced or written.
  shadowlab::checkSpp(options.spp, "--spp");
  shadowlab::checkLightSamples(options.lightSamples, "--light-samples");
  if (options.threads < 0) {
    throw shadowlab::InputError("shadowlab reference: error: --threads " + std::to_string(options.threads) +
                                "; expected 0 (all hardware threads) or more");
  }
  // The same --set syntax as raster, run, sweep and stability; method keys change the
  // rasterizer, not the truth, so only scene: values apply.
  for (const std::string& s : options.sets)
    if (s.rfind("scene:", 0) != 0)
      throw shadowlab::InputError("--set: error: got \"" + s +
                                  "\"; expected scene:/json/pointer=value (the reference takes no method keys)");
  const shadowlab::SetArguments set = shadowlab::applySetArguments("", options.sets);
  const shadowlab::Scene scene = shadowlab::loadScene(shadowlab::resolveScenePath(options.scene), set.sceneOverrides);
  const shadowlab::ReferenceChannels channelSet =
      options.allChannels ? shadowlab::ReferenceChannels::All : shadowlab::ReferenceChannels::Compare;
  shadowlab::app::checkMemory("reference", shadowlab::app::referenceJobMemory(scene, channelSet), options.maxMemoryGiB);
  const std::string created = shadowlab::app::firstMissingFolder(options.outDir);
  shadowlab::OutputFolder out(options.outDir);  // an unusable -o fails here, before the trace
  if (!created.empty()) shadowlab::registerInterruptPath(created);  // until out.keep()
  const auto loaded = Clock::now();

  shadowlab::ReferenceOptions referenceOptions;
  referenceOptions.spp = options.spp;
  referenceOptions.lightSamples = options.lightSamples;
  referenceOptions.threads = options.threads;
  // The picture is drawn during the trace (the same bytes as referencePicture draws from every
  // channel), so only the channels written are traced: the Compare set unless --all-channels.
  referenceOptions.channels = channelSet;
  referenceOptions.progress = shadowlab::app::terminalProgress("reference: tracing");
  shadowlab::ReferenceStats stats;
  std::vector<uint8_t> picture;
  const shadowlab::Frame frame = shadowlab::renderReference(scene, referenceOptions, &stats, &picture);
  const auto traced = Clock::now();

  const std::string exrPath = options.outDir + "/reference.exr";
  const std::string pngPath = options.outDir + "/reference.png";
  const std::string jsonPath = options.outDir + "/reference.json";
  // The EXR (zip) and the PNG are independent and each mostly one core's work: write them side
  // by side. Both writers are atomic (temporary file + rename).
  std::exception_ptr pngError;
  std::thread pngWriter([&] {
    try {
      shadowlab::writeRgbPng(pngPath, frame.width, frame.height, picture);
    } catch (...) {
      pngError = std::current_exception();
    }
  });
  try {
    shadowlab::writeFrameExr(frame, exrPath);
  } catch (...) {
    pngWriter.join();
    throw;
  }
  pngWriter.join();
  if (pngError) std::rethrow_exception(pngError);
  const auto written = Clock::now();

  auto seconds = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
  nlohmann::json report = {
      {"scene", scene.name},
      {"scene_path", scene.path},
      {"scene_hash", scene.hash},
      {"camera_hash", frame.meta.value("camera_hash", "")},
      {"reference_hash", shadowlab::referenceHash(scene, referenceOptions)},
      {"width", frame.width},
      {"height", frame.height},
      {"spp", options.spp},
      {"light_samples", options.lightSamples},
      {"threads", options.threads},
      {"channels", shadowlab::referenceChannelsKey(channelSet)},
      {"lights", frame.meta["lights"]},
      {"projectors", frame.meta["projectors"]},
      {"triangles", scene.triangleCount()},
      {"rays", stats.primaryRays + stats.shadowRays},
      {"primary_rays", stats.primaryRays},
      {"shadow_rays", stats.shadowRays},
      {"trace_seconds", stats.traceSeconds},
      {"mrays_per_s", stats.mraysPerS()},
      {"build_seconds", stats.buildSeconds},
      {"load_seconds", seconds(start, loaded)},
      {"render_seconds", seconds(loaded, traced)},
      {"write_seconds", seconds(traced, written)},
      {"command_wall_seconds", seconds(start, written)},
      {"outputs", {"reference.exr", "reference.png", "reference.json"}},
  };
  shadowlab::writeJsonAtomic(jsonPath, report);
  out.keep();
  if (!created.empty()) shadowlab::unregisterInterruptPath(created);
  std::printf("reference: %s %dx%d spp %d: %.3f Mrays in %.3f s (%.1f Mrays/s), build %.3f s, total %.3f s -> %s\n",
              scene.name.c_str(), frame.width, frame.height, options.spp,
              double(stats.primaryRays + stats.shadowRays) * 1e-6, stats.traceSeconds, stats.mraysPerS(),
              stats.buildSeconds, seconds(start, Clock::now()), options.outDir.c_str());
  return 0;
}

shadowlab::app::Registrar reg{
    "reference", [](CLI::App& app) {
      auto* sub = app.add_subcommand("reference", "Trace the Embree ground truth of a scene");
      auto options = std::make_shared<Options>();
      sub->add_option("scene", options->scene, "bundled scene name (see `shadowlab scenes`) or path to a scene .json")
          ->required();
      sub->add_option("-o,--out", options->outDir, "output folder: reference.exr, reference.png, reference.json")
          ->required();
      shadowlab::app::addMaxMemoryOption(sub, &options->maxMemoryGiB);
      sub->add_option("--set", options->sets, "scene:/json/pointer=value: override one scene value (repeatable)")
          ->allow_extra_args(false);
      sub->add_option("--spp", options->spp, "stratified samples per pixel, 1..1024 (fractional visibility)")
          ->check(shadowlab::app::integerRange(shadowlab::kMinSpp, shadowlab::kMaxSpp, "reference samples per pixel"))
          ->capture_default_str();
      sub->add_option("--light-samples", options->lightSamples,
                      "samples of a sized light per pixel sample, 1..4096 (soft shadows; hard lights take none)")
          ->check(shadowlab::app::integerRange(shadowlab::kMinLightSamples, shadowlab::kMaxLightSamples,
                                               "samples of a sized light per pixel sample"))
          ->capture_default_str();
      sub->add_option("--threads", options->threads, "worker threads, 0 = all; results are identical for any value")
          ->capture_default_str();
      sub->add_flag("--all-channels", options->allChannels,
                    "reference.exr with every channel (adds prim_id, P, N, proj.*.u/v to the Compare set that "
                    "compare and the reference cache read)");
      return std::function<int()>([options] { return run(*options); });
    }};

}  // namespace
}  // namespace cmd_reference
