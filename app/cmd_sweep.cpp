// `shadowlab sweep [SCENES...] [--grid key=v1,v2]... [--sweep FILE] [--set key=value]... -o DIR`:
// every scene x configuration of the grid, one row each, resumable; ends with results.json,
// results.csv, figures/ and report.html (compare/SWEEPS.md).
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "command.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace {

namespace fs = std::filesystem;
using namespace shadowlab;

struct Options {
  std::vector<std::string> scenes;
  std::vector<std::string> grid;
  std::string sweepFile;
  std::vector<std::string> sets;
  std::string methodFile;
  std::string outDir;
  std::string light;
  int spp = 0;  // 0: not given (the sweep file's, else 1)
  std::string cacheDir;
  std::string device;
  bool keepImages = false;
  bool noReport = false;
  std::string shard;             // "I/N": only this shard's rows, into DIR/shards/I-of-N (no report)
  std::string frontierMetric;    // empty: not given (error_rate)
  std::string frontierThreshold; // text, checked here so "abc" is a GCC-style InputError, not CLI11's
};

std::atomic<bool> gStop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void onInterrupt(int) { gStop.store(true); }

// SA_RESETHAND: the first Ctrl-C asks for a clean stop after the configuration in progress; a
// second one kills the process the default way (rows already appended are safe either way).
void installInterruptHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onInterrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int run(const Options& o) {
  // ---- inputs: every error surfaces here, before the output folder exists --------------------
  SweepShard shard;
  if (!o.shard.empty()) shard = parseShardArgument(o.shard);
  SweepSpec spec;
  if (!o.sweepFile.empty()) loadSweepFile(o.sweepFile, spec);
  if (!o.scenes.empty()) spec.scenes = o.scenes;  // the command line names replace the file's
  for (const auto& g : o.grid) {
    SweepAxis axis = parseGridArgument(g);
    bool replaced = false;
    for (auto& existing : spec.grid)
      if (existing.key == axis.key) {
        existing = axis;
        replaced = true;
      }
    if (!replaced) spec.grid.push_back(std::move(axis));
  }
  for (const auto& s : o.sets) {
    SweepSetting setting = parseSetArgument(s);
    bool replaced = false;
    for (auto& existing : spec.fixed)
      if (existing.key == setting.key) {
        existing = setting;
        replaced = true;
      }
    if (!replaced) spec.fixed.push_back(std::move(setting));
  }
  if (!o.methodFile.empty()) spec.methodFile = o.methodFile;
  if (!o.light.empty()) spec.light = o.light;
  if (o.spp != 0) {
    if (o.spp < 1) throw InputError("--spp: error: got " + std::to_string(o.spp) + "; expected an integer >= 1");
    spec.spp = o.spp;
  }
  if (o.keepImages) spec.keepImages = true;
  if (!o.frontierMetric.empty()) spec.frontierMetric = o.frontierMetric;
  if (!o.frontierThreshold.empty()) {
    char* end = nullptr;
    double t = std::strtod(o.frontierThreshold.c_str(), &end);
    if (!end || *end != '\0' || !std::isfinite(t) || t < 0)
      throw InputError("--frontier-threshold: error: got \"" + o.frontierThreshold +
                       "\"; expected a number >= 0 (a rate, e.g. 0.01)");
    spec.frontierThreshold = t;
  }
  const SweepPlan plan = planSweep(spec);
  // Every output location, before any work.
  OutputFolder out(o.outDir);
  const std::string cacheDir = o.cacheDir.empty() ? defaultSweepCacheDir(o.outDir) : o.cacheDir;
  OutputFolder cacheFolder(cacheDir, o.cacheDir.empty() ? "-o (its reference cache)" : "--cache");
  cacheFolder.keep();  // a cache outlives the command

  // ---- work ------------------------------------------------------------------------------------
  auto runner = makePipelineRunner(cacheDir, spec.spp, o.device);
  SweepOptions options;
  options.outDir = o.outDir;
  options.progress = stderr;
  options.progressBar = ::isatty(STDERR_FILENO) == 1;
  options.stop = &gStop;
  options.writeReport = !o.noReport;
  options.shard = shard;
  // $SHADOWLAB_HOME (an unpacked bundle, like scenes/data) holds compare/report/charts.py too.
  const char* home = std::getenv("SHADOWLAB_HOME");
  options.reportScript = defaultReportScript(home && *home ? home : SHADOWLAB_SOURCE_DIR);
  std::fprintf(stderr, "sweep: %zu scene(s) x %zu configuration(s) = %zu rows into %s (reference cache %s)\n",
               plan.sceneNames.size(), plan.configs.size(), plan.jobs.size(), o.outDir.c_str(), cacheDir.c_str());
  if (shard.active())
    std::fprintf(stderr, "sweep: shard %zu/%zu: every %zu-th row from row %zu, into %s\n", shard.index, shard.count,
                 shard.count, shard.index, shardDir(o.outDir, shard).c_str());
  installInterruptHandlers();
  const SweepSummary summary = runSweep(plan, *runner, options);
  out.keep();  // rows, log and lock live there: a later run continues from them
  if (summary.interrupted) {
    std::fprintf(stderr,
                 "sweep: interrupted: %zu of %zu rows are saved in %s/rows.jsonl; run the same command again to "
                 "continue\n",
                 summary.resumed + summary.ran, summary.configurations,
                 (shard.active() ? shardDir(o.outDir, shard) : o.outDir).c_str());
    return 130;
  }
  for (const auto& n : summary.notes) std::fprintf(stderr, "sweep: note: %s\n", n.c_str());
  if (gStop.load()) {
    // Every row is saved; only the report may be incomplete (its chart script saw the Ctrl-C too).
    std::fprintf(stderr, "sweep: interrupted while writing the report; every row is saved, run the same command "
                         "again to regenerate it\n");
    return 130;
  }
  std::printf("sweep: %zu rows (%zu run, %zu resumed) in %.2f s\n", summary.configurations, summary.ran,
              summary.resumed, summary.commandWallSeconds);
  if (shard.active()) {
    std::printf("sweep: shard %zu/%zu done in %s; when every shard is done: shadowlab merge %s\n", shard.index,
                shard.count, shardDir(o.outDir, shard).c_str(), o.outDir.c_str());
    return 0;
  }
  std::printf("sweep: wrote %s and %s\n", summary.resultsJson.c_str(), summary.resultsCsv.c_str());
  if (!summary.reportHtml.empty()) std::printf("report: %s\n", fs::absolute(summary.reportHtml).c_str());
  return 0;
}

app::Registrar reg{"sweep", [](CLI::App& app) {
  auto opts = std::make_shared<Options>();
  auto* sub = app.add_subcommand("sweep", "Sweep scenes x a grid of method settings into a report (compare/SWEEPS.md)");
  sub->add_option("SCENES", opts->scenes, "Bundled scene names or scene files (default: every bundled scene)");
  sub->add_option("--grid", opts->grid,
                  "Swept key and its values, repeatable: key=v1,v2,... (method keys, or scene:/json/pointer)")
      ->allow_extra_args(false);
  sub->add_option("--sweep", opts->sweepFile, "Sweep file (JSON: scenes, grid, set, ...); the command line adds to it");
  sub->add_option("--set", opts->sets, "Method setting for every configuration key=value, repeatable")
      ->allow_extra_args(false);
  sub->add_option("--method", opts->methodFile, "Base method file (JSON, see raster/METHODS.md)");
  sub->add_option("-o,--out", opts->outDir, "Output folder (running again continues an interrupted sweep)")->required();
  sub->add_option("--light", opts->light, "Light to render and compare (default: each scene's first)");
  sub->add_option("--spp", opts->spp, "Reference samples per pixel (default 1)");
  sub->add_option("--cache", opts->cacheDir,
                  "Reference cache folder (default: $SHADOWLAB_CACHE, else .shadowlab-cache beside the output folder)");
  sub->add_option("--device", opts->device, "Vulkan device name substring (default: lavapipe)");
  sub->add_flag("--keep-images", opts->keepImages, "Write raster.exr and errors.png per configuration under DIR/images/");
  sub->add_option("--frontier-metric", opts->frontierMetric,
                  "Metric walked along swept scene: parameters for failure frontiers (default error_rate)");
  sub->add_option("--frontier-threshold", opts->frontierThreshold,
                  "Rate above which a configuration counts as broken (default 0.01)");
  sub->add_flag("--no-report", opts->noReport, "Write results.json/csv only: no charts, triptychs or report.html");
  sub->add_option("--shard", opts->shard,
                  "I/N: run only the rows whose plan index is I mod N, into DIR/shards/I-of-N (no report; "
                  "`shadowlab merge DIR` gathers the shards)");
  return std::function<int()>([opts] { return run(*opts); });
}};

}  // namespace
