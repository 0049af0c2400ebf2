// `shadowlab tune SCENES... (--max-error E [--max metric=v]... | --budget-ms B) [--keys k1,k2,...]
// [--range key=lo:hi]... [--fixed key=value]... -o DIR`: the least expensive method that meets the
// target on every scene (or the most accurate within the budget), by a search rather than a grid;
// resumable; writes tuned.json, tune.json, tune.html, results.json/csv, report.html (compare/TUNE.md).
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "command.h"
#include "shadowlab/compare/tune.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace cmd_tune {
namespace {

namespace fs = std::filesystem;
using namespace shadowlab;

struct Options : app::StudyOptions {
  std::vector<std::string> scenes;
  std::string maxError, budgetMs;  // text: checked here, so "abc" is a GCC-style InputError
  std::vector<std::string> maxRates;
  std::string keys;
  std::vector<std::string> ranges;
  std::vector<std::string> fixed;
  bool noReport = false;
  bool checkGrid = false;
};

std::atomic<bool> gStop{false};
extern "C" void onTuneInterrupt(int) { gStop.store(true); }

int run(const Options& o) {
  // ---- inputs: every error surfaces here, before the output folder exists --------------------
  TuneSpec spec;
  spec.scenes = o.scenes;
  if (!o.maxError.empty()) spec.maxError = parseTuneNumber("--max-error", o.maxError);
  if (!o.budgetMs.empty()) spec.budgetMs = parseTuneNumber("--budget-ms", o.budgetMs);
  for (const auto& m : o.maxRates) spec.maxRates.push_back(parseTuneMax(m));
  // --max alone is a target on those metrics; error_rate is then free: --max-error 1, a rate every
  // row meets. (With --budget-ms, planTune refuses --max: a budget has no target.)
  if (!o.maxRates.empty() && o.maxError.empty() && o.budgetMs.empty()) spec.maxError = 1.0;
  if (!o.keys.empty()) {
    size_t start = 0;
    while (true) {
      size_t comma = o.keys.find(',', start);
      spec.keys.push_back(o.keys.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  spec.ranges = o.ranges;
  for (const auto& f : o.fixed) {
    if (f.find('=') == std::string::npos)
      throw InputError("--fixed " + f + ": error: no '=' found; expected key=value");
    SweepSetting s = parseSetArgument(f);
    s.origin = "--fixed " + f;
    spec.fixed.push_back(s);
  }
  spec.methodFile = o.methodFile;
  spec.light = o.light;
  spec.spp = o.spp.value_or(1);
  checkSpp(spec.spp, "--spp");
  spec.lightSamples = o.lightSamples.value_or(kDefaultLightSamples);
  checkLightSamples(spec.lightSamples, "--light-samples");
  if (o.gpuTimeoutS) checkGpuTimeout(*o.gpuTimeoutS, "--gpu-timeout-s");
  TunePlan plan = planTune(spec);
  OutputFolder out(o.outDir);
  const std::string cacheDir = o.cacheDir.empty() ? defaultSweepCacheDir(o.outDir) : o.cacheDir;
  OutputFolder cacheFolder(cacheDir, o.cacheDir.empty() ? "-o (its reference cache)" : "--cache");
  cacheFolder.keep();

  // ---- work ------------------------------------------------------------------------------------
  // Its triptychs show the chosen configuration, not a scene's best or worst row: nothing kept.
  auto runner = makePipelineRunner(cacheDir, spec.spp, o.device, plan.sweep.sceneNames.size(), false, false,
                                   spec.lightSamples, o.gpuTimeoutS.value_or(0));
  TuneOptions options;
  options.outDir = o.outDir;
  options.progress = stderr;
  options.stop = &gStop;
  options.writeReport = !o.noReport;
  options.checkGrid = o.checkGrid;
  if (o.timingRepetitions) options.timingRepetitions = *o.timingRepetitions;
  const char* home = std::getenv("SHADOWLAB_HOME");
  options.reportScript = defaultReportScript(home && *home ? home : SHADOWLAB_SOURCE_DIR);
  std::fprintf(stderr, "tune: %zu scene(s), keys", plan.sweep.sceneNames.size());
  for (const auto& k : plan.keys) std::fprintf(stderr, " %s (%zu values)", k.key.c_str(), k.values.size());
  std::fprintf(stderr, "; the dense grid would be %zu rows; into %s\n",
               plan.gridConfigurations * plan.sweep.sceneNames.size(), o.outDir.c_str());
  app::installStopHandlers(onTuneInterrupt);
  const TuneResult result = runTune(plan, *runner, options);
  out.keep();
  if (result.interrupted) {
    std::fprintf(stderr,
                 "tune: interrupted: every evaluated row is saved in %s/rows.jsonl; run the same command again to "
                 "continue\n",
                 o.outDir.c_str());
    return 130;
  }
  for (const auto& n : result.notes) std::fprintf(stderr, "tune: note: %s\n", n.c_str());
  std::printf("%s\n", result.verdict.c_str());
  std::printf("tune: wrote %s, %s and %s\n", result.tunedJson.empty() ? "(no tuned.json)" : result.tunedJson.c_str(),
              result.tuneJson.c_str(), result.tuneHtml.c_str());
  if (!result.reportHtml.empty()) std::printf("report: %s\n", fs::absolute(result.reportHtml).c_str());
  return result.robust.met ? 0 : 1;
}

app::Registrar reg{
    "tune", [](CLI::App& app) {
      auto opts = std::make_shared<Options>();
      auto* sub = app.add_subcommand(
          "tune", "The cheapest method meeting an accuracy target on every scene, by search (compare/TUNE.md)");
      sub->add_option("SCENES", opts->scenes, "Bundled scene names or scene files (default: every bundled scene)");
      sub->add_option("--max-error", opts->maxError,
                      "Target: error_rate <= E on every scene; the least estimated cost wins (exit 1 when no "
                      "configuration meets it)");
      sub->add_option("--max", opts->maxRates,
                      "Target: METRIC <= V on every scene, e.g. acne_rate=0.0005 or penumbra_mae=0.02 (repeatable; "
                      "alone, or beside --max-error; compare/TUNE.md)")
          ->allow_extra_args(false);
      sub->add_option("--budget-ms", opts->budgetMs,
                      "Instead: the lowest worst-case error_rate whose ESTIMATED cost (the cost model of "
                      "compare/TUNE.md, not a measured time) is <= B ms");
      sub->add_option("--keys", opts->keys,
                      std::string("Keys to search, comma-separated (default ") + defaultTuneKeys() +
                          "); bias.slope, bias.compare, bias.normal, bias.constant, map.size, filter, filter.size, "
                          "filter.taps, fit, map.format");
      sub->add_option("--range", opts->ranges,
                      "A key's values: key=lo:hi[:intervals] (biases; default 16 intervals), key=lo:hi (map.size, "
                      "filter.taps: powers of two; filter.size: odd), or key=v1,v2,... (repeatable)")
          ->allow_extra_args(false);
      sub->add_option("--fixed", opts->fixed,
                      "A method key or scene:/pointer value for every configuration (repeatable)")
          ->allow_extra_args(false);
      app::addStudyOptions(sub, *opts, "tune");
      sub->add_flag("--no-report", opts->noReport, "No report.html (tune.html, tune.json, results.json/csv still)");
      sub->add_flag("--check-grid", opts->checkGrid,
                    "Also run the dense grid of the same keys and values and compare its best with the choice "
                    "(slow: the measurement of compare/TUNE.md)");
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
}  // namespace cmd_tune
