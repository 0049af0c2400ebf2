// `shadowlab compare REF_DIR RASTER_DIR -o DIR`: classifies every wrong pixel of a raster frame
// against a reference frame and writes metrics.json, errors.png and triptych.png.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "command.h"
#include "shadowlab/compare/config_name.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/frame_check.h"
#include "shadowlab/compare/results.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"

namespace {

namespace fs = std::filesystem;
using namespace shadowlab;

struct Options {
  std::string referenceDir;
  std::string rasterDir;
  std::string outDir;
  std::string light;
  float boundaryTexels = 2.0f;
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

int run(const Options& o) {
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
  if (metrics.nothingCompared()) {
    // The outputs are written (errors.png shows what each renderer saw), but a comparison of no
    // pixel is no result: exit 2, so that a script stops here rather than at the gate.
    std::printf("compared 0 pixels (%llu geometry mismatch) in %.1f ms\n",
                (unsigned long long)metrics.count(PixelClass::GeometryMismatch), compareMs);
    std::printf("wrote %s/metrics.json, errors.png, triptych.png\n", o.outDir.c_str());
    std::fflush(stdout);
    std::fprintf(stderr, "%s and %s: error: %s\n", refPath.c_str(), rasPath.c_str(),
                 nothingComparedMessage(metrics).c_str());
    return 2;
  }
  std::printf("compared %llu pixels (%llu geometry mismatch): error_rate %.4f (%s) in %.1f ms\n",
              (unsigned long long)metrics.pixelsCompared,
              (unsigned long long)metrics.count(PixelClass::GeometryMismatch), metrics.errorRate,
              errorClassSummary(metrics, false).c_str(), compareMs);
  if (metrics.hasProjector) std::printf("%s\n", projectorSummary(metrics).c_str());
  if (metrics.mCapped > 0) std::printf("%s\n", footprintCapNote(metrics).c_str());
  std::printf("wrote %s/metrics.json, errors.png, triptych.png\n", o.outDir.c_str());
  return 0;
}

app::Registrar reg{
    "compare", [](CLI::App& app) {
      auto opts = std::make_shared<Options>();
      auto* sub =
          app.add_subcommand("compare", "Classify every wrong shadow pixel of a raster frame against the reference");
      sub->add_option("REF_DIR", opts->referenceDir, "Folder with reference.exr (or the .exr itself)")->required();
      sub->add_option("RASTER_DIR", opts->rasterDir, "Folder with raster.exr (or the .exr itself)")->required();
      sub->add_option("-o,--out", opts->outDir, "Output folder for metrics.json, errors.png, triptych.png")->required();
      sub->add_option("--light", opts->light, "Light to compare (default: the light the raster frame rendered)");
      sub->add_option("--boundary-texels", opts->boundaryTexels,
                      "Aliasing: disagreements within this many map texels of a reference shadow boundary")
          ->check(CLI::NonNegativeNumber)
          ->capture_default_str();
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
