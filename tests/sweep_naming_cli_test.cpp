// Through the real binary: one name per configuration for every command (a `run` is gated against
// the sweep row of the same configuration, however either was spelled), one range of reference
// samples per pixel checked before anything is written, and --grid / --set given twice refused.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/results.h"
#include "shadowlab/scenes/io.h"
#include "support/cli.h"

namespace sweep_naming_cli_test {

namespace fs = std::filesystem;
using shadowlab::testing::CliRun;
using shadowlab::testing::freshTempDir;
using shadowlab::testing::runShadowlab;
using shadowlab::testing::slurp;

namespace {

// sphere_on_plane at 240x135 as DIR/sphere_on_plane.json: the bundled scene's name and geometry,
// cheap enough for the suite.
std::string smallScene(const fs::path& dir) {
  auto doc = nlohmann::json::parse(
      shadowlab::readFile(std::string(SHADOWLAB_SOURCE_DIR) + "/scenes/data/sphere_on_plane.json"), nullptr, true,
      /*ignore_comments=*/true);
  doc["camera"]["width"] = 240;
  doc["camera"]["height"] = 135;
  const std::string path = (dir / "sphere_on_plane.json").string();
  std::ofstream(path) << doc.dump(2);
  return path;
}

std::string firstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

}  // namespace

// `run` with a method key and a scene: value, `sweep` with the scene: value set for every
// configuration and the method key in its grid: the gate finds the run's row in the sweep's results
// and passes, leaving the sweep's other rows out (not run); a doctored baseline fails it, and a run
// of a configuration the sweep does not have is refused (exit 2), not passed on no comparison.
// (Names of rows with a key at its default: tests/sweep_config_name_test.cpp.) Method values are
// printed as written (0.0005, not the float's widened 0.0005000000237487257).
TEST(SweepNamingCli, RunIsGatedAgainstTheSweepRowOfTheSameConfiguration) {
  const fs::path dir = freshTempDir("shadowlab_naming_gate");
  const std::string scene = smallScene(dir);
  const std::string cache = (dir / "cache").string();
  CliRun sweep = runShadowlab("sweep " + scene + " --grid map.size=256,512 --set scene:/camera/height=120 -o " +
                                  (dir / "sweep").string() + " --cache " + cache + " --no-report",
                              dir);
  if (sweep.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << sweep.err;
  ASSERT_EQ(sweep.code, 0) << sweep.err;
  CliRun run = runShadowlab("run " + scene + " --set scene:/camera/height=120 --set map.size=256 -o " +
                                (dir / "run").string() + " --cache " + cache,
                            dir);
  ASSERT_EQ(run.code, 0) << run.err;

  const auto rows = shadowlab::loadResultRows((dir / "sweep" / "results.json").string());
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].config, "map.size=256,scene:/camera/height=120");
  EXPECT_EQ(rows[1].config, "map.size=512,scene:/camera/height=120");
  const auto single = shadowlab::loadResultRows((dir / "run" / "metrics.json").string());
  ASSERT_EQ(single.size(), 1u);
  EXPECT_EQ(single[0].config, rows[0].config);
  EXPECT_EQ(single[0].method, rows[0].method);

  const std::string metricsJson = slurp(dir / "run" / "metrics.json");
  EXPECT_NE(metricsJson.find("\"bias.compare\": 0.0005,"), std::string::npos) << metricsJson;
  EXPECT_NE(metricsJson.find("\"tsm.focus\": 0.8,"), std::string::npos) << metricsJson;
  EXPECT_EQ(metricsJson.find("0.0005000000237487257"), std::string::npos) << metricsJson;
  const std::string csv = slurp(dir / "sweep" / "results.csv");
  EXPECT_NE(csv.find(",0.0005,"), std::string::npos) << csv;
  EXPECT_EQ(csv.find("0.00050000002"), std::string::npos) << csv;

  const std::string baseline = (dir / "sweep" / "results.json").string();
  CliRun gate = runShadowlab("gate " + (dir / "run" / "metrics.json").string() + " --baseline " + baseline +
                                 " --json " + (dir / "gate.json").string(),
                             dir);
  ASSERT_EQ(gate.code, 0) << gate.out << gate.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(dir / "gate.json"));
  EXPECT_EQ(report["counts"]["rows_compared"], 1) << report["counts"].dump();
  EXPECT_EQ(report["counts"]["rows_new"], 0) << report["counts"].dump();
  EXPECT_EQ(report["counts"]["rows_not_run"], 1) << report["counts"].dump();

  // The same baseline with the matched row's error_rate halved (a 256 map aliases: it is not 0):
  // the run is now worse than the baseline and the gate fails on that row.
  nlohmann::json doctored = nlohmann::json::parse(slurp(baseline));
  auto& row = doctored["rows"][0];
  ASSERT_GT(row["metrics"]["error_rate"].get<double>(), 0.0);
  row["metrics"]["error_rate"] = row["metrics"]["error_rate"].get<double>() / 2;
  std::ofstream(dir / "doctored.json") << doctored.dump(2);
  CliRun failed = runShadowlab(
      "gate " + (dir / "run" / "metrics.json").string() + " --baseline " + (dir / "doctored.json").string(), dir);
  EXPECT_EQ(failed.code, 1) << failed.out << failed.err;
  EXPECT_NE((failed.out + failed.err).find("error_rate"), std::string::npos) << failed.out << failed.err;

  // A run of a configuration the sweep did not run compares nothing: bad input, not a pass.
  CliRun other = runShadowlab("run " + scene + " --set scene:/camera/height=120 --set map.size=128 -o " +
                                  (dir / "other").string() + " --cache " + cache,
                              dir);
  ASSERT_EQ(other.code, 0) << other.err;
  CliRun unmatched =
      runShadowlab("gate " + (dir / "other" / "metrics.json").string() + " --baseline " + baseline, dir);
  EXPECT_EQ(unmatched.code, 2) << unmatched.out << unmatched.err;
  EXPECT_NE(unmatched.err.find("matches none of the 2 rows of the baseline"), std::string::npos) << unmatched.err;
  fs::remove_all(dir);
}

// Reference samples per pixel: one range (1..1024) for the sweep file, sweep, run, tune and
// reference, checked before the output folder exists; the error names the file and /spp, or the
// option. `sweep --spp 0` is refused, not run at 1.
TEST(SweepNamingCli, SamplesPerPixelOutOfRangeExit2BeforeAnythingIsWritten) {
  const fs::path dir = freshTempDir("shadowlab_naming_spp");
  const std::string out = (dir / "out").string();
  const std::string sweepFile = (dir / "spp.sweep.json").string();
  std::ofstream(sweepFile) << R"({ "scenes": ["sphere_on_plane"], "grid": {"map.size": [256]}, "spp": 2000 })";
  const std::string expected = "expected an integer 1..1024 (reference samples per pixel)";

  CliRun file = runShadowlab("sweep --sweep " + sweepFile + " -o " + out, dir);
  EXPECT_EQ(file.code, 2) << file.err;
  EXPECT_EQ(firstLine(file.err), sweepFile + ": /spp: error: got 2000; " + expected) << file.err;
  EXPECT_FALSE(fs::exists(out)) << "nothing may be created: " << file.err;

  for (const char* command : {"sweep sphere_on_plane --grid map.size=256", "run sphere_on_plane",
                              "tune grazing --max-error 0.01", "reference sphere_on_plane"})
    for (const char* spp : {"0", "2000"}) {
      CliRun r = runShadowlab(std::string(command) + " --spp " + spp + " -o " + out, dir);
      EXPECT_EQ(r.code, 2) << command << " --spp " << spp << ": " << r.err;
      EXPECT_EQ(firstLine(r.err), std::string("--spp: error: got ") + spp + "; " + expected)
          << command << " --spp " << spp;
      EXPECT_FALSE(fs::exists(out)) << command << " --spp " << spp << " created " << out;
      EXPECT_FALSE(fs::exists(dir / ".shadowlab-cache")) << command;
    }
  fs::remove_all(dir);
}

// A key given twice on the command line is refused, naming both arguments (the last one silently
// won before); a --grid or --set that replaces a sweep file's key stays allowed.
TEST(SweepNamingCli, AKeyGivenTwiceIsRefused) {
  const fs::path dir = freshTempDir("shadowlab_naming_twice");
  const std::string out = (dir / "out").string();
  CliRun grid = runShadowlab("sweep sphere_on_plane --grid map.size=256 --grid map.size=512 -o " + out, dir);
  EXPECT_EQ(grid.code, 2) << grid.err;
  EXPECT_EQ(firstLine(grid.err),
            "--grid map.size=512: error: \"map.size\" is swept again (first by --grid map.size=256); expected each "
            "key once")
      << grid.err;
  CliRun set = runShadowlab("sweep sphere_on_plane --set bias.slope=1 --set bias.slope=2 -o " + out, dir);
  EXPECT_EQ(set.code, 2) << set.err;
  EXPECT_EQ(firstLine(set.err),
            "--set bias.slope=2: error: \"bias.slope\" is set again (first by --set bias.slope=1); expected each key "
            "once")
      << set.err;
  CliRun run =
      runShadowlab("run sphere_on_plane --set scene:/camera/width=64 --set scene:/camera/width=32 -o " + out, dir);
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_EQ(firstLine(run.err),
            "--set scene:/camera/width=32: error: \"scene:/camera/width\" is set again (first by --set "
            "scene:/camera/width=64); expected each key once")
      << run.err;
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

}  // namespace sweep_naming_cli_test
