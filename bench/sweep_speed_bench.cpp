// Sweep speed. Two numbers:
//  * BM_SweepMachineryPerRow: what the sweep itself adds per row (planning, the fsync'd journal
//    append, bookkeeping, results.json/csv), with a runner that does no rendering;
//  * BM_Sweep100At1080p: the speed goal of compare/SWEEPS.md, a 100-configuration sweep of sphere_on_plane at
//    1920x1080 end to end (reference from the cache after the first iteration, raster, compare,
//    charts, triptychs, report), on the default device (lavapipe). Goal: <= 15 s on 2 cores.
// Run: build/bench/sweep_speed_bench [--benchmark_filter=Machinery]
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "shadowlab/compare/sweep.h"

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

class NullRunner : public SweepRunner {
 public:
  SweepRunOutput run(const Scene&, const Method& m, const std::string&, const std::string&) override {
    SweepRunOutput out;
    out.metrics = {{"error_rate", 1.0 / m.mapSize}, {"acne_rate", 0.0}, {"leak_rate", 0.0}};
    out.timings = {{"shadow_gpu_ms", 1.0}, {"camera_gpu_ms", 1.0}, {"compare_ms", 1.0}};
    return out;
  }
  bool writeTriptych(const Scene&, const Method&, const std::string&, const std::string&) override { return false; }
};

SweepSpec hundredConfigs(bool fullHd) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid.push_back(parseGridArgument("map.size=256,512,1024,2048,4096"));
  spec.grid.push_back(parseGridArgument("bias.slope=0,0.5,1,1.5,2,3,4,6,8,12"));
  spec.grid.push_back(parseGridArgument("filter=none,pcf"));
  if (fullHd) {
    spec.fixed.push_back(parseSetArgument("scene:/camera/width=1920"));
    spec.fixed.push_back(parseSetArgument("scene:/camera/height=1080"));
  }
  return spec;
}

std::string benchDir(const char* name) {
  return (fs::temp_directory_path() / (std::string("shadowlab_sweep_bench_") + name + "_" + std::to_string(::getpid())))
      .string();
}

void BM_SweepMachineryPerRow(benchmark::State& state) {
  const SweepPlan plan = planSweep(hundredConfigs(false));
  const std::string dir = benchDir("machinery");
  NullRunner runner;
  double seconds = 0;
  for (auto _ : state) {
    state.PauseTiming();
    fs::remove_all(dir);
    state.ResumeTiming();
    SweepOptions o;
    o.outDir = dir;
    o.progress = nullptr;
    o.writeReport = false;
    SweepSummary s = runSweep(plan, runner, o);
    seconds += s.commandWallSeconds;
    benchmark::DoNotOptimize(s.ran);
  }
  state.counters["rows"] = double(plan.jobs.size());
  state.counters["ms_per_row"] = seconds * 1000.0 / double(state.iterations()) / double(plan.jobs.size());
  fs::remove_all(dir);
}
BENCHMARK(BM_SweepMachineryPerRow)->Unit(benchmark::kMillisecond);

void BM_Sweep100At1080p(benchmark::State& state) {
  const SweepPlan plan = planSweep(hundredConfigs(true));
  const std::string dir = benchDir("1080p");
  const std::string cache = dir + "_cache";
  auto runner = makePipelineRunner(cache, 1);
  double total = 0, loop = 0, report = 0;
  for (auto _ : state) {
    state.PauseTiming();
    fs::remove_all(dir);
    state.ResumeTiming();
    SweepOptions o;
    o.outDir = dir;
    o.progress = nullptr;
    o.reportScript = defaultReportScript(SHADOWLAB_SOURCE_DIR);
    SweepSummary s = runSweep(plan, *runner, o);
    total = s.commandWallSeconds;
    auto results = nlohmann::json::parse(std::ifstream(s.resultsJson));
    loop = results.value("loop_wall_seconds", 0.0);
    report = results.value("report_wall_seconds", 0.0);
  }
  state.counters["total_s"] = total;
  state.counters["loop_s"] = loop;
  state.counters["report_s"] = report;
  fs::remove_all(dir);
  fs::remove_all(cache);
}
BENCHMARK(BM_Sweep100At1080p)->Unit(benchmark::kSecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
