// `shadowlab stability SCENE [--method M.json] [--set key=value ...] --path dolly|orbit --frames N
//  [--distance D | --angle-deg A] -o DIR`: shimmer measured exactly. The evaluation camera (the
// scene's) stays fixed while the camera the light's fit follows moves along the path, so every
// pixel shows the same surface in every frame and one reference (cached) serves all frames.
// Writes DIR/stability.json (compare/METRICS.md, "Temporal stability"). Every input is validated
// before anything is traced, rendered or written.
#include <cmath>
#include <cstdio>
#include <memory>

#include "command.h"
#include "shadowlab/compare/pipeline.h"
#include "shadowlab/compare/stability.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace {

using namespace shadowlab;

constexpr int kMaxFrames = 1024;  // a path longer than this is a mistake, not a measurement

struct Options {
  std::string scene;
  std::string methodFile;
  std::vector<std::string> sets;
  std::string light;
  std::string path;
  int frames = 0;
  double distanceWorld = 1.0;  // dolly: total travel along the view direction, world units
  double angleDeg = 10.0;      // orbit: total rotation about look_at, degrees
  std::string outDir;
  std::string cacheDir;
  std::string device;
  CLI::Option* distanceOpt = nullptr;
  CLI::Option* angleOpt = nullptr;
};

const char* kWhere = "shadowlab stability";

int run(const Options& o) {
  // ---- inputs: every error surfaces before anything is traced, rendered or written ------------
  auto bad = [](const std::string& opt, const std::string& what) {
    return InputError(std::string(kWhere) + ": " + opt + ": error: " + what);
  };
  if (o.outDir.empty()) throw bad("-o", "the output folder is empty; expected a folder");
  if (o.path != "dolly" && o.path != "orbit")
    throw bad("--path", "got \"" + o.path + "\"; expected dolly or orbit");
  if (o.frames < 2 || o.frames > kMaxFrames)
    throw bad("--frames", "got " + std::to_string(o.frames) + "; expected 2.." + std::to_string(kMaxFrames));
  const bool dolly = o.path == "dolly";
  if (dolly && o.angleOpt->count() > 0) throw bad("--angle-deg", "given with --path dolly; expected --distance");
  if (!dolly && o.distanceOpt->count() > 0) throw bad("--distance", "given with --path orbit; expected --angle-deg");
  if (!std::isfinite(o.distanceWorld))
    throw bad("--distance", "got " + std::to_string(o.distanceWorld) + "; expected a finite distance (world units)");
  if (!(std::isfinite(o.angleDeg) && std::abs(o.angleDeg) <= 360.0))
    throw bad("--angle-deg", "got " + std::to_string(o.angleDeg) + "; expected a finite angle in -360..360 degrees");
  Method method;
  if (!o.methodFile.empty()) method = loadMethodFile(o.methodFile);
  for (const auto& s : o.sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--set " + s + ": error: got \"" + s + "\"; expected key=value (e.g. cascades.stabilize=true)");
    applyMethodSetting(method, s.substr(0, eq), s.substr(eq + 1), "--set " + s);
  }
  validateMethod(method, o.methodFile.empty() ? "--set" : o.methodFile);
  const Scene scene = loadScene(resolveScenePath(o.scene));
  if (scene.lights.empty())
    throw InputError(formatError(scene.path, "/lights", "the scene has no light; expected at least one to compare"));
  if (!o.light.empty() && !scene.findLight(o.light))
    throw bad("--light", "scene " + scene.path + " has no light \"" + o.light + "\"");
  const std::string light = o.light.empty() ? scene.lights.front().name : o.light;
  // The path generators validate the camera (a dolly needs a view direction, an orbit an up).
  const std::vector<Camera> path = dolly ? dollyPath(scene.camera, float(o.distanceWorld), o.frames)
                                         : orbitPath(scene.camera, float(o.angleDeg), o.frames);

  // ---- work ------------------------------------------------------------------------------------
  RasterDeviceOptions deviceOptions;
  deviceOptions.device = o.device;
  Rasterizer rasterizer(deviceOptions);
  ReferenceCache cache(o.cacheDir);
  bool traced = false;
  const Frame reference = cache.get(scene, ReferenceOptions{}, &traced);
  std::vector<Frame> rasters;
  for (const Camera& fit : path) rasters.push_back(rasterizer.render(scene, method, light, nullptr, &fit));
  CompareOptions compareOptions;
  compareOptions.light = light;
  const StabilityMetrics s = measureStability(reference, rasters, compareOptions);

  nlohmann::json cameras = nlohmann::json::array();
  for (const Camera& c : path)
    cameras.push_back({{"position", {c.position.x, c.position.y, c.position.z}},
                       {"look_at", {c.lookAt.x, c.lookAt.y, c.lookAt.z}}});
  nlohmann::json pathJson = {{"kind", o.path}, {"frames", o.frames}, {"fit_cameras", cameras}};
  if (dolly) pathJson["distance_world"] = o.distanceWorld;
  else pathJson["angle_deg"] = o.angleDeg;
  nlohmann::json report = s.toJson();
  report["scene"] = scene.name;
  report["scene_hash"] = scene.hash;
  report["camera_hash"] = scene.camera.hash();
  report["light"] = light;
  report["method"] = methodToJson(method);
  report["path"] = pathJson;
  report["device"] = rasterizer.deviceName();
  makeDirs(o.outDir);
  writeJsonAtomic(o.outDir + "/stability.json", report);
  std::printf("stability: %s %s %d frames, reference %s: shimmer_rate %.6g, error_rate mean %.5f max %.5f std %.5f"
              " -> %s/stability.json\n",
              scene.name.c_str(), o.path.c_str(), o.frames, traced ? "traced" : "cached", s.shimmerRate,
              s.errorRateMean, s.errorRateMax, s.errorRateStd, o.outDir.c_str());
  return 0;
}

app::Registrar reg{"stability", [](CLI::App& app) {
  auto opts = std::make_shared<Options>();
  auto* sub = app.add_subcommand("stability", "Shimmer: a fixed view while the light's fit follows a moving camera");
  sub->add_option("SCENE", opts->scene, "Bundled scene name or path to a scene file")->required();
  sub->add_option("--method", opts->methodFile, "Method file (JSON, see raster/METHODS.md)");
  sub->add_option("--set", opts->sets, "Method setting key=value, repeatable (e.g. --set fit=cascades)");
  sub->add_option("--light", opts->light, "Light to render and compare (default: the scene's first)");
  sub->add_option("--path", opts->path, "Fit camera path: dolly or orbit")->required();
  sub->add_option("--frames", opts->frames, "Frames on the path, 2..1024")->required();
  opts->distanceOpt = sub->add_option("--distance", opts->distanceWorld,
                                      "dolly: total travel along the view direction, world units")
                          ->capture_default_str();
  opts->angleOpt = sub->add_option("--angle-deg", opts->angleDeg, "orbit: total rotation about look_at, degrees")
                       ->capture_default_str();
  sub->add_option("-o,--out", opts->outDir, "Output folder")->required();
  sub->add_option("--cache", opts->cacheDir, "Reference cache folder (default: $SHADOWLAB_CACHE, else .shadowlab-cache)");
  sub->add_option("--device", opts->device, "Vulkan device name substring (default: lavapipe)");
  return std::function<int()>([opts] { return run(*opts); });
}};

}  // namespace
