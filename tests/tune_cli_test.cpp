// `shadowlab tune` through the real binary: bad arguments exit 2 naming the argument and write
// nothing; on grazing + contact + thin_wall (160x90) `--max-error 0.002` returns a setting whose
// rows meet the target on all three, that `shadowlab run --method tuned.json` reproduces exactly,
// and that no cheaper point of the dense grid of the same keys beats (--check-grid runs that grid);
// run again it renders nothing; an unreachable target exits 1 with the outputs written.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/results.h"
#include "shadowlab/scenes/io.h"
#include "support/cli.h"

namespace tune_cli_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::CliRun;
using shadowlab::testing::runShadowlab;

namespace {

fs::path tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_tune_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

const std::string kSmall = " --fixed scene:/camera/width=160 --fixed scene:/camera/height=90";

}  // namespace

TEST(TuneCli, BadArgumentsExit2NamingThemAndWriteNothing) {
  const fs::path dir = tempDir("bad");
  const std::string out = (dir / "out").string();
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"grazing", "--max-error/--budget-ms: error: neither given; expected one of them"},
      {"grazing --max-error 0.002 --budget-ms 5", "--max-error/--budget-ms: error: both given"},
      {"grazing --max-error nan", "--max-error: error: got \"nan\"; expected a rate from 0 to 1"},
      {"grazing --max-error -0.1", "--max-error: error: got \"-0.1\""},
      {"grazing --max-error 2", "--max-error: error: got \"2\""},
      {"grazing --budget-ms 0", "--budget-ms: error: got \"0\"; expected a time in milliseconds > 0"},
      {"grazing --max-error 0.002 --keys bias.slope,map.sise",
       "--keys map.sise: error: unknown key \"map.sise\"; expected one of bias.adaptive, bias.compare"},
      {"grazing --max-error 0.002 --keys cull", "--keys cull: error: \"cull\" cannot be tuned (set it with --fixed)"},
      {"grazing --max-error 0.002 --range bias.slope=3:1", "--range bias.slope=3:1: error: empty range 3:1 (lo > hi)"},
      {"grazing --max-error 0.002 --range map.size=300:500", "--range map.size=300:500: error: empty range 300:500"},
      {"grazing --max-error 0.002 --range fit=tight", "--range fit=tight: error: \"fit\" is not a tuned key"},
      {"grazing --max-error 0.002 --range bias.slope=0:1:0", "error: got 0 intervals; expected an integer 1..64"},
      {"grazing --max-error 0.002 --fixed map.size=512",
       "--keys map.size: error: \"map.size\" is both tuned and fixed"},
      {"grazing --max-error 0.002 --max acne=0.1", "--max acne=0.1: error: unknown metric \"acne\"; expected one of"},
      {"grazing --budget-ms 5 --max acne_rate=0.1", "--max: error: given with --budget-ms"},
      {"grazin --max-error 0.002", "grazin"},
  };
  for (const Case& c : cases) {
    CliRun r = runShadowlab("tune " + c.args + " -o '" + out + "'", dir);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("error:"), std::string::npos) << c.args;
    EXPECT_FALSE(fs::exists(out)) << c.args << ": a refused input must write nothing";
    EXPECT_FALSE(fs::exists(dir / ".shadowlab-cache")) << c.args << ": not even the reference cache";
  }
  fs::remove_all(dir);
}

// tune's acceptance case, at 160x90 with a smaller grid (map.size 256..2048, three filters,
// bias.slope 0..2 in steps of 0.25: 108 configurations x 3 scenes).
TEST(TuneCli, MaxErrorOnThreeScenesMeetsTheTargetAndNoCheaperGridPointDoes) {
  const fs::path dir = tempDir("e2e");
  const std::string out = (dir / "out").string(), cache = (dir / "cache").string();
  const std::string args = "tune grazing contact thin_wall --max-error 0.002" + kSmall +
                           " --range map.size=256:2048 --range filter=none,hw2x2,pcf --range bias.slope=0:2:8"
                           " --check-grid --no-report --cache '" +
                           cache + "' -o '" + out + "'";
  CliRun r = runShadowlab(args, dir);
  if (r.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << r.err;
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("bias.slope "), std::string::npos) << "the verdict on stdout: " << r.out;
  EXPECT_NE(r.out.find("The dense grid (324 rows) finds"), std::string::npos) << r.out;

  const auto tune = nlohmann::json::parse(readFile(out + "/tune.json"));
  const auto& robust = tune.at("robust");
  ASSERT_TRUE(robust.at("met").get<bool>()) << tune.at("verdict");
  const std::string config = robust.at("config").get<std::string>();
  // No cheaper configuration of the dense grid meets the target (or the search found it).
  const auto& grid = tune.at("grid_check");
  ASSERT_TRUE(grid.at("met").get<bool>());
  EXPECT_EQ(grid.at("rows").get<size_t>(), 324u);
  EXPECT_LE(robust.at("estimated_ms").get<double>(), grid.at("estimated_ms").get<double>() * 1.05)
      << "search " << config << ", grid " << grid.at("config");
  EXPECT_LT(tune.at("rows_total").get<size_t>(), 324u);

  // The rows of the choice meet the target on all three, and `run --method tuned.json` gives the
  // same numbers: tuned.json is the method the rows measured.
  const auto rows = loadResultRows(out + "/results.json");
  EXPECT_EQ(rows.size(), tune.at("rows_total").get<size_t>());
  for (const char* scene : {"grazing", "contact", "thin_wall"}) {
    const ResultRow* row = nullptr;
    for (const auto& x : rows)
      if (x.scene == scene && x.config == config) row = &x;
    ASSERT_NE(row, nullptr) << scene << " " << config;
    EXPECT_LE(row->metrics.at("error_rate").get<double>(), 0.002) << scene;
    const fs::path runDir = dir / (std::string("run_") + scene);
    CliRun run = runShadowlab(std::string("run ") + scene + " --method '" + out +
                                  "/tuned.json' --set scene:/camera/width=160 --set scene:/camera/height=90 --cache '" +
                                  cache + "' -o '" + runDir.string() + "'",
                              dir);
    ASSERT_EQ(run.code, 0) << run.err;
    const auto single = loadResultRows(runDir.string() + "/metrics.json");
    ASSERT_EQ(single.size(), 1u);
    EXPECT_EQ(single[0].metrics, row->metrics) << scene;
  }
  EXPECT_TRUE(fs::is_regular_file(out + "/tune.html"));
  EXPECT_NE(readFile(out + "/tune.html").find("<svg"), std::string::npos);
  for (const char* scene : {"grazing", "contact", "thin_wall"})
    EXPECT_TRUE(fs::is_regular_file(out + "/figures/tune_triptych_" + scene + ".png")) << scene;

  // Again: every row comes from rows.jsonl, the same choice.
  CliRun again = runShadowlab(args, dir);
  ASSERT_EQ(again.code, 0) << again.err;
  const auto tune2 = nlohmann::json::parse(readFile(out + "/tune.json"));
  EXPECT_EQ(tune2.at("rows_run").get<size_t>(), 0u);
  EXPECT_EQ(tune2.at("grid_check").at("rows_run").get<size_t>(), 0u);
  EXPECT_EQ(tune2.at("robust").at("config"), robust.at("config"));
  fs::remove_all(dir);
}

TEST(TuneCli, UnreachableTargetExits1WithAVerdictAndTheOutputs) {
  const fs::path dir = tempDir("unreachable");
  const std::string out = (dir / "out").string();
  CliRun r = runShadowlab("tune grazing thin_wall --max-error 0.00001" + kSmall +
                              " --range map.size=256:512 --range filter=none --range bias.slope=1:2:1 --no-report"
                              " --cache '" +
                              (dir / "cache").string() + "' -o '" + out + "'",
                          dir);
  if (r.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << r.err;
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.out.find("no setting meets 1e-05 on grazing, thin_wall; best found"), std::string::npos) << r.out;
  for (const char* f : {"tuned.json", "tune.json", "tune.html", "results.json", "results.csv"})
    EXPECT_TRUE(fs::is_regular_file(out + "/" + f)) << f;
  fs::remove_all(dir);
}

// --max takes the visibility errors of compare/METRICS.md "Soft shadows" as well as the class
// rates: known names reach the value's check, unknown ones are refused with the whole list.
TEST(TuneCli, MaxAcceptsTheSoftShadowMetrics) {
  const fs::path dir = tempDir("soft_max");
  const std::string out = (dir / "out").string();
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--max penumbra_mae=1.5", "--max penumbra_mae=1.5: error: got \"1.5\"; expected a number from 0 to 1"},
      {"--max over_shadowing=-1", "--max over_shadowing=-1: error: got \"-1\""},
      {"--max penumbra_hard_rate=0.1 --max penumbra_hard_rate=0.2", "--max penumbra_hard_rate: error: given twice"},
      {"--max penumbra=0.1", "--max penumbra=0.1: error: unknown metric \"penumbra\"; expected one of acne_rate, "},
  };
  for (const Case& c : cases) {
    CliRun r = runShadowlab("tune grazing --max-error 0.002 " + c.args + " -o '" + out + "'", dir);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
  CliRun unknown = runShadowlab("tune grazing --max-error 0.002 --max penumbra=0.1 -o '" + out + "'", dir);
  for (const char* name : {"penumbra_wide_rate", "penumbra_hard_rate", "lit_mae", "penumbra_mae", "penumbra_rmse",
                           "umbra_rmse", "over_shadowing", "under_shadowing"})
    EXPECT_NE(unknown.err.find(name), std::string::npos) << name << " missing from the list: " << unknown.err;

  // On grazing alone (a hard sun: no penumbra, penumbra_mae null on its row) --max penumbra_mae
  // constrains no scene: a target in name only, refused once the first configuration is measured.
  const std::string small =
      " --fixed scene:/camera/width=64 --fixed scene:/camera/height=36 --range map.size=512:512"
      " --range filter=none --range bias.slope=1,2 --no-report --light-samples 16 --cache '" +
      (dir / "cache").string() + "' -o '" + out + "'";
  CliRun vacuous = runShadowlab("tune grazing --max-error 0.5 --max penumbra_mae=0.02 --max lit_mae=0.5" + small, dir);
  if (vacuous.code == 3) GTEST_SKIP() << "no Vulkan device (shadowlab exit 3): " << vacuous.err;
  EXPECT_EQ(vacuous.code, 2) << vacuous.err;
  EXPECT_NE(vacuous.err.find("--max penumbra_mae=0.02: error: constrains none of the scenes: grazing (penumbra_pixels "
                             "0: their truth has no pixel of that region); expected a target some scene measures"),
            std::string::npos)
      << vacuous.err;
  EXPECT_FALSE(fs::exists(out + "/tune.json"));
  fs::remove_all(out);
  // Beside soft_post (a sphere light) it constrains that scene; grazing is named in a note. --max
  // alone is a target (error_rate free).
  CliRun r = runShadowlab("tune grazing soft_post --max penumbra_mae=0.9 --max lit_mae=0.5" + small, dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("tune: note: --max penumbra_mae constrains nothing on grazing (penumbra_pixels 0: their truth "
                       "has no pixel of that region): met there by definition"),
            std::string::npos)
      << r.err;
  const auto tune = nlohmann::json::parse(readFile(out + "/tune.json"));
  EXPECT_TRUE(tune.at("robust").at("met").get<bool>()) << tune.dump();
  const auto rows = loadResultRows(out + "/results.json");
  ASSERT_FALSE(rows.empty());
  for (const auto& row : rows) {
    if (row.scene == "grazing") {
      EXPECT_EQ(row.metrics.at("penumbra_pixels"), 0);
      EXPECT_TRUE(row.metrics.at("penumbra_mae").is_null());
    } else {
      EXPECT_GT(row.metrics.at("penumbra_pixels").get<double>(), 0);
      EXPECT_LE(row.metrics.at("penumbra_mae").get<double>(), 0.9);
    }
    EXPECT_LE(row.metrics.at("lit_mae").get<double>(), 0.5);
  }
  EXPECT_NE(tune.dump().find("penumbra_mae"), std::string::npos) << "the target in tune.json";
  fs::remove_all(dir);
}

}  // namespace tune_cli_test
