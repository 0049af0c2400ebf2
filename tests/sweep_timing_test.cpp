// Timing where it decides something (sweep.h, rowsWhoseTimeDecides; compare/TIMINGS.md, "Timed
// repetitions"): which rows are timed again, that runSweep times exactly those, keeps their median
// through a resume, and times none with --timing-repetitions 0. The GPU side (a real sweep's fronts
// in both grid orders) is tests/report_chromium_test.cpp, ReportTimings.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "shadowlab/compare/method_cost.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/io.h"
#include "support/fake_sweep_runner.h"

namespace sweep_timing_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

using FakeRunner = shadowlab::testing::FakeSweepRunner;

ResultRow row(const std::string& scene, double errorRate, double methodGpuMs, bool compared = true) {
  ResultRow r;
  r.scene = scene;
  r.config = scene + "@" + std::to_string(errorRate) + "/" + std::to_string(methodGpuMs);
  r.metrics = {{"error_rate", errorRate}, {"pixels_compared", compared ? 100 : 0}};
  if (!compared) r.metrics["nothing_compared"] = true;
  r.timings = {{"method_gpu_ms", methodGpuMs}};
  return r;
}

std::string tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_sweep_timing_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d.string();
}

}  // namespace

// Scene a, (error_rate, ms): the front is (0, 100), (0.01, 10), (0.05, 2), (0.1, 1). (0.05, 2.5)
// ties the front's error at 1.25x its time and (0.2, 1.4) is 1.4x the fastest row: within the
// noise factor 1.5, so both are timed again; (0.2, 5) is 5x a more accurate row and (0.3, 12) 1.2x
// (0.01, 10) but 12x (0.1, 1): robustly beaten. Scene b's only row is its front. A row that
// compared nothing, and one without an error rate, are never ranked.
TEST(SweepTiming, RowsWithinTheNoiseBandOfEachScenesFront) {
  std::vector<ResultRow> rows = {row("a", 0.1, 1.0),  row("a", 0.05, 2.0),      row("a", 0.05, 2.5), row("a", 0.01, 10),
                                 row("a", 0.2, 1.4),  row("a", 0.2, 5.0),       row("a", 0.0, 100),  row("a", 0.3, 12),
                                 row("b", 0.3, 50.0), row("a", 0.0, 0.1, false)};
  rows.push_back(row("a", 0.5, 0.05));
  rows.back().metrics["error_rate"] = nullptr;
  std::vector<const ResultRow*> ptrs;
  for (const auto& r : rows) ptrs.push_back(&r);
  EXPECT_EQ(rowsWhoseTimeDecides(ptrs), (std::vector<size_t>{0, 1, 2, 3, 4, 6, 8}));
  // A tighter band times fewer: at 1.2, (0.2, 1.4) is beaten (1.2 < 1.4), (0.05, 2.5) too (2.4 < 2.5).
  EXPECT_EQ(rowsWhoseTimeDecides(ptrs, {}, 1.2), (std::vector<size_t>{0, 1, 3, 6, 8}));
  // Factor 1: the Pareto front itself, ties in error at the same time included.
  rows.push_back(row("a", 0.1, 1.0));
  ptrs.clear();
  for (const auto& r : rows) ptrs.push_back(&r);
  EXPECT_EQ(rowsWhoseTimeDecides(ptrs, {}, 1.0), (std::vector<size_t>{0, 1, 3, 6, 8, 11}));
}

// Configurations of one modelled cost (a bias axis: the same passes) measure alike but for noise:
// the most accurate stands for them, unless a measurement contradicts the model beyond the noise.
// Scene c, (error_rate, ms, model ms): (0.05, 1.2, 5) is the front; (0.1, 1.0, 5) and (0.2, 0.9, 5)
// are no cheaper by the model and not faster beyond the factor; (0.3, 0.5, 5) is 2.4x faster than
// the model allows (1.2 / 0.5 > 1.5), so its time decides; (0.01, 9, 20) is dearer and more
// accurate: the front's next step. Without the model every row but none is timed.
TEST(SweepTiming, RowsOfOneModelledCostAreRepresentedByTheMostAccurate) {
  const std::vector<ResultRow> rows = {row("c", 0.1, 1.0), row("c", 0.05, 1.2), row("c", 0.2, 0.9), row("c", 0.3, 0.5),
                                       row("c", 0.01, 9.0)};
  std::vector<const ResultRow*> ptrs;
  for (const auto& r : rows) ptrs.push_back(&r);
  EXPECT_EQ(rowsWhoseTimeDecides(ptrs, {5, 5, 5, 5, 20}), (std::vector<size_t>{1, 3, 4}));
  EXPECT_EQ(rowsWhoseTimeDecides(ptrs), (std::vector<size_t>{0, 1, 2, 3, 4}));
}

// runSweep times again the rows rowsWhoseTimeDecides names, once: they carry method_gpu_ms_min
// and _max and results.json says how many; a resumed sweep keeps their medians and times nothing.
TEST(SweepTiming, RunSweepTimesTheDecidingRowsOnceAndKeepsThemOnResume) {
  const std::string dir = tempDir("resume");
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  // The fake's error is 1/size + 0.001 slope, its time size/100 ms: the front is slope 0 at every
  // size; the rows of slope 8 and 100 cost what their size's slope-0 row costs by the model (a
  // bias changes no pass) and measure the same: 3 rows of 9 are timed again.
  spec.grid.push_back(parseGridArgument("map.size=256,1024,4096"));
  spec.grid.push_back(parseGridArgument("bias.slope=0,8,100"));
  const SweepPlan plan = planSweep(spec);
  FakeRunner runner;
  runner.timesAgain = true;
  SweepOptions o;
  o.outDir = dir;
  o.progress = nullptr;
  o.writeReport = false;
  const SweepSummary s = runSweep(plan, runner, o);
  std::vector<ResultRow> rows = loadResultRows(dir + "/results.json");
  ASSERT_EQ(rows.size(), 9u);
  // What the selection says of the rows as first measured (the fake's single samples).
  std::vector<ResultRow> single = rows;
  for (auto& r : single) r.timings = {{"method_gpu_ms", r.method.at("map.size").get<int>() / 100.0}};
  std::vector<const ResultRow*> ptrs;
  std::vector<double> model;
  for (size_t i = 0; i < single.size(); ++i) {
    ptrs.push_back(&single[i]);
    const SweepJob& job = plan.jobs[i];
    model.push_back(estimateMethodCost(plan.variants[job.variantIndex], plan.configs[job.configIndex].method, job.light)
                        .estimatedMs);
  }
  const std::vector<size_t> deciding = rowsWhoseTimeDecides(ptrs, model);
  ASSERT_EQ(deciding, (std::vector<size_t>{0, 3, 6}));  // slope 0 at 256, 1024 and 4096 (plan order)
  EXPECT_EQ(jobsWhoseTimeDecides(plan, ptrs), deciding);
  EXPECT_EQ(s.retimed, deciding.size());
  EXPECT_EQ(runner.retimes.size(), deciding.size());
  for (const auto& [what, n] : runner.retimes) EXPECT_EQ(n, 1) << what;
  const std::set<size_t> want(deciding.begin(), deciding.end());
  for (size_t i = 0; i < rows.size(); ++i) {
    const bool median = rows[i].timings.contains("method_gpu_ms_min");
    EXPECT_EQ(median, want.count(i) == 1) << rows[i].config;
    EXPECT_EQ(median, rows[i].timings.contains("method_gpu_ms_max")) << rows[i].config;
    if (median) {
      // The row's own sample (size/100 ms) and the fake's two more (0.9 of it, +0.1 ms for the first):
      // the median is the middle run, the range the other two.
      const double own = rows[i].method.at("map.size").get<int>() / 100.0;
      EXPECT_DOUBLE_EQ(rows[i].timings.at("method_gpu_ms").get<double>(), 0.9 * own + 0.1);
      EXPECT_DOUBLE_EQ(rows[i].timings.at("shadow_gpu_ms").get<double>(), 0.9 * own + 0.1);
      EXPECT_DOUBLE_EQ(rows[i].timings.at("method_gpu_ms_min").get<double>(), 0.9 * own);
      EXPECT_DOUBLE_EQ(rows[i].timings.at("method_gpu_ms_max").get<double>(), own);
    }
  }
  const nlohmann::json results = nlohmann::json::parse(readFile(dir + "/results.json"));
  EXPECT_EQ(results["timing"]["repetitions"], 3);
  EXPECT_EQ(results["timing"]["rows_with_median"], deciding.size());
  EXPECT_EQ(results["timing"]["rows_single_sample"], rows.size() - deciding.size());

  // Resumed: every row from the journal, medians included; nothing rendered or timed again.
  FakeRunner again;
  again.timesAgain = true;
  const SweepSummary r = runSweep(plan, again, o);
  EXPECT_EQ(r.resumed, 9u);
  EXPECT_EQ(again.total, 0);
  EXPECT_TRUE(again.retimes.empty());
  const std::vector<ResultRow> resumed = loadResultRows(dir + "/results.json");
  for (size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(resumed[i].timings, rows[i].timings) << rows[i].config;
  fs::remove_all(dir);

  // --timing-repetitions 0 (or 1: the render's own run): every row keeps its single sample.
  for (int reps : {0, 1}) {
    FakeRunner none;
    none.timesAgain = true;
    o.timingRepetitions = reps;
    runSweep(plan, none, o);
    EXPECT_TRUE(none.retimes.empty()) << reps;
    for (const auto& row : loadResultRows(dir + "/results.json"))
      EXPECT_FALSE(row.timings.contains("method_gpu_ms_min")) << row.config;
    EXPECT_EQ(nlohmann::json::parse(readFile(dir + "/results.json"))["timing"]["repetitions"], 1);
    fs::remove_all(dir);
  }
}

// Rows a caller names (shadowlab tune's quoted configurations) are timed again even with the
// front's selection off, as tune's own runSweep calls are.
TEST(SweepTiming, NamedRowsAreTimedAgainWithoutTheFront) {
  const std::string dir = tempDir("named");
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid.push_back(parseGridArgument("map.size=256,1024"));
  const SweepPlan plan = planSweep(spec);
  FakeRunner runner;
  runner.timesAgain = true;
  SweepOptions o;
  o.outDir = dir;
  o.progress = nullptr;
  o.writeResults = false;
  o.retimeKeys = {plan.jobs[1].key()};
  const SweepSummary s = runSweep(plan, runner, o);
  EXPECT_EQ(s.retimed, 1u);
  ASSERT_EQ(runner.retimes.size(), 1u);
  EXPECT_EQ(runner.retimes.begin()->first.rfind("sphere_on_plane|1024|", 0), 0u) << runner.retimes.begin()->first;
  ASSERT_EQ(s.rows.size(), 2u);
  EXPECT_FALSE(s.rows[0].timings.contains("method_gpu_ms_min"));
  EXPECT_TRUE(s.rows[1].timings.contains("method_gpu_ms_min"));
  EXPECT_EQ(s.retimedTimings.at(plan.jobs[1].key()), s.rows[1].timings);
  fs::remove_all(dir);
}

}  // namespace sweep_timing_test
