// `shadowlab merge OUT_DIR`: gathers the journals of a sharded sweep (`shadowlab sweep ... --shard
// I/N -o OUT_DIR`, one per machine) into OUT_DIR/results.json, results.csv and the report, the
// same files an unsharded sweep writes (compare/SWEEPS.md, "Many machines").
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "command.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"

namespace cmd_merge {
namespace {

namespace fs = std::filesystem;
using namespace shadowlab;

struct Options {
  std::string outDir;
  std::string cacheDir;
  std::string device;
  double gpuTimeoutS = 0;
  bool noReport = false;
};

int run(const Options& o) {
  // The sweep as the shards recorded it, planned again: scene or method files edited since the
  // shards ran change the fingerprint, and the merge refuses.
  checkGpuTimeout(o.gpuTimeoutS, "--gpu-timeout-s");
  const SweepSpec spec = loadShardedSpec(o.outDir);
  const SweepPlan plan = planSweep(spec);
  const std::string cacheDir = o.cacheDir.empty() ? defaultSweepCacheDir(o.outDir) : o.cacheDir;
  // The runner renders only for the report's triptychs (created on first use).
  auto runner = makePipelineRunner(cacheDir, spec.spp, o.device, 1, false, true, spec.lightSamples, o.gpuTimeoutS);
  SweepOptions options;
  options.outDir = o.outDir;
  options.progress = stderr;
  options.writeReport = !o.noReport;
  const char* home = std::getenv("SHADOWLAB_HOME");
  options.reportScript = defaultReportScript(home && *home ? home : SHADOWLAB_SOURCE_DIR);
  const SweepSummary summary = mergeSweepShards(plan, *runner, options);
  for (const auto& n : summary.notes) std::fprintf(stderr, "merge: note: %s\n", n.c_str());
  std::printf("merge: %zu rows from the shards of %s\n", summary.configurations, o.outDir.c_str());
  std::printf("merge: wrote %s and %s\n", summary.resultsJson.c_str(), summary.resultsCsv.c_str());
  if (!summary.reportHtml.empty()) std::printf("report: %s\n", fs::absolute(summary.reportHtml).c_str());
  return 0;
}

app::Registrar reg{
    "merge", [](CLI::App& app) {
      auto opts = std::make_shared<Options>();
      auto* sub =
          app.add_subcommand("merge", "Merge the shards of a sweep (sweep --shard I/N) into results and a report");
      sub->add_option("OUT_DIR", opts->outDir, "The -o folder the shards ran into (holds shards/I-of-N/)")->required();
      sub->add_option(
          "--cache", opts->cacheDir,
          "Reference cache folder for the triptychs (default: $SHADOWLAB_CACHE, else .shadowlab-cache beside OUT_DIR)");
      sub->add_option("--device", opts->device, "Vulkan device name substring for the triptychs (default: lavapipe)");
      app::addGpuTimeoutOption(sub, &opts->gpuTimeoutS);
      sub->add_flag("--no-report", opts->noReport, "Write results.json/csv only: no charts, triptychs or report.html");
      return std::function<int()>([opts] { return run(*opts); });
    }};

}  // namespace
}  // namespace cmd_merge
