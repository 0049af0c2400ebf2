// `shadowlab raster SCENE [--method M.json] [--set key=value ...] [--light NAME] [--device NAME] -o DIR`:
// renders the scene with the Vulkan shadow-mapping rasterizer and writes DIR/raster.exr (the
// channels of scenes/frame.h), DIR/raster.png (a readable picture) and DIR/raster.json (resolved
// method, GPU pass times, device). Everything is validated and rendered before anything is written.
#include <memory>
#include <string>
#include <vector>

#include "command.h"
#include "job_limits.h"
#include "shadowlab/compare/set_arguments.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/method.h"

namespace cmd_raster {
namespace {

struct Options {
  std::string scene;
  std::string methodFile;
  std::vector<std::string> settings;
  std::string light;
  std::string device;
  std::string outDir;
  bool validation = false;
  double maxMemoryGiB = 0;
  double gpuTimeoutS = 0;
};

int run(const Options& o) {
  using namespace shadowlab;
  // The same --set as run, sweep and stability: method keys and scene:/pointer values.
  const SetArguments set = applySetArguments(o.methodFile, o.settings);
  const Method& method = set.method;
  if (!method.renderer.empty())
    throw InputError("--set renderer=" + method.renderer +
                     ": error: raster draws with the built-in rasterizer; expected `shadowlab run` or `sweep` for an "
                     "outside renderer (adapters/README.md)");
  const Scene scene = loadScene(resolveScenePath(o.scene), set.sceneOverrides);
  checkGpuTimeout(o.gpuTimeoutS, "--gpu-timeout-s");
  precompileTechnique(method);  // a technique that does not compile: exit 2 before any output
  app::checkMemory("raster", app::rasterJobMemory(scene, method), o.maxMemoryGiB);
  OutputFolder out(o.outDir);  // an unusable -o fails here, before the device starts

  RasterDeviceOptions deviceOptions;
  deviceOptions.device = o.device;
  deviceOptions.validation = o.validation;
  deviceOptions.gpuTimeoutS = o.gpuTimeoutS;
  Rasterizer rasterizer(deviceOptions);
  app::checkDeviceMemory("raster", rasterizer, scene, method, o.light);
  RasterTimings t;
  Frame frame = rasterizer.render(scene, method, o.light, &t);
  if (o.validation && rasterizer.validationMessages() > 0)
    throw DriverError("vulkan validation reported " + std::to_string(rasterizer.validationMessages()) +
                      " message(s) (printed above)");

  writeFrameExr(frame, o.outDir + "/raster.exr");
  writeRgbPng(o.outDir + "/raster.png", frame.width, frame.height, rasterPicture(scene, frame));
  nlohmann::json report = {{"scene", scene.name},
                           {"scene_path", scene.path},
                           {"scene_hash", scene.hash},
                           {"camera_hash", frame.meta["camera_hash"]},
                           {"width", frame.width},
                           {"height", frame.height},
                           {"light", frame.meta["light"]},
                           {"method", methodToJson(method)},
                           {"device", rasterizer.deviceName()},
                           {timing::kShadowGpuMs, t.shadowGpuMs},
                           {timing::kCameraGpuMs, t.cameraGpuMs},
                           {timing::kVisibilityGpuMs, t.visibilityGpuMs},
                           {timing::kLookupGpuMs, t.lookupGpuMs},
                           {timing::kMethodGpuMs, t.methodGpuMs()},
                           {timing::kMomentsGpuMs, t.momentsGpuMs},
                           {timing::kEvidenceGpuMs, t.evidenceGpuMs},
                           {timing::kReadbackMs, t.readbackMs},
                           {timing::kRenderWallMs, t.renderWallMs}};
  if (t.sdsmSampled) {
    report[timing::kSdsmGpuMs] = t.sdsmGpuMs;
    report[timing::kSdsmReduceMs] = t.sdsmReduceMs;
  }
  writeJsonAtomic(o.outDir + "/raster.json", report);
  out.keep();
  std::printf("raster: %s %dx%d light=%s device=%s shadow %.2f ms, camera %.2f ms, readback %.2f ms -> %s\n",
              scene.name.c_str(), frame.width, frame.height, frame.meta["light"].get<std::string>().c_str(),
              rasterizer.deviceName().c_str(), t.shadowGpuMs, t.cameraGpuMs, t.readbackMs, o.outDir.c_str());
  return 0;
}

shadowlab::app::Registrar reg{
    "raster", [](CLI::App& app) {
      auto* sub = app.add_subcommand("raster", "Render a scene with the Vulkan shadow-mapping rasterizer");
      auto opts = std::make_shared<Options>();
      sub->add_option("scene", opts->scene, "Scene name (bundled) or path to a scene .json")->required();
      sub->add_option("--method", opts->methodFile, "Method file (JSON, keys in raster/METHODS.md)");
      sub->add_option("--set", opts->settings,
                      "key=value: a method key (raster/METHODS.md) or scene:/json/pointer=value (repeatable)")
          ->allow_extra_args(false);
      sub->add_option("--light", opts->light, "Light to render (default: the scene's first)");
      sub->add_option("--device", opts->device, "Vulkan device name substring (default: lavapipe/llvmpipe)");
      sub->add_flag("--validation", opts->validation, "Enable the Khronos validation layer; fail on any message");
      sub->add_option("-o,--out", opts->outDir, "Output folder")->required();
      shadowlab::app::addMaxMemoryOption(sub, &opts->maxMemoryGiB);
      shadowlab::app::addGpuTimeoutOption(sub, &opts->gpuTimeoutS);
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
}  // namespace cmd_raster
