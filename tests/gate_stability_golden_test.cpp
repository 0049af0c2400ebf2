// The project gates its own temporal stability: the golden stability run (the arguments in
// tests/golden/stability.args: unstabilized cascades on long_view's "walk" dolly, 6 frames at
// 320x180) is re-run through the real binary and gated against tests/golden/stability_baseline.json
// under tests/golden/tolerances.json. A change that makes shadows shimmer more (or less) fails here
// with the metric's name and both values. Doctored baselines must fail: under the golden's "equal"
// tolerances in either direction, under the built-in directional tolerances only when the current
// run is worse (shimmer_rate, error_rate_max, error_jump_max: lower is better). Update on purpose
// with tests/golden/update.sh.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "support/cli.h"

namespace gate_stability_golden_test {

namespace {

namespace fs = std::filesystem;

const fs::path kGolden = fs::path(SHADOWLAB_SOURCE_DIR) / "tests" / "golden";

using shadowlab::testing::CliRun;
using shadowlab::testing::slurp;

class StabilityGolden : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_stability_golden_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const char* name : {"stability_baseline.json", "stability.args", "tolerances.json"})
      ASSERT_TRUE(fs::exists(kGolden / name))
          << "golden file missing: " << (kGolden / name) << " (regenerate with tests/golden/update.sh)";
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  CliRun shadowlab(const std::string& args) { return shadowlab::testing::runShadowlab(args, dir_); }

  // The golden run's arguments: stability.args without its comment lines.
  static std::string goldenArgs() {
    std::ifstream in(kGolden / "stability.args");
    std::string line, args;
    while (std::getline(in, line))
      if (!line.empty() && line[0] != '#') args += line + " ";
    return args;
  }

  fs::path dir_;
};

TEST_F(StabilityGolden, GoldenStabilityRunPassesTheGateAndDoctoredBaselinesFail) {
  const fs::path out = dir_ / "run";
  CliRun run = shadowlab("stability " + goldenArgs() + "-o " + out.string() + " --cache " + (dir_ / "cache").string());
  if (run.code == 3 && run.err.find("no Vulkan device") != std::string::npos)
    GTEST_SKIP() << "no Vulkan device, the golden stability run cannot run: " << run.err;
  ASSERT_EQ(run.code, 0) << "the golden stability run failed:\n" << run.out << run.err;
  const std::string current = (out / "stability.json").string();
  ASSERT_TRUE(fs::exists(current));
  const std::string baseline = (kGolden / "stability_baseline.json").string();
  const std::string tolerances = (kGolden / "tolerances.json").string();

  CliRun gate = shadowlab("gate " + current + " --baseline " + baseline + " --tolerances " + tolerances + " --json " +
                          (dir_ / "gate.json").string());
  EXPECT_EQ(gate.code, 0) << "the golden stability gate failed: a change moved these metrics (if on purpose, run "
                             "tests/golden/update.sh and commit the reviewed baseline):\n"
                          << gate.err << gate.out;
  nlohmann::json report = nlohmann::json::parse(slurp(dir_ / "gate.json"));
  EXPECT_EQ(report["counts"]["rows_compared"], 1);
  EXPECT_EQ(report["counts"]["rows_new"], 0);
  // Every gated stability metric was checked, not merely present.
  std::set<std::string> checked;
  for (const auto& c : report["checks"])
    if (c["kind"] == "metric") checked.insert(c["metric"].get<std::string>());
  for (const char* m :
       {"frames", "shimmer_rate", "error_rate_mean", "error_rate_max", "error_rate_std", "error_jump_max"})
    EXPECT_TRUE(checked.count(m)) << m << " was not gated: " << report.dump();

  // The golden must show something to gate: unstabilized cascades shimmer.
  nlohmann::json golden = nlohmann::json::parse(slurp(baseline));
  const double shimmer = golden["metrics"]["shimmer_rate"].get<double>();
  const double jump = golden["metrics"]["error_jump_max"].get<double>();
  EXPECT_GT(shimmer, 2e-4);
  EXPECT_GT(jump, 2e-4);

  // A baseline from before a change that doubled the shimmer and the largest error jump: the
  // current run must now fail, naming both metrics.
  nlohmann::json better = golden;
  better["metrics"]["shimmer_rate"] = shimmer / 2;
  better["metrics"]["error_jump_max"] = jump / 2;
  std::ofstream(dir_ / "better.json") << better.dump(2);
  CliRun caught =
      shadowlab("gate " + current + " --baseline " + (dir_ / "better.json").string() + " --tolerances " + tolerances);
  EXPECT_EQ(caught.code, 1) << caught.out << caught.err;
  const std::string row = golden["scene"].get<std::string>() + " | " + golden["config"].get<std::string>() + " | " +
                          golden["light"].get<std::string>();
  EXPECT_NE(caught.err.find("shadowlab gate: error: " + row + ": metric \"shimmer_rate\" is "), std::string::npos)
      << caught.err;
  EXPECT_NE(caught.err.find(": metric \"error_jump_max\" is "), std::string::npos) << caught.err;
  EXPECT_NE(caught.out.find("FAIL: 2 regressions,"), std::string::npos) << caught.out;

  // The built-in tolerances (a user's CI): exact, lower is better. The baselines are this run's
  // own stability.json doctored (a golden from another machine may differ in a few pixels). Against
  // halved values the run is worse and fails ("above the baseline"); against doubled ones it is
  // better and passes, counted as improvements.
  const nlohmann::json mine = nlohmann::json::parse(slurp(current));
  nlohmann::json halved = mine, doubled = mine;
  for (const char* m : {"shimmer_rate", "error_rate_max"}) {
    halved["metrics"][m] = mine["metrics"][m].get<double>() / 2;
    doubled["metrics"][m] = mine["metrics"][m].get<double>() * 2;
  }
  std::ofstream(dir_ / "halved.json") << halved.dump(2);
  std::ofstream(dir_ / "worse.json") << doubled.dump(2);
  CliRun directional = shadowlab("gate " + current + " --baseline " + (dir_ / "halved.json").string());
  EXPECT_EQ(directional.code, 1) << directional.out << directional.err;
  EXPECT_NE(directional.err.find("metric \"shimmer_rate\" is "), std::string::npos) << directional.err;
  EXPECT_NE(directional.err.find("metric \"error_rate_max\" is "), std::string::npos) << directional.err;
  EXPECT_NE(directional.err.find(", above the baseline "), std::string::npos) << directional.err;
  EXPECT_NE(directional.out.find("FAIL: 2 regressions,"), std::string::npos) << directional.out;
  CliRun improved = shadowlab("gate " + current + " --baseline " + (dir_ / "worse.json").string());
  EXPECT_EQ(improved.code, 0) << improved.out << improved.err;
  EXPECT_NE(improved.out.find("2 improved"), std::string::npos) << improved.out;
}

}  // namespace

}  // namespace gate_stability_golden_test
