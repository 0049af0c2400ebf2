// `shadowlab stability SCENE [--method M.json] [--set key=value ...]
//      (--path dolly|orbit|NAME [--frames N] [--distance D | --angle-deg A] | --light-path KEY=FROM:TO:FRAMES ...)
//      -o DIR`
// Temporal stability (compare/METRICS.md, "Temporal stability"):
// - a camera path (--path): the evaluation camera (the scene's) stays fixed while the camera the
//   light's fit follows moves along a generated path (dolly, orbit) or one the scene file declares
//   ("paths"); every pixel shows the same surface in every frame and one reference (cached) serves
//   all frames: shimmer measured exactly.
// - a light path (--light-path): the camera stays fixed and a directional light's elevation and/or
//   azimuth steps along the path; each frame is its own scene with its own reference (cached).
// Writes DIR/stability.json: the per-frame numbers and a result row (schema shadowlab.stability/1)
// that `shadowlab gate` checks (compare/GATE.md). Every input is validated before anything is
// traced, rendered or written.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>

#include <unistd.h>

#include "command.h"
#include "job_limits.h"
#include "shadowlab/compare/adapter_session.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/compare/stability.h"
#include "shadowlab/scenes/light_path.h"
#include "shadowlab/compare/set_arguments.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/adapter_manifest.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/number_text.h"

namespace cmd_stability {
namespace {

// A .gltf or .glb path (any case): a scene of its own, not a JSON document (scenes/FORMAT.md).
bool sceneIsGltf(const std::string& path) {
  std::string ext = path.substr(std::min(path.size(), path.find_last_of('.')));
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".gltf" || ext == ".glb";
}

using namespace shadowlab;

struct Options {
  std::string scene;
  std::string methodFile;
  std::vector<std::string> sets;
  std::string light;
  std::string path;
  int frames = 0;
  double distanceWorld = 1.0;  // dolly: total travel along the view direction, world units
  double angleDeg = 10.0;      // orbit: total rotation about look_at, degrees
  std::vector<std::string> lightPaths;
  std::string outDir;
  std::string cacheDir;
  double maxMemoryGiB = 0;
  std::string device;
  double gpuTimeoutS = 0;
  CLI::Option* distanceOpt = nullptr;
  CLI::Option* angleOpt = nullptr;
  CLI::Option* framesOpt = nullptr;
};

constexpr const char* kStabilitySchema = "shadowlab.stability/1";

std::string numberText(double v) { return canonicalValueText(nlohmann::json(v)); }

int run(const Options& o) {
  const auto t0 = std::chrono::steady_clock::now();
  // ---- inputs: every error surfaces before anything is traced, rendered or written ------------
  // The option is the place, as every command's option errors read ("--frames: error: got 1; ...").
  auto bad = [](const std::string& opt, const std::string& what) { return InputError(opt + ": error: " + what); };
  if (o.outDir.empty()) throw bad("-o", "the output folder is empty; expected a folder");
  const bool lightPath = !o.lightPaths.empty();
  if (lightPath == !o.path.empty())
    throw bad(lightPath ? "--light-path" : "--path",
              lightPath ? "given with --path; expected one of them (a moving light or a moving fit camera)"
                        : "neither --path nor --light-path given; expected one of them");
  const bool generated = o.path == "dolly" || o.path == "orbit";
  const bool dolly = o.path == "dolly";
  const bool framesGiven = o.framesOpt->count() > 0;
  if (framesGiven && (o.frames < 2 || o.frames > kMaxPathFrames))
    throw bad("--frames", "got " + std::to_string(o.frames) + "; expected 2.." + std::to_string(kMaxPathFrames));
  if (generated && !framesGiven)
    throw bad("--frames", "missing; expected the number of frames of the " + o.path + " path");
  if (lightPath && framesGiven)
    throw bad("--frames", "given with --light-path; expected the frames in KEY=FROM:TO:FRAMES");
  if (o.angleOpt->count() > 0 && o.path != "orbit")
    throw bad("--angle-deg", "given with " + (lightPath ? std::string("--light-path") : "--path " + o.path) +
                                 "; expected it only with --path orbit");
  if (o.distanceOpt->count() > 0 && o.path != "dolly")
    throw bad("--distance", "given with " + (lightPath ? std::string("--light-path") : "--path " + o.path) +
                                "; expected it only with --path dolly");
  if (!std::isfinite(o.distanceWorld))
    throw bad("--distance",
              "got " + shadowlab::numberText(o.distanceWorld) + "; expected a finite distance (world units)");
  if (!(std::isfinite(o.angleDeg) && std::abs(o.angleDeg) <= 360.0))
    throw bad("--angle-deg",
              "got " + shadowlab::numberText(o.angleDeg) + "; expected a finite angle in -360..360 degrees");
  std::vector<LightPathAxis> axes;
  for (const auto& text : o.lightPaths) axes.push_back(parseLightPath(text));

  // --set: method keys, or scene values as in sweeps (scene:/json/pointer=value).
  const SetArguments set = applySetArguments(o.methodFile, o.sets);
  const Method& method = set.method;
  // An outside renderer fits its map as it does (three.js: around the scene's bounds): a fit-camera
  // path moves what only the built-in rasterizer fits to. A light path is any renderer's.
  if (!method.renderer.empty() && !lightPath)
    throw InputError("--set renderer=" + method.renderer +
                     ": error: a fit-camera path (--path) moves the camera the built-in rasterizer fits its map to, "
                     "and an outside renderer fits its own; expected --light-path for an outside renderer "
                     "(adapters/README.md)");
  if (!method.renderer.empty()) checkAdapterMayRun(method, "shadowlab stability");
  const std::vector<SceneOverride>& sceneOverrides = set.sceneOverrides;

  const std::string scenePath = resolveScenePath(o.scene);
  const Scene scene = loadScene(scenePath, sceneOverrides);
  if (scene.lights.empty())
    throw InputError(formatError(scene.path, "/lights", "the scene has no light; expected at least one to compare"));
  if (!o.light.empty() && !scene.findLight(o.light))
    throw bad("--light", "scene " + scene.path + " has no light \"" + o.light + "\"");
  const std::string light = scene.lightOrDefault(o.light);

  // The path: fit cameras (camera path) or per-frame scene overrides (light path).
  std::vector<Camera> fitCameras;
  nlohmann::json pathJson;
  std::string pathConfig;
  // A light path moves a JSON light (elevation_deg, azimuth_deg): a glTF file's lights have neither.
  if (lightPath && sceneIsGltf(scene.path))
    throw bad("--light-path",
              "scene " + scene.path +
                  " is a glTF file, whose lights have no elevation_deg or azimuth_deg to move; expected "
                  "a JSON scene (a JSON scene may hold the glTF: scenes/FORMAT.md, \"glTF files\")");
  const nlohmann::json sceneDocument = lightPath ? readJsonFile(scene.path) : nlohmann::json();
  int frames = 0;
  if (lightPath) {
    frames = axes.front().frames;
    // Checks the light and the axes; the user's own scene: values must not move the same light.
    (void)lightPathOverrides(sceneDocument, scene, light, axes, 0);
    std::string axisText;
    nlohmann::json axisJson = nlohmann::json::array();
    for (const auto& a : axes) {
      axisText += (axisText.empty() ? "" : "+") + a.key + ":" + numberText(a.from) + ":" + numberText(a.to);
      axisJson.push_back({{"key", a.key}, {"from", a.from}, {"to", a.to}});
    }
    pathJson = {{"kind", "light"}, {"frames", frames}, {"light_path", axisJson}};
    pathConfig = "light_path=" + axisText + ",frames=" + std::to_string(frames);
  } else if (generated) {
    // The path generators validate the camera (a dolly needs a view direction, an orbit an up).
    fitCameras = dolly ? dollyPath(scene.camera, float(o.distanceWorld), o.frames)
                       : orbitPath(scene.camera, float(o.angleDeg), o.frames);
    pathJson = {{"kind", o.path}, {"frames", o.frames}};
    if (dolly) pathJson["distance_world"] = o.distanceWorld;
    else pathJson["angle_deg"] = o.angleDeg;
    pathConfig = "path=" + o.path + "," +
                 (dolly ? "distance=" + numberText(o.distanceWorld) : "angle_deg=" + numberText(o.angleDeg)) +
                 ",frames=" + std::to_string(o.frames);
  } else {
    const CameraPath* declared = scene.findPath(o.path);
    if (!declared) {
      std::string names;
      for (const auto& p : scene.paths) names += " " + p.name;
      throw bad("--path", "got \"" + o.path + "\"; expected dolly, orbit or a path of " + scene.path +
                              (names.empty() ? std::string(" (it declares none)") : ":" + names));
    }
    fitCameras = expandCameraPath(scene.camera, *declared, framesGiven ? o.frames : 0);
    pathJson = {{"kind", toString(declared->kind)}, {"name", declared->name}, {"frames", int(fitCameras.size())}};
    if (declared->kind == CameraPathKind::Dolly) pathJson["distance_world"] = jsonFloat(declared->distanceWorld);
    if (declared->kind == CameraPathKind::Orbit) pathJson["angle_deg"] = jsonFloat(declared->angleDeg);
    pathConfig = "path=" + declared->name + ",frames=" + std::to_string(fitCameras.size());
  }
  if (!lightPath) frames = int(fitCameras.size());
  // Light path: every frame's scene is the same file under other angles; the ends are loaded here
  // so that a value the loader refuses surfaces before any work (the frames between lie between).
  auto frameScene = [&](int k) {
    std::vector<SceneOverride> overrides = sceneOverrides;
    for (auto& l : lightPathOverrides(sceneDocument, scene, light, axes, k)) {
      for (const auto& u : sceneOverrides)
        if (u.pointer == l.pointer || l.pointer.rfind(u.pointer + "/", 0) == 0 ||
            u.pointer.rfind(l.pointer + "/", 0) == 0)
          throw bad("--set scene:" + u.pointer,
                    "the light path moves " + l.pointer + "; expected it set by one of them");
      overrides.push_back(l);
    }
    return loadScene(scenePath, overrides);
  };
  if (lightPath) {
    (void)frameScene(0);
    (void)frameScene(frames - 1);
  }

  const std::string config = set.config + " @ " + pathConfig;

  checkGpuTimeout(o.gpuTimeoutS, "--gpu-timeout-s");
  app::checkMemory("stability", app::compareJobMemory(scene, set.method), o.maxMemoryGiB);
  // Every output location, before any work: a bad -o or --cache must not cost a trace first.
  OutputFolder out(o.outDir);
  ReferenceCache cache(o.cacheDir);
  OutputFolder cacheFolder(cache.dir(), "--cache");
  cacheFolder.keep();  // a cache outlives the command

  // ---- work ------------------------------------------------------------------------------------
  RasterDeviceOptions deviceOptions;
  deviceOptions.device = o.device;
  deviceOptions.gpuTimeoutS = o.gpuTimeoutS;
  // The built-in rasterizer, or an outside renderer's adapter (one batch a frame: each frame is a
  // scene of its own), its work under the cache folder.
  const bool outside = !method.renderer.empty();
  std::unique_ptr<Rasterizer> ownRasterizer;
  if (!outside) ownRasterizer = std::make_unique<Rasterizer>(deviceOptions);
  std::unique_ptr<AdapterSession> adapter;
  const std::string adapterWork = cache.dir() + "/adapter-work/stability-" + std::to_string(long(::getpid()));
  if (outside) adapter = std::make_unique<AdapterSession>(adapterWork, cache.dir());
  if (ownRasterizer) app::checkDeviceMemory("stability", *ownRasterizer, scene, method, light);  // before any reference
  CompareOptions compareOptions;
  compareOptions.light = light;
  StabilityMetrics s;
  int traced = 0;
  nlohmann::json perFrame = nlohmann::json::array();
  if (lightPath) {
    // One frame at a time (its scene, reference, raster): memory stays that of one frame.
    std::vector<double> errors;
    for (int k = 0; k < frames; ++k) {
      const Scene frameSceneK = frameScene(k);
      bool t = false;
      const Frame reference = cache.get(frameSceneK, ReferenceOptions{}, &t);
      traced += t;
      Metrics m;
      if (adapter) {
        const std::vector<AdapterOutcome> got = adapter->render(frameSceneK, light, {{set.config, method}}, reference);
        got.front().throwIfFailed();  // exit 3, its log named
        m = got.front().metrics;
      } else {
        m = compareFrames(reference, ownRasterizer->render(frameSceneK, method, light), compareOptions);
      }
      errors.push_back(m.errorRate);
      nlohmann::json values = nlohmann::json::object();
      for (const auto& a : axes) values[a.key] = a.value(k);
      nlohmann::json frameRow = {{"light", values}, {"error_rate", m.errorRate}, {"pixels_compared", m.pixelsCompared}};
      for (const PixelClassInfo& c : kPixelClasses)
        if (c.error && c.rateMetric) frameRow[c.rateMetric] = m.rate(c.cls);
      perFrame.push_back(frameRow);
    }
    setErrorStatistics(s, errors);
  } else {
    bool t = false;
    const Frame reference = cache.get(scene, ReferenceOptions{}, &t);
    traced += t;
    // One frame at a time against the previous one: memory stays that of two frames.
    StabilityStream stream(reference, compareOptions);
    Rasterizer& rasterizer = *ownRasterizer;
    for (const Camera& fit : fitCameras)
      rasterizer.recycle(stream.add(rasterizer.render(scene, method, light, nullptr, &fit)));
    s = stream.result();
    nlohmann::json cameras = nlohmann::json::array();
    for (const Camera& c : fitCameras)
      cameras.push_back({{"position", {c.position.x, c.position.y, c.position.z}},
                         {"look_at", {c.lookAt.x, c.lookAt.y, c.lookAt.z}},
                         {"up", {c.up.x, c.up.y, c.up.z}}});
    pathJson["fit_cameras"] = cameras;
  }
  const double commandWallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  // stability.json: the per-frame numbers at the top level, and a result row (scene, config, light,
  // method, metrics, timings) the gate reads like a metrics.json.
  nlohmann::json report = s.toJson();
  report["schema"] = kStabilitySchema;
  report["scene"] = scene.name;
  report["config"] = config;
  report["light"] = light;
  report["method"] = methodToJson(method);
  report["metrics"] = s.gateMetrics();
  report["timings"] = {{timing::kCommandWallMs, commandWallMs}};  // writing stability.json excluded
  report["scene_hash"] = scene.hash;
  report["camera_hash"] = scene.camera.hash();
  report["path"] = pathJson;
  if (lightPath) report["per_frame"] = perFrame;
  report["references_traced"] = traced;
  report["device"] = ownRasterizer ? ownRasterizer->deviceName() : "renderer " + rendererManifest(method)->name;
  writeJsonAtomic(o.outDir + "/stability.json", report);
  out.keep();
  if (adapter) {
    std::error_code ec;
    std::filesystem::remove_all(adapterWork, ec);
  }
  std::printf("stability: %s %s, %d frames, %d reference(s) traced: ", scene.name.c_str(), pathConfig.c_str(), frames,
              traced);
  if (s.hasShimmer()) std::printf("shimmer_rate %.6g, ", s.shimmerRate);
  std::printf("error_rate mean %.5f max %.5f std %.5f, error_jump_max %.5f -> %s/stability.json\n", s.errorRateMean,
              s.errorRateMax, s.errorRateStd, s.errorJumpMax, o.outDir.c_str());
  return 0;
}

app::Registrar reg{
    "stability", [](CLI::App& app) {
      auto opts = std::make_shared<Options>();
      auto* sub = app.add_subcommand(
          "stability", "Temporal stability: shimmer along a fit-camera path, or error along a light path");
      sub->add_option("SCENE", opts->scene, "Bundled scene name or path to a scene file")->required();
      sub->add_option("--method", opts->methodFile, "Method file (JSON, see raster/METHODS.md)");
      sub->add_option("--set", opts->sets,
                      "key=value, repeatable: a method key (e.g. fit=cascades) or scene:/json/pointer (e.g. "
                      "scene:/camera/width=320)")
          ->allow_extra_args(false);  // one value per --set: SCENE may follow it
      sub->add_option("--light", opts->light, "Light to render, compare and move (default: the scene's first)");
      sub->add_option("--path", opts->path, "Fit camera path: dolly, orbit, or a path the scene file declares");
      opts->framesOpt = sub->add_option(
          "--frames", opts->frames, "Frames on the path, 2..1024 (dolly, orbit; replaces a scene path's own count)");
      opts->distanceOpt = sub->add_option("--distance", opts->distanceWorld,
                                          "dolly: total travel along the view direction, world units")
                              ->capture_default_str();
      opts->angleOpt = sub->add_option("--angle-deg", opts->angleDeg, "orbit: total rotation about look_at, degrees")
                           ->capture_default_str();
      sub->add_option("--light-path", opts->lightPaths,
                      "Moving light, repeatable: KEY=FROM:TO:FRAMES with KEY elevation_deg or azimuth_deg "
                      "(e.g. elevation_deg=60:10:11); the camera stays fixed")
          ->allow_extra_args(false);  // one value per --light-path: SCENE may follow it
      sub->add_option("-o,--out", opts->outDir, "Output folder")->required();
      app::addMaxMemoryOption(sub, &opts->maxMemoryGiB);
      sub->add_option("--cache", opts->cacheDir,
                      "Reference cache folder (default: $SHADOWLAB_CACHE, else .shadowlab-cache)");
      sub->add_option("--device", opts->device, "Vulkan device name substring (default: lavapipe)");
      app::addGpuTimeoutOption(sub, &opts->gpuTimeoutS);
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
}  // namespace cmd_stability
