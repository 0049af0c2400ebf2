// Failure frontiers (compare/SWEEPS.md): the frontier function on synthetic numbers with exact
// answers, the walk direction taken from the scene's declared failure values, and an elevation sweep
// of `grazing` through the real binary where a constant bias alone must break at a higher sun than
// the same constant plus slope-scaled bias.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/sweep_frontier.h"
#include "shadowlab/scenes/error.h"

namespace sweep_frontier_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

const std::string kBinary = SHADOWLAB_BINARY;
const std::string kElevation = "scene:/lights/0/elevation_deg";

SweepPlan grazingPlan(const std::vector<std::string>& grid) {
  SweepSpec spec;
  spec.scenes = {"grazing"};
  for (const auto& g : grid) spec.grid.push_back(parseGridArgument(g));
  return planSweep(spec);
}

// One synthetic row per configuration: `metric(config values)` as error_rate (null: no metric).
std::vector<ResultRow> rowsOf(const SweepPlan& plan,
                              const std::function<nlohmann::json(const std::map<std::string, std::string>&)>& metric) {
  std::vector<ResultRow> rows;
  for (const auto& c : plan.configs) {
    std::map<std::string, std::string> v(c.values.begin(), c.values.end());
    ResultRow r;
    r.scene = plan.sceneNames.at(0);
    r.config = c.config;
    r.light = "sun";
    r.metrics["error_rate"] = metric(v);
    rows.push_back(r);
  }
  return rows;
}

const nlohmann::json& frontierOf(const nlohmann::json& frontiers, const std::string& method) {
  for (const auto& f : frontiers)
    if (f["method"] == method) return f;
  ADD_FAILURE() << "no frontier for " << method << " in " << frontiers.dump();
  static const nlohmann::json none;
  return none;
}

}  // namespace

TEST(FrontierFunction, ExactAnswers) {
  // Holds: nothing strictly above the threshold (equal is not a failure).
  Frontier h = findFrontier({0, 0.005, 0.01}, 0.01);
  EXPECT_TRUE(h.holds);
  // Breaks at the first value.
  Frontier first = findFrontier({0.2, 0.3}, 0.01);
  EXPECT_FALSE(first.holds);
  EXPECT_EQ(first.breakIndex, 0u);
  EXPECT_FALSE(first.recovers);
  // Breaks in the middle.
  Frontier mid = findFrontier({0, 0.001, 0.02, 0.5}, 0.01);
  EXPECT_FALSE(mid.holds);
  EXPECT_EQ(mid.breakIndex, 2u);
  EXPECT_FALSE(mid.recovers);
  // Non-monotone: the first failure is the frontier; the dip after it is reported, not hidden.
  Frontier nm = findFrontier({0, 0.02, 0.005, 0.03}, 0.01);
  EXPECT_FALSE(nm.holds);
  EXPECT_EQ(nm.breakIndex, 1u);
  EXPECT_TRUE(nm.recovers);
  EXPECT_TRUE(findFrontier({}, 0.01).holds);
}

TEST(FrontierFunction, WalksTheDeclaredFailureDirectionWhateverTheGridOrder) {
  // grazing declares elevation from 45 (easy) down to 1 (hard); the grid gives them shuffled.
  SweepPlan plan = grazingPlan({kElevation + "=4,60,1,30", "bias.slope=0,2"});
  auto rows = rowsOf(plan, [](const std::map<std::string, std::string>& v) -> nlohmann::json {
    double e = std::stod(v.at(kElevation));
    if (v.at("bias.slope") == "0") return e <= 30 ? 0.05 : 0.0;  // breaks at 30, holds to 60
    return e <= 1 ? 0.02 : 0.001;                                // breaks at 1, holds to 4
  });
  nlohmann::json fr = computeFrontiers(plan, rows, "error_rate", 0.01);
  ASSERT_EQ(fr.size(), 2u) << fr.dump(1);
  const auto& s0 = frontierOf(fr, "bias.slope=0");
  EXPECT_EQ(s0["direction"], "decreasing");
  EXPECT_EQ(s0["breaks_at"], 30.0);
  EXPECT_EQ(s0["holds_to"], 60.0);
  ASSERT_EQ(s0["points"].size(), 4u);
  EXPECT_EQ(s0["points"][0]["value"], 60.0);
  EXPECT_EQ(s0["points"][3]["value"], 1.0);
  const auto& s2 = frontierOf(fr, "bias.slope=2");
  EXPECT_EQ(s2["breaks_at"], 1.0);
  EXPECT_EQ(s2["holds_to"], 4.0);
  for (const auto& f : fr) std::printf("  %s\n", f["sentence"].get<std::string>().c_str());
}

// scene:failure is walked like the pointer it stands for: grazing's declared elevation, from high
// to low, and the sentence names the declared parameter.
TEST(FrontierFunction, SceneFailureKeyWalksTheDeclaredParameter) {
  SweepPlan plan = grazingPlan({"scene:failure=4,60,30", "bias.slope=0,2"});
  auto rows = rowsOf(plan, [](const std::map<std::string, std::string>& v) -> nlohmann::json {
    double e = std::stod(v.at("scene:failure"));
    return v.at("bias.slope") == "0" && e <= 30 ? 0.2 : 0.001;
  });
  nlohmann::json fr = computeFrontiers(plan, rows, "error_rate", 0.01);
  ASSERT_EQ(fr.size(), 2u) << fr.dump(1);
  const auto& s0 = frontierOf(fr, "bias.slope=0");
  EXPECT_EQ(s0["parameter"], "scene:failure");
  EXPECT_EQ(s0["pointer"], "/lights/0/elevation_deg");
  EXPECT_EQ(s0["direction"], "decreasing");
  EXPECT_EQ(s0["breaks_at"], 30.0);
  EXPECT_EQ(s0["holds_to"], 60.0);
  EXPECT_EQ(s0["sentence"], "bias.slope=0: breaks at elevation_deg=30 (error_rate 20% > 1%), holds to 60");
  EXPECT_TRUE(frontierOf(fr, "bias.slope=2")["holds"].get<bool>());
}

TEST(FrontierFunction, HoldsBreaksAtFirstMissingAndNoSceneKey) {
  SweepPlan plan = grazingPlan({kElevation + "=60,30,8", "bias.slope=0,1,2"});
  auto rows = rowsOf(plan, [](const std::map<std::string, std::string>& v) -> nlohmann::json {
    if (v.at("bias.slope") == "0") return 0.5;                                 // broken everywhere
    if (v.at("bias.slope") == "1") return 0.0;                                 // holds everywhere
    return v.at(kElevation) == "30" ? nlohmann::json() : nlohmann::json(0.0);  // a missing metric
  });
  nlohmann::json fr = computeFrontiers(plan, rows, "error_rate", 0.01);
  ASSERT_EQ(fr.size(), 3u);
  const auto& broken = frontierOf(fr, "bias.slope=0");
  EXPECT_FALSE(broken["holds"]);
  EXPECT_EQ(broken["breaks_at"], 60.0);
  EXPECT_TRUE(broken["holds_to"].is_null());
  const auto& holds = frontierOf(fr, "bias.slope=1");
  EXPECT_TRUE(holds["holds"]);
  EXPECT_TRUE(holds["breaks_at"].is_null());
  EXPECT_EQ(holds["holds_to"], 8.0);
  const auto& gap = frontierOf(fr, "bias.slope=2");
  EXPECT_EQ(gap["points"].size(), 2u);
  EXPECT_EQ(gap["missing"], nlohmann::json::array({"30"}));

  // No scene: key (or a single value of one): no frontiers at all, and no error.
  SweepPlan noScene = grazingPlan({"bias.slope=0,2", "scene:/camera/width=480"});
  EXPECT_TRUE(computeFrontiers(noScene, rowsOf(noScene, [](const auto&) { return 0.5; }), "error_rate", 0.01).empty());
}

TEST(FrontierFunction, AnUndeclaredSceneParameterIsWalkedInGridOrder) {
  SweepPlan plan = grazingPlan({"scene:/camera/vfov_deg=30,70,50"});
  auto rows = rowsOf(plan, [](const std::map<std::string, std::string>& v) -> nlohmann::json {
    return v.at("scene:/camera/vfov_deg") == "50" ? 0.5 : 0.0;
  });
  nlohmann::json fr = computeFrontiers(plan, rows, "error_rate", 0.01);
  ASSERT_EQ(fr.size(), 1u);
  EXPECT_EQ(fr[0]["direction"], "grid order");
  EXPECT_EQ(fr[0]["breaks_at"], 50.0);
  EXPECT_EQ(fr[0]["holds_to"], 70.0);
}

TEST(FrontierFunction, BadFrontierSettingsAreInputErrors) {
  SweepSpec spec;
  spec.scenes = {"grazing"};
  spec.frontierThreshold = -0.5;
  try {
    planSweep(spec);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--frontier-threshold"), std::string::npos) << e.what();
  }
  spec.frontierThreshold = std::nan("");
  EXPECT_THROW(planSweep(spec), InputError);
  spec.frontierThreshold = 0.01;
  spec.frontierMetric = "acnerate";
  try {
    planSweep(spec);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown metric \"acnerate\""), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("acne_rate"), std::string::npos) << e.what();
  }
}

namespace {

int runBinary(const std::vector<std::string>& args, const std::string& errPath) {
  pid_t pid = ::fork();
  if (pid == 0) {
    FILE* e = std::freopen(errPath.c_str(), "w", stderr);
    FILE* o = std::freopen((errPath + ".out").c_str(), "w", stdout);
    (void)e;
    (void)o;
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_frontier_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

}  // namespace

TEST(FrontierCli, BadFrontierFlagsExitTwoAndWriteNothing) {
  std::string dir = tempDir("bad");
  std::string out = dir + "/out";
  EXPECT_EQ(runBinary({kBinary, "sweep", "grazing", "--frontier-threshold", "abc", "-o", out}, dir + "/e1"), 2);
  EXPECT_NE(slurp(dir + "/e1").find("--frontier-threshold: error: got \"abc\""), std::string::npos)
      << slurp(dir + "/e1");
  EXPECT_EQ(runBinary({kBinary, "sweep", "grazing", "--frontier-metric", "nope", "-o", out}, dir + "/e2"), 2);
  EXPECT_NE(slurp(dir + "/e2").find("--frontier-metric: error: unknown metric \"nope\""), std::string::npos)
      << slurp(dir + "/e2");
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

// The frontier's defining case: an elevation sweep on grazing finds an acne frontier for every bias method, and a
// constant comparison bias alone breaks at a higher sun than the same constant plus slope bias.
TEST(FrontierCli, GrazingElevationSweepFindsAcneFrontiersSlopeBiasHoldsLower) {
  std::string dir = tempDir("grazing");
  std::string out = dir + "/out";
  auto t0 = std::chrono::steady_clock::now();
  int rc =
      runBinary({kBinary, "sweep", "grazing", "--grid", kElevation + "=60,30,15,8,4,2,1", "--grid",
                 "bias.slope=0,0.25,2", "--set", "bias.compare=0.0005", "--set", "scene:/camera/width=480", "--set",
                 "scene:/camera/height=270", "--frontier-metric", "acne_rate", "--cache", dir + "/cache", "-o", out},
                dir + "/err");
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(rc, 0) << slurp(dir + "/err");
  std::printf("  sweep of 21 rows with report: %.1f s\n", seconds);
  nlohmann::json results = nlohmann::json::parse(slurp(out + "/results.json"));
  const nlohmann::json& fr = results["frontiers"];
  ASSERT_EQ(fr.size(), 3u) << fr.dump(1);
  for (const auto& f : fr) {
    std::printf("  %s  [", f["sentence"].get<std::string>().c_str());
    for (const auto& p : f["points"]) std::printf(" %g:%.4f", p["value"].get<double>(), p["metric"].get<double>());
    std::printf(" ]\n");
    EXPECT_EQ(f["metric"], "acne_rate");
    EXPECT_EQ(f["direction"], "decreasing");
  }
  // Measured at 480x270: the constant alone breaks at 15 deg (acne 22%), with slope 0.25
  // at 8 deg (10%); slope 2 keeps acne under 0.1% down to 1 deg. Both weak biases must have a
  // frontier, the constant's must be the higher sun, and the strong slope bias must fail no earlier.
  const auto& constant = frontierOf(fr, "bias.slope=0");
  const auto& slope = frontierOf(fr, "bias.slope=0.25");
  const auto& strong = frontierOf(fr, "bias.slope=2");
  EXPECT_FALSE(constant["holds"]) << "no acne frontier for the constant bias";
  EXPECT_FALSE(slope["holds"]) << "no acne frontier for the constant + slope bias";
  ASSERT_TRUE(constant["breaks_at"].is_number() && slope["breaks_at"].is_number());
  EXPECT_GT(constant["breaks_at"].get<double>(), slope["breaks_at"].get<double>());
  if (!strong["holds"].get<bool>()) {
    EXPECT_LE(strong["breaks_at"].get<double>(), slope["breaks_at"].get<double>());
  }
  // The report tabulates them and charts them.
  std::string html = slurp(out + "/report.html");
  EXPECT_NE(html.find("Failure frontiers"), std::string::npos);
  EXPECT_NE(html.find(constant["sentence"].get<std::string>().substr(0, 20)), std::string::npos);
  EXPECT_TRUE(fs::exists(out + "/figures/frontiers.svg")) << slurp(out + "/figures/charts.log");
  fs::remove_all(dir);
}

}  // namespace sweep_frontier_test
