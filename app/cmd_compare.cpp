// `shadowlab compare REF_DIR RASTER_DIR -o DIR`: classifies every wrong pixel of a raster frame
// against a reference frame and writes metrics.json, errors.png and triptych.png.
// `shadowlab compare SCENE FRAME -o DIR`: the same for a frame rendered by another program (a .png,
// or an .exr without shadowlab's metadata; scenes/FRAME-CONTRACT.md): the truth is traced for the
// scene, the frame's alignment checked, then it is compared as any other frame.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "command.h"
#include "shadowlab/compare/config_name.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/frame_check.h"
#include "shadowlab/compare/outside_alignment.h"
#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/compare/results.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/number_text.h"

namespace cmd_compare {
namespace {

namespace fs = std::filesystem;
using namespace shadowlab;

struct Options {
  std::string referenceDir;
  std::string rasterDir;
  std::string outDir;
  std::string light;
  float boundaryTexels = 2.0f;
  // Outside frames only (scenes/FRAME-CONTRACT.md).
  std::string channel;
  std::string coverage;
  std::string coverageChannel;
  std::optional<float> coverageFar;
  std::string renderer;
  bool outsideOnlyGiven() const {
    return !channel.empty() || !coverage.empty() || !coverageChannel.empty() || coverageFar || !renderer.empty();
  }
};

// A folder means the renderer's output folder; a path to a file is taken as it is.
std::string framePath(const std::string& given, const char* fileName) {
  std::error_code ec;
  if (fs::is_directory(given, ec)) return (fs::path(given) / fileName).string();
  return given;
}

std::string metaString(const Frame& f, const char* key, const std::string& fallback) {
  auto it = f.meta.find(key);
  return it != f.meta.end() && it->is_string() && !it->get<std::string>().empty() ? it->get<std::string>() : fallback;
}

// raster.json holds the timings `shadowlab raster` measured; copy every *_ms number. One written by
// an older build (total_ms, shadow_ms, ...) is refused with the new name: rerun `shadowlab raster`.
nlohmann::json rasterTimings(const std::string& rasterExr) {
  nlohmann::json timings = nlohmann::json::object();
  const std::string path = (fs::path(rasterExr).parent_path() / "raster.json").string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return timings;
  const nlohmann::json j = readJsonFile(path);
  auto collect = [&](const nlohmann::json& obj, const std::string& pointer) {
    if (!obj.is_object()) return;
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      const std::string& k = it.key();
      if (const char* renamed = timing::renamedTiming(k, timing::TimingSource::RasterJson))
        throw InputError(formatError(path, pointer + "/" + k, timing::renamedTimingMessage(k, renamed)));
      if (k.size() > 3 && k.compare(k.size() - 3, 3, "_ms") == 0 && it->is_number()) timings[k] = *it;
    }
  };
  collect(j, "");
  if (j.is_object() && j.contains("timings")) collect(j["timings"], "/timings");
  return timings;
}

// What both kinds of comparison print and return once the outputs are written.
int report(const Metrics& metrics, double compareMs, const std::string& outDir, const std::string& refName,
           const std::string& frameName) {
  if (metrics.nothingCompared()) {
    std::printf("compared 0 pixels (%llu geometry mismatch) in %.1f ms\n",
                (unsigned long long)metrics.count(PixelClass::GeometryMismatch), compareMs);
    std::printf("wrote %s/metrics.json, errors.png, triptych.png\n", outDir.c_str());
    std::fflush(stdout);
    std::fprintf(stderr, "%s and %s: error: %s\n", refName.c_str(), frameName.c_str(),
                 nothingComparedMessage(metrics).c_str());
    return 2;
  }
  std::printf("compared %llu pixels (%llu geometry mismatch): error_rate %.4f (%s) in %.1f ms\n",
              (unsigned long long)metrics.pixelsCompared,
              (unsigned long long)metrics.count(PixelClass::GeometryMismatch), metrics.errorRate,
              errorClassSummary(metrics, false).c_str(), compareMs);
  if (metrics.hasProjector) std::printf("%s\n", projectorSummary(metrics).c_str());
  if (metrics.mCapped > 0) std::printf("%s\n", footprintCapNote(metrics).c_str());
  std::printf("wrote %s/metrics.json, errors.png, triptych.png\n", outDir.c_str());
  return 0;
}

int runOwn(const Options& o) {
  const std::string refPath = framePath(o.referenceDir, "reference.exr");
  const std::string rasPath = framePath(o.rasterDir, "raster.exr");
  std::error_code ec;
  for (const auto& [path, what] : {std::pair{refPath, "shadowlab reference"}, std::pair{rasPath, "shadowlab raster"}}) {
    if (!fs::is_regular_file(path, ec)) {
      throw InputError(formatError(path, "",
                                   std::string("no such file; expected the output of `") + what + "` (comparing " +
                                       refPath + " with " + rasPath + ")"));
    }
  }
  OutputFolder out(o.outDir);  // an unusable -o fails before the frames are read and compared
  const Frame reference = readFrameToCompare(refPath);
  const Frame raster = readFrameToCompare(rasPath);
  CompareOptions options;
  options.light = o.light;
  options.boundaryTexels = o.boundaryTexels;
  options.referenceName = refPath;
  options.rasterName = rasPath;
  Classification classification;
  const auto t0 = std::chrono::steady_clock::now();
  const Metrics metrics = compareFrames(reference, raster, options, &classification);
  const double compareMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  ResultRow row;
  row.scene = metaString(reference, "scene", metaString(raster, "scene", "unknown"));
  row.light = resolveCompareLight(reference, raster, options);
  auto method = raster.meta.find("method");
  if (method != raster.meta.end() && method->is_object()) row.method = *method;
  // The one name of a configuration (config_name.h), from the method the raster frame records (a
  // frame records no scene: values).
  row.config = configName(row.method, {});
  row.metrics = metrics.toJson();
  row.timings = rasterTimings(rasPath);
  row.timings["compare_ms"] = compareMs;

  // Everything is validated and computed: only now does the output folder appear.
  writeMetricsJson((fs::path(o.outDir) / "metrics.json").string(), row);
  writeErrorsPng((fs::path(o.outDir) / "errors.png").string(), classification, &reference);
  writeTriptychPng((fs::path(o.outDir) / "triptych.png").string(), reference, raster, classification);
  out.keep();
  // The outputs are written (errors.png shows what each renderer saw), but a comparison of no
  // pixel is no result: report() exits 2 then, so that a script stops here rather than at the gate.
  return report(metrics, compareMs, o.outDir, refPath, rasPath);
}

// A frame from another program: the truth is traced here (with the All channels, which the
// evidence of an outside frame is filled from), the frame is read, sized, checked for alignment
// and only then compared.
int runOutside(const Options& o) {
  const std::string& framePath = o.rasterDir;
  std::error_code ec;
  if (fs::is_directory(o.referenceDir, ec)) {
    throw InputError(formatError(o.referenceDir, "",
                                 "is a folder; a frame from another program (" + framePath +
                                     ") is compared against its scene: expected SCENE (a bundled name, a JSON, glTF "
                                     "or glb file), whose truth compare traces"));
  }
  const Scene scene = loadScene(resolveScenePath(o.referenceDir));
  if (!o.light.empty() && !scene.findLight(o.light)) {
    std::string names;
    for (const auto& l : scene.lights) names += (names.empty() ? "" : ", ") + l.name;
    throw InputError("--light " + o.light + ": error: scene " + scene.path + " has no light \"" + o.light +
                     "\"; expected one of: " + (names.empty() ? "(none)" : names));
  }
  if (scene.lights.empty())
    throw InputError(formatError(scene.path, "/lights",
                                 "the scene has no light; expected a light whose shadow the outside frame shows"));
  const std::string light = scene.lightOrDefault(o.light);
  if (o.coverageFar && !std::isfinite(*o.coverageFar))
    throw InputError("--coverage-far: error: got " + numberText(*o.coverageFar) + "; expected a finite depth");
  if (!o.coverageChannel.empty() && o.coverage.empty())
    throw InputError("--coverage-channel: error: given without --coverage; expected a coverage image to read it from");
  const DeclaredRenderer declared = o.renderer.empty() ? DeclaredRenderer{} : readDeclaredRenderer(o.renderer);
  // Sizes are refused from the header, before a pixel of a wrong-sized image is decoded.
  auto sized = [&](const std::string& file) {
    return [&scene, file](int width, int height) { checkOutsideSize(width, height, scene.camera, file); };
  };
  const ImagePlane vis = readImagePlane(framePath, o.channel, sized(framePath));
  std::optional<ImagePlane> coverage;
  if (!o.coverage.empty()) coverage = readImagePlane(o.coverage, o.coverageChannel, sized(o.coverage));
  OutputFolder out(o.outDir);  // an unusable -o fails before anything is traced

  ReferenceOptions traceOptions;
  traceOptions.channels = ReferenceChannels::All;
  const Frame truth = renderReference(scene, traceOptions);
  {
    const std::vector<float>& hit = truth.get("hit");
    if (std::none_of(hit.begin(), hit.end(), [](float h) { return h >= 0.5f; }))
      throw InputError(formatError(scene.path, "/camera", "the camera sees no surface; expected a view of the scene"));
  }
  CoverageRule rule;
  rule.far = o.coverageFar;
  Frame outside =
      makeOutsideFrame(truth, light, vis, framePath, coverage ? &*coverage : nullptr, o.coverage, rule, declared);
  const AlignmentCheck alignment =
      checkOutsideAlignment(scene, truth, outside, coverage.has_value(), light, framePath, traceOptions);

  CompareOptions options;
  options.light = light;
  options.boundaryTexels = o.boundaryTexels;
  options.referenceName = scene.path + " (traced)";
  options.rasterName = framePath;
  prepareOutsideComparison(truth, outside, declared, options);
  Classification classification;
  const auto t0 = std::chrono::steady_clock::now();
  const Metrics metrics = compareFrames(truth, outside, options, &classification);
  const double compareMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  ResultRow row;
  row.scene = scene.name;
  row.light = light;
  row.method = outsideMethodJson(declared, outside, alignment);
  row.config = outsideConfigName(declared);
  row.metrics = metrics.toJson();
  row.timings[timing::kCompareMs] = compareMs;
  // The renderer's own time, so that the gate can hold its cost beside its accuracy.
  if (declared.frameMs) row.timings[timing::kRendererFrameMs] = *declared.frameMs;

  writeMetricsJson((fs::path(o.outDir) / "metrics.json").string(), row);
  writeErrorsPng((fs::path(o.outDir) / "errors.png").string(), classification, &truth);
  writeTriptychPng((fs::path(o.outDir) / "triptych.png").string(), truth, outside, classification);
  out.keep();
  if (alignment.verdict == "cannot tell")
    std::printf("alignment: cannot tell (%llu edge pixels in the truth's pattern; %llu needed)\n",
                (unsigned long long)alignment.edgePixels, (unsigned long long)kMinEdgePixels);
  std::printf("outside frame: %s, %s channel %s, coverage %s, boundary band %g pixels\n",
              declared.name.empty() ? "(renderer not declared)" : declared.name.c_str(), vis.description.c_str(),
              vis.channel.c_str(), coverage ? "given" : "assumed (the truth's)", double(o.boundaryTexels));
  return report(metrics, compareMs, o.outDir, options.referenceName, framePath);
}

int run(const Options& o) {
  if (isOutsideFrameFile(o.rasterDir)) return runOutside(o);
  if (o.outsideOnlyGiven()) {
    throw InputError(o.rasterDir +
                     ": error: --channel, --coverage, --coverage-channel, --coverage-far and --renderer apply to a "
                     "frame from another program (a .png, or an .exr without shadowlab's metadata); expected such a "
                     "frame or none of these options");
  }
  return runOwn(o);
}

app::Registrar reg{
    "compare", [](CLI::App& app) {
      auto opts = std::make_shared<Options>();
      auto* sub =
          app.add_subcommand("compare", "Classify every wrong shadow pixel of a raster frame against the reference");
      sub->add_option("REF_DIR", opts->referenceDir,
                      "Folder with reference.exr (or the .exr itself); for a frame from another program: the scene "
                      "(bundled name, JSON, glTF/glb)")
          ->required();
      sub->add_option("RASTER_DIR", opts->rasterDir,
                      "Folder with raster.exr (or the .exr itself), or a frame from another program: a .png, or an "
                      ".exr without shadowlab's metadata (scenes/FRAME-CONTRACT.md)")
          ->required();
      sub->add_option("-o,--out", opts->outDir, "Output folder for metrics.json, errors.png, triptych.png")->required();
      sub->add_option("--light", opts->light,
                      "Light to compare (default: the light the raster frame rendered; an outside frame: the scene's "
                      "first light)");
      sub->add_option("--boundary-texels", opts->boundaryTexels,
                      "Aliasing: disagreements within this many map texels of a reference shadow boundary")
          ->check(CLI::NonNegativeNumber)
          ->capture_default_str();
      sub->add_option("--channel", opts->channel,
                      "Outside frame: its visibility channel (PNG: Y, R, G, B or A; EXR: a name; default: grey, "
                      "\"vis\" or the only channel)");
      sub->add_option("--coverage", opts->coverage,
                      "Outside frame: the renderer's coverage image (PNG/EXR; a mask, surface where > 0.5, or a depth "
                      "image with --coverage-far); without it the truth's hit is assumed");
      sub->add_option("--coverage-channel", opts->coverageChannel, "Outside frame: the coverage image's channel");
      sub->add_option("--coverage-far", opts->coverageFar,
                      "Outside frame: the coverage image is depth; no surface where it equals this value (1: cleared "
                      "to the far plane, 0: reversed-Z)");
      sub->add_option("--renderer", opts->renderer,
                      "Outside frame: what the renderer used (JSON: name, light_clip_from_world, map_size, biases, "
                      "filter, frame_ms, settings)");
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
}  // namespace cmd_compare
