// The sweep loop with an injected fake runner (no renderer): rows are appended durably, an
// interrupted sweep resumes without running any finished configuration again, a torn last line
// is dropped, a damaged earlier line is refused, stale rows (another method) are run again, and
// results.json / results.csv hold exactly one row per scene x configuration.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "support/fake_sweep_runner.h"

namespace sweep_resume_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

using FakeRunner = shadowlab::testing::FakeSweepRunner;

// The fake's error_rate of a sphere_on_plane configuration.
double fakeErrorRate(const Method& m) { return shadowlab::testing::fakeErrorRate("sphere_on_plane", m); }

std::string tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_sweep_resume_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d.string();
}

SweepPlan smallPlan(std::vector<std::string> grid, std::vector<std::string> sets = {}) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  for (const auto& g : grid) spec.grid.push_back(parseGridArgument(g));
  for (const auto& s : sets) spec.fixed.push_back(parseSetArgument(s));
  return planSweep(spec);
}

SweepOptions quietOptions(const std::string& dir) {
  SweepOptions o;
  o.outDir = dir;
  o.progress = nullptr;
  o.writeReport = false;
  return o;
}

std::vector<std::string> lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  std::string line;
  while (std::getline(in, line)) out.push_back(line);
  return out;
}

}  // namespace

TEST(SweepResume, WritesOneRowPerConfigurationWithItsNumbers) {
  const std::string dir = tempDir("rows");
  SweepPlan plan = smallPlan({"map.size=256,512", "bias.slope=0,2"});
  FakeRunner runner;
  SweepSummary s = runSweep(plan, runner, quietOptions(dir));
  EXPECT_FALSE(s.interrupted);
  EXPECT_EQ(s.ran, 4u);
  EXPECT_EQ(s.resumed, 0u);
  auto rows = loadResultRows(dir + "/results.json");
  ASSERT_EQ(rows.size(), 4u);
  const char* expected[] = {"bias.slope=0,map.size=256", "bias.slope=2,map.size=256", "bias.slope=0,map.size=512",
                            "bias.slope=2,map.size=512"};
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(rows[i].scene, "sphere_on_plane");
    EXPECT_EQ(rows[i].config, expected[i]);
    EXPECT_EQ(rows[i].light, "sun");
    const Method& m = plan.configs[i].method;
    EXPECT_DOUBLE_EQ(rows[i].metrics.at("error_rate").get<double>(), fakeErrorRate(m));
    EXPECT_EQ(rows[i].method.at("map.size").get<int>(), m.mapSize);
    for (const char* t : {"shadow_gpu_ms", "camera_gpu_ms", "readback_ms", "compare_ms", "config_wall_ms"})
      EXPECT_TRUE(rows[i].timings.contains(t)) << t;
  }
  // results.json records the total and the per-configuration times.
  auto results = nlohmann::json::parse(readFile(dir + "/results.json"));
  EXPECT_EQ(results.at("configurations").get<int>(), 4);
  EXPECT_GE(results.at("command_wall_seconds").get<double>(), 0.0);
  ASSERT_EQ(results.at("config_wall_seconds").size(), 4u);
  EXPECT_EQ(results.at("config_wall_seconds")[3].at("config"), "bias.slope=2,map.size=512");
  EXPECT_EQ(results.at("sweep").at("grid")[0].at("key"), "map.size");
  EXPECT_EQ(results.at("sweep").at("grid")[0].at("values"), nlohmann::json({"256", "512"}));

  // CSV: header then one line per row; the config (it holds commas) is quoted.
  auto csv = lines(dir + "/results.csv");
  ASSERT_EQ(csv.size(), 5u);
  EXPECT_EQ(csv[0].rfind("scene,config,light,", 0), 0u) << csv[0];
  for (const char* col : {",map.size,", ",bias.slope,", ",error_rate,", ",config_wall_ms"})
    EXPECT_NE(csv[0].find(col), std::string::npos) << col;
  EXPECT_EQ(csv[1].rfind("sphere_on_plane,\"bias.slope=0,map.size=256\",sun,", 0), 0u) << csv[1];
  fs::remove_all(dir);
}

TEST(SweepResume, InterruptedSweepContinuesWithoutRunningAnyRowTwice) {
  const std::string dir = tempDir("interrupt");
  SweepPlan plan = smallPlan({"map.size=256,512,1024", "bias.slope=0,1,2"});  // 9 rows
  std::atomic<bool> stop{false};
  FakeRunner first;
  first.stopAfter = &stop;
  first.stopAfterRuns = 4;
  SweepOptions o = quietOptions(dir);
  o.stop = &stop;
  SweepSummary s1 = runSweep(plan, first, o);
  EXPECT_TRUE(s1.interrupted);
  EXPECT_EQ(s1.ran, 4u) << "the configuration in progress when the stop came is finished and kept";
  EXPECT_EQ(lines(dir + "/rows.jsonl").size(), 4u);
  EXPECT_FALSE(fs::exists(dir + "/results.json")) << "an interrupted sweep does not write partial results";

  stop = false;
  FakeRunner second;
  SweepSummary s2 = runSweep(plan, second, o);
  EXPECT_FALSE(s2.interrupted);
  EXPECT_EQ(s2.resumed, 4u);
  EXPECT_EQ(s2.ran, 5u);
  for (const auto& [key, n] : first.runs) EXPECT_EQ(second.runs.count(key), 0u) << key << " ran again";
  for (const auto& [key, n] : second.runs) EXPECT_EQ(n, 1) << key;
  auto rows = loadResultRows(dir + "/results.json");
  ASSERT_EQ(rows.size(), 9u);
  std::set<std::string> keys;
  for (const auto& r : rows) EXPECT_TRUE(keys.insert(r.key()).second) << "duplicate " << r.key();

  // A third run finds everything done and runs nothing.
  FakeRunner third;
  SweepSummary s3 = runSweep(plan, third, o);
  EXPECT_EQ(s3.ran, 0u);
  EXPECT_EQ(s3.resumed, 9u);
  EXPECT_EQ(third.total, 0);
  fs::remove_all(dir);
}

TEST(SweepResume, TornLastLineIsDroppedAndRunAgain) {
  const std::string dir = tempDir("torn");
  SweepPlan plan = smallPlan({"map.size=256,512,1024"});
  FakeRunner first;
  runSweep(plan, first, quietOptions(dir));
  // Simulate a kill in the middle of appending the third row: cut its line short.
  auto all = lines(dir + "/rows.jsonl");
  ASSERT_EQ(all.size(), 3u);
  {
    std::ofstream out(dir + "/rows.jsonl", std::ios::trunc);
    out << all[0] << "\n" << all[1] << "\n" << all[2].substr(0, all[2].size() / 2);
  }
  FakeRunner second;
  SweepSummary s = runSweep(plan, second, quietOptions(dir));
  EXPECT_EQ(s.resumed, 2u);
  EXPECT_EQ(s.ran, 1u);
  ASSERT_EQ(second.runs.size(), 1u);
  EXPECT_NE(second.runs.begin()->first.find("|1024|"), std::string::npos);
  auto now = lines(dir + "/rows.jsonl");
  ASSERT_EQ(now.size(), 3u) << "the torn line is truncated away, not left before the new row";
  for (const auto& l : now) EXPECT_TRUE(nlohmann::json::accept(l)) << l;
  fs::remove_all(dir);
}

TEST(SweepResume, DamagedEarlierLineIsRefused) {
  const std::string dir = tempDir("damaged");
  SweepPlan plan = smallPlan({"map.size=256,512"});
  FakeRunner first;
  runSweep(plan, first, quietOptions(dir));
  auto all = lines(dir + "/rows.jsonl");
  {
    std::ofstream out(dir + "/rows.jsonl", std::ios::trunc);
    out << "{not json\n" << all[1] << "\n";
  }
  FakeRunner second;
  try {
    runSweep(plan, second, quietOptions(dir));
    FAIL() << "a damaged row before the last line must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/rows.jsonl:1"), std::string::npos) << e.what();
  }
  EXPECT_EQ(second.total, 0);
  fs::remove_all(dir);
}

TEST(SweepResume, RowsOfAnotherMethodAreRunAgain) {
  const std::string dir = tempDir("stale");
  FakeRunner first;
  runSweep(smallPlan({"map.size=256,512"}, {"bias.slope=1"}), first, quietOptions(dir));
  // Another fixed bias: other configurations (their names hold the bias), run again.
  FakeRunner second;
  SweepSummary s = runSweep(smallPlan({"map.size=256,512"}, {"bias.slope=3"}), second, quietOptions(dir));
  EXPECT_EQ(s.resumed, 0u);
  EXPECT_EQ(s.ran, 2u);
  auto rows = loadResultRows(dir + "/results.json");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_DOUBLE_EQ(rows[0].method.at("bias.slope").get<double>(), 3.0);
  fs::remove_all(dir);
}

TEST(SweepResume, ParetoFrontKeepsOnlyRowsThatBeatEveryFasterRow) {
  std::vector<ResultRow> rows(5);
  const double ms[] = {10, 20, 30, 40, 15};
  const double err[] = {0.5, 0.2, 0.3, 0.1, 0.6};
  for (int i = 0; i < 5; ++i) {
    rows[i].scene = "s";
    rows[i].config = "c" + std::to_string(i);
    // The harness's camera pass (the evidence resolve) shrinks as the method's time grows: ranked
    // by shadow + camera the front would be c3 alone. It must not count (compare/TIMINGS.md).
    rows[i].timings = {{"shadow_gpu_ms", ms[i] / 2},
                       {"lookup_gpu_ms", ms[i] / 2},
                       {"method_gpu_ms", ms[i]},
                       {"camera_gpu_ms", 1000.0 / ms[i]}};
    rows[i].metrics = {{"error_rate", err[i]}};
  }
  // By method time: c0 (10, 0.5) front; c4 (15, 0.6) dominated; c1 (20, 0.2) front; c2 (30, 0.3)
  // dominated; c3 (40, 0.1) front.
  EXPECT_EQ(paretoFront(rows, "s"), (std::vector<size_t>{0, 1, 3}));
  EXPECT_TRUE(paretoFront(rows, "other").empty());
  // A row from before the lookup pass (no method_gpu_ms): its shadow pass + lookup (absent: 0).
  rows[3].timings = {{"shadow_gpu_ms", 5.0}, {"camera_gpu_ms", 1.0}};  // now the fastest, and the most accurate
  EXPECT_EQ(paretoFront(rows, "s"), (std::vector<size_t>{3}));
}

TEST(SweepResume, ASecondSweepIntoTheSameFolderIsRefusedWhileOneRuns) {
  const std::string dir = tempDir("lock");
  SweepPlan plan = smallPlan({"map.size=256,512"});
  // The fake runner starts a nested sweep into the same folder while the outer one holds it.
  struct Nested : FakeRunner {
    const SweepPlan* plan = nullptr;
    std::string dir, error;
    SweepRunOutput run(const Scene& s, const Method& m, const std::string& l, const std::string& i) override {
      if (error.empty()) {
        FakeRunner inner;
        try {
          runSweep(*plan, inner, quietOptions(dir));
          error = "(none)";
        } catch (const InputError& e) {
          error = e.what();
        }
      }
      return FakeRunner::run(s, m, l, i);
    }
  } runner;
  runner.plan = &plan;
  runner.dir = dir;
  runSweep(plan, runner, quietOptions(dir));
  EXPECT_NE(runner.error.find("another sweep is writing into this folder"), std::string::npos) << runner.error;
  EXPECT_EQ(lines(dir + "/rows.jsonl").size(), 2u);
  fs::remove_all(dir);
}

// Every row names the device of its timings; resuming rows another device measured is refused
// (exit 2 from the CLI), naming both devices, and leaves the journal as it was.
TEST(SweepResume, RowsOfAnotherDeviceAreRefusedNotMixed) {
  const std::string dir = tempDir("device");
  SweepPlan plan = smallPlan({"map.size=256,512"});
  FakeRunner gpu;
  gpu.device = "NVIDIA H100 (NVIDIA)";
  runSweep(plan, gpu, quietOptions(dir));
  for (const auto& line : lines(dir + "/rows.jsonl"))
    EXPECT_EQ(nlohmann::json::parse(line).at("device"), "NVIDIA H100 (NVIDIA)") << line;
  auto results = nlohmann::json::parse(readFile(dir + "/results.json"));
  for (const auto& row : results.at("rows")) EXPECT_EQ(row.at("device"), "NVIDIA H100 (NVIDIA)") << row.dump();

  const std::string journalBefore = readFile(dir + "/rows.jsonl");
  FakeRunner cpu;
  cpu.device = "llvmpipe (llvmpipe)";
  try {
    runSweep(plan, cpu, quietOptions(dir));
    FAIL() << "resuming rows of another device must throw";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("rows.jsonl"), std::string::npos) << what;
    EXPECT_NE(what.find("\"NVIDIA H100 (NVIDIA)\""), std::string::npos) << what;
    EXPECT_NE(what.find("\"llvmpipe (llvmpipe)\""), std::string::npos) << what;
  }
  EXPECT_EQ(cpu.total, 0) << "nothing may run on the second device";
  EXPECT_EQ(readFile(dir + "/rows.jsonl"), journalBefore);

  // The same device resumes as before.
  FakeRunner again;
  again.device = "NVIDIA H100 (NVIDIA)";
  SweepSummary s = runSweep(plan, again, quietOptions(dir));
  EXPECT_EQ(s.resumed, 2u);
  EXPECT_EQ(again.total, 0);
  fs::remove_all(dir);
}

// A journal an older build wrote has no "device": its timings cannot be placed on a device's
// axis, so a runner that has a device refuses it too.
TEST(SweepResume, RowsWithoutARecordedDeviceAreRefusedByADevice) {
  const std::string dir = tempDir("nodevice");
  SweepPlan plan = smallPlan({"map.size=256"});
  FakeRunner old;  // device "": writes "device": ""
  runSweep(plan, old, quietOptions(dir));
  std::string journal = readFile(dir + "/rows.jsonl");
  nlohmann::json line = nlohmann::json::parse(journal.substr(0, journal.find('\n')));
  line.erase("device");
  writeFileAtomic(dir + "/rows.jsonl", line.dump() + "\n");
  FakeRunner now;
  now.device = "llvmpipe (llvmpipe)";
  try {
    runSweep(plan, now, quietOptions(dir));
    FAIL() << "rows without a device must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not recorded"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace sweep_resume_test
