// shadowlab tune's search with an injected fake runner (no renderer): on a known landscape of
// acne (falls with the slope bias), leaks (rise with it) and aliasing (falls with the map size,
// depends on the filter) the search must find what the dense grid of the same keys finds (the
// cheapest configuration meeting the target on every scene; under --budget-ms the lowest
// worst-case error) with a fraction of its rows; its rows go through the sweep journal, so a
// second run renders nothing and an interrupted one resumes without running a row twice. Also the
// cost model's arithmetic and planTune's refusals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "shadowlab/compare/method_cost.h"
#include "shadowlab/compare/set_arguments.h"
#include "shadowlab/compare/tune.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "support/input_error.h"

namespace tune_search_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::inputErrorOf;

namespace {

// Per scene: acne below `acneUntil` (quadratic), leaks above `leakFrom` (linear, larger on coarse
// maps), aliasing ~ 1/map.size scaled by the filter. Smooth U-curves in the slope bias, monotone
// in the map size: the shape the search assumes.
struct SceneShape {
  double acneUntil, acneGain, leakFrom, leakGain, aliasing;
};
SceneShape shapeOf(const std::string& scene) {
  if (scene == "grazing") return {1.25, 0.08, 3.0, 0.002, 0.6};
  if (scene == "contact") return {0.5, 0.02, 1.5, 0.004, 0.4};
  return {0.25, 0.02, 1.0, 0.003, 1.5};  // thin_wall
}
double filterFactor(const Method& m) {
  switch (m.filter) {
    case Filter::None: return 1.0;
    case Filter::Hw2x2: return 0.8;
    case Filter::Bilinear4: return 0.85;
    case Filter::Pcf: return 0.7 + 0.02 * m.filterSize;
    case Filter::Poisson: return 0.75;
    case Filter::Vsm:
    case Filter::Evsm2:
    case Filter::Evsm4:
    case Filter::Msm: return 0.9;  // dearer (the moments pass) and no better here
    case Filter::Pcss:
    case Filter::Dpcf: return 0.95;  // soft filters: dearer, and these scenes' lights are hard
  }
  return 1.0;
}
nlohmann::json fakeMetrics(const std::string& scene, const Method& m) {
  const SceneShape s = shapeOf(scene);
  const double b = m.biasSlope;
  const double acne =
      s.acneGain * std::pow(std::max(0.0, s.acneUntil - b), 2.0) * (m.filter == Filter::Pcf ? 0.5 : 1.0);
  const double leak = s.leakGain * std::max(0.0, b - s.leakFrom) * std::sqrt(1024.0 / m.mapSize);
  const double aliasing = s.aliasing / m.mapSize * filterFactor(m);
  return {{"error_rate", acne + leak + aliasing},
          {"acne_rate", acne},
          {"leak_rate", leak},
          {"aliasing_rate", aliasing},
          {"coverage_rate", 0.0},
          {"other_rate", 0.0}};
}

class FakeRunner : public SweepRunner {
 public:
  std::map<std::string, int> runs;  // scene | config text -> times run
  int total = 0;
  std::atomic<bool>* stop = nullptr;
  int stopAfter = -1;
  SweepRunOutput run(const Scene& scene, const Method& m, const std::string&, const std::string&) override {
    ++runs[scene.name + "|" + methodToJson(m).dump()];
    if (++total == stopAfter && stop) stop->store(true);
    SweepRunOutput out;
    out.metrics = fakeMetrics(scene.name, m);
    out.timings = {{"shadow_gpu_ms", 1.0}, {"camera_gpu_ms", 2.0}};
    return out;
  }
  bool writeTriptych(const Scene&, const Method&, const std::string&, const std::string&) override { return false; }
};

// The journal fsyncs every row: on a RAM disk (when there is one) the thousands of grid rows take
// milliseconds instead of seconds.
std::string tempDir(const std::string& name) {
  std::error_code ec;
  const fs::path base = fs::is_directory("/dev/shm", ec) && ::access("/dev/shm", W_OK) == 0 ? fs::path("/dev/shm")
                                                                                            : fs::temp_directory_path();
  fs::path d = base / ("shadowlab_tune_search_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d.string();
}

TuneSpec threeScenes() {
  TuneSpec spec;
  spec.scenes = {"grazing", "contact", "thin_wall"};
  return spec;
}

TuneOptions quiet(const std::string& dir, bool grid = true) {
  TuneOptions o;
  o.outDir = dir;
  o.progress = nullptr;
  o.writeReport = false;
  o.checkGrid = grid;
  return o;
}

}  // namespace

// --max-error: the search's choice is the dense grid's cheapest configuration meeting the target
// (the grid is run through the same runner and judged by the same cost model), for several targets.
TEST(TuneSearch, MaxErrorFindsTheDenseGridsCheapestWithAFifthOfItsRows) {
  // One folder: the grid's rows (the same for every target) are rendered once, then resumed.
  const std::string dir = tempDir("max");
  int met = 0;
  for (double target : {0.0005, 0.001, 0.002, 0.004, 0.008}) {
    TuneSpec spec = threeScenes();
    spec.maxError = target;
    TunePlan plan = planTune(spec);
    // bias.slope 0:4:16, every filter of kinds.h, map.size 256..4096
    EXPECT_EQ(plan.gridConfigurations, 17u * filterKinds().size() * 5u);
    FakeRunner runner;
    TuneResult r = runTune(plan, runner, quiet(dir));
    ASSERT_TRUE(r.grid.checked);
    EXPECT_EQ(r.gridRows, 3u * plan.gridConfigurations);
    // The count is honest: each distinct row rendered once, by the search or the grid.
    EXPECT_EQ(size_t(runner.total), r.rowsRun + r.grid.rowsRun);
    for (const auto& [key, n] : runner.runs) EXPECT_EQ(n, 1) << key;
    // The search's rows (every scene together and each alone) against the grid's.
    EXPECT_LE(double(r.rowsTotal), 0.2 * double(r.gridRows)) << target << ": " << r.rowsTotal << " of " << r.gridRows;
    EXPECT_EQ(r.robust.met, r.grid.met) << target << ": " << r.verdict;
    if (!r.grid.met) continue;
    ++met;
    ASSERT_TRUE(r.robust.met);
    const TuneEvaluation& chosen = r.evaluations.at(size_t(r.robust.evaluation));
    // Its rows meet the target on every scene (checked against the landscape, not the search's bookkeeping).
    for (const char* scene : {"grazing", "contact", "thin_wall"})
      EXPECT_LE(fakeMetrics(scene, chosen.method).at("error_rate").get<double>(), target)
          << scene << " " << chosen.config;
    EXPECT_LE(r.robust.costMs, r.grid.costMs * 1.05)
        << target << ": search " << chosen.config << ", grid " << r.grid.config;
    EXPECT_EQ(r.robust.costMs, r.grid.costMs) << "on a landscape of the assumed shape it is the grid's best";
    // Per scene: each alone meets the target at no more cost than all together.
    ASSERT_EQ(r.perScene.size(), 3u);
    for (const auto& c : r.perScene) {
      EXPECT_TRUE(c.met) << c.scope;
      EXPECT_LE(c.costMs, r.robust.costMs) << c.scope;
    }
    // tuned.json is the choice as a method file.
    const Method tuned = loadMethodFile(dir + "/tuned.json");
    EXPECT_EQ(tuned.mapSize, chosen.method.mapSize);
    EXPECT_EQ(tuned.biasSlope, chosen.method.biasSlope);
    EXPECT_EQ(tuned.filter, chosen.method.filter);
  }
  EXPECT_GE(met, 3) << "most targets are reachable on this landscape";
  fs::remove_all(dir);
}

// --budget-ms: the lowest worst-case error whose estimated cost fits, as the dense grid finds it.
TEST(TuneSearch, BudgetFindsTheDenseGridsMostAccurateWithinIt) {
  const std::string dir = tempDir("budget");
  for (double budget : {1.0, 6.0, 8.0, 12.0, 40.0}) {
    TuneSpec spec = threeScenes();
    spec.budgetMs = budget;
    TunePlan plan = planTune(spec);
    FakeRunner runner;
    TuneResult r = runTune(plan, runner, quiet(dir));
    EXPECT_EQ(r.robust.met, r.grid.met) << budget << ": " << r.verdict;
    if (budget == 1.0) {
      // Below the cheapest configuration (grazing at 960x540: ~5.3 ms): nothing fits, said so.
      EXPECT_FALSE(r.robust.met);
      EXPECT_NE(r.verdict.find("nothing fits 1 ms: the cheapest configuration"), std::string::npos) << r.verdict;
      continue;
    }
    ASSERT_TRUE(r.robust.met) << budget << ": " << r.verdict;
    EXPECT_LE(r.robust.costMs, budget);
    EXPECT_LE(r.robust.worstError, r.grid.worstError * 1.05) << budget << ": grid " << r.grid.config;
    EXPECT_LE(double(r.rowsTotal), 0.2 * double(r.gridRows)) << budget;
  }
  fs::remove_all(dir);
}

// A target nothing meets: not met, the best found named in the verdict, every output still written.
TEST(TuneSearch, UnreachableTargetSaysSoAndStillWritesTheOutputs) {
  const std::string dir = tempDir("unreachable");
  TuneSpec spec = threeScenes();
  spec.maxError = 1e-5;
  TunePlan plan = planTune(spec);
  FakeRunner runner;
  TuneResult r = runTune(plan, runner, quiet(dir, false));
  EXPECT_FALSE(r.robust.met);
  ASSERT_GE(r.robust.evaluation, 0);
  EXPECT_NE(r.verdict.find("no setting meets 1e-05 on grazing, contact, thin_wall; best found"), std::string::npos)
      << r.verdict;
  for (const char* f : {"tuned.json", "tune.json", "tune.html", "results.json", "results.csv", "rows.jsonl"})
    EXPECT_TRUE(fs::is_regular_file(dir + "/" + f)) << f;
  const auto j = nlohmann::json::parse(readFile(dir + "/tune.json"));
  EXPECT_FALSE(j.at("robust").at("met").get<bool>());
  EXPECT_EQ(j.at("rows_total").get<size_t>(), r.rowsTotal);
  // results.json holds exactly the evaluated rows.
  EXPECT_EQ(loadResultRows(dir + "/results.json").size(), r.rowsTotal);
  fs::remove_all(dir);
}

// The rows are the sweep journal's: a second run renders nothing and chooses the same; an
// interrupted run resumes without rendering any row twice.
TEST(TuneSearch, ResumesFromTheJournalWithoutRenderingARowTwice) {
  const std::string dir = tempDir("resume");
  TuneSpec spec = threeScenes();
  spec.maxError = 0.002;
  TunePlan plan = planTune(spec);
  std::atomic<bool> stop{false};
  FakeRunner first;
  first.stop = &stop;
  first.stopAfter = 20;
  TuneOptions o = quiet(dir, false);
  o.stop = &stop;
  TuneResult r1 = runTune(plan, first, o);
  EXPECT_TRUE(r1.interrupted);
  EXPECT_EQ(first.total, 20);
  EXPECT_FALSE(fs::exists(dir + "/tune.json")) << "an interrupted tune writes no verdict";

  stop = false;
  FakeRunner second;
  TuneResult r2 = runTune(plan, second, quiet(dir, false));
  ASSERT_FALSE(r2.interrupted);
  EXPECT_EQ(r2.rowsResumed, 20u);
  for (const auto& [key, n] : first.runs) EXPECT_EQ(second.runs.count(key), 0u) << key << " rendered again";
  const std::string tuneJson = readFile(dir + "/tune.json");

  FakeRunner third;
  TuneResult r3 = runTune(plan, third, quiet(dir, false));
  EXPECT_EQ(third.total, 0);
  EXPECT_EQ(r3.rowsRun, 0u);
  EXPECT_EQ(r3.rowsTotal, r2.rowsTotal);
  ASSERT_GE(r3.robust.evaluation, 0);
  EXPECT_EQ(r3.evaluations[size_t(r3.robust.evaluation)].config, r2.evaluations[size_t(r2.robust.evaluation)].config);
  auto a = nlohmann::json::parse(tuneJson), b = nlohmann::json::parse(readFile(dir + "/tune.json"));
  for (const char* k : {"config", "sentence", "worst_error_rate", "estimated_ms", "rows_asked"})
    EXPECT_EQ(a.at("robust").at(k), b.at("robust").at(k)) << k << ": same rows, same choice, same words";
  EXPECT_EQ(b.at("robust").at("rows_run"), 0);
  EXPECT_EQ(a.at("evaluations"), b.at("evaluations"));
  fs::remove_all(dir);
}

// Several bias keys at once (coordinate descent), filter.size only where filter=pcf.
TEST(TuneSearch, TwoBiasKeysAndADependentKeyStayWithinTheGrid) {
  const std::string dir = tempDir("twokeys");
  TuneSpec spec = threeScenes();
  spec.maxError = 0.002;
  spec.keys = {"bias.slope", "bias.normal", "filter", "filter.size", "map.size"};
  spec.ranges = {"bias.slope=0:4:8", "bias.normal=0:2:4", "filter=none,pcf", "filter.size=3:5", "map.size=512:2048"};
  TunePlan plan = planTune(spec);
  // filter none x one held filter.size + pcf x two sizes = 3 combinations.
  EXPECT_EQ(plan.gridConfigurations, 9u * 5u * 3u * 3u);
  FakeRunner runner;
  TuneResult r = runTune(plan, runner, quiet(dir));
  ASSERT_TRUE(r.robust.met) << r.verdict;
  EXPECT_LE(r.robust.costMs, r.grid.costMs * 1.05);
  for (const auto& e : r.evaluations)
    if (e.method.filter != Filter::Pcf) {
      EXPECT_EQ(e.method.filterSize, 3) << e.config;
    }
  fs::remove_all(dir);
}

TEST(TuneCostModel, GrowsWithWhatTheMethodDoes) {
  TuneSpec spec = threeScenes();
  spec.maxError = 0.01;
  const TunePlan plan = planTune(spec);
  const Scene& scene = plan.sweep.variants.at(0);
  Method m;
  auto cost = [&](const Method& x) { return estimateMethodCost(scene, x, ""); };
  const MethodCost base = cost(m);
  EXPECT_EQ(base.layers, 1);
  EXPECT_EQ(base.pixels, double(scene.camera.width) * scene.camera.height);
  EXPECT_DOUBLE_EQ(base.mapBytes, 2048.0 * 2048.0 * 4.0);
  EXPECT_DOUBLE_EQ(base.estimatedMs, base.shadowMs + base.lookupMs);
  Method big = m;
  big.mapSize = 4096;
  EXPECT_GT(cost(big).shadowMs, 3.9 * base.shadowMs);  // texels dominate the shadow pass
  Method d16 = m;
  d16.mapFormat = DepthFormat::D16;
  EXPECT_DOUBLE_EQ(cost(d16).mapBytes, base.mapBytes / 2);
  Method pcf3 = m, pcf5 = m, hw = m, poisson = m;
  pcf3.filter = pcf5.filter = Filter::Pcf;
  pcf5.filterSize = 5;
  hw.filter = Filter::Hw2x2;
  poisson.filter = Filter::Poisson;
  EXPECT_EQ(cost(hw).estimatedMs, base.estimatedMs);
  EXPECT_GT(cost(pcf3).lookupMs, base.lookupMs);
  EXPECT_GT(cost(pcf5).lookupMs, cost(pcf3).lookupMs);
  EXPECT_EQ(cost(pcf5).tapsPerPixel, 25);
  EXPECT_GT(cost(poisson).lookupMs, cost(pcf3).lookupMs);
  // Filterable maps pay a moments pass (more with 4 moments and a wider blur) and its memory.
  Method vsm = m, msm = m, vsmWide = m;
  vsm.filter = vsmWide.filter = Filter::Vsm;
  msm.filter = Filter::Msm;
  vsmWide.filterBlur = 6;
  EXPECT_GT(cost(vsm).shadowMs, 10 * base.shadowMs);
  EXPECT_GT(cost(msm).shadowMs, cost(vsm).shadowMs);
  EXPECT_GT(cost(vsmWide).shadowMs, cost(vsm).shadowMs);
  EXPECT_DOUBLE_EQ(cost(vsm).mapBytes, base.mapBytes + 2048.0 * 2048.0 * 8.0);
  EXPECT_DOUBLE_EQ(cost(msm).mapBytes, base.mapBytes + 2048.0 * 2048.0 * 16.0);
  Method cascades = m;
  cascades.fit = Fit::Cascades;
  cascades.cascadeCount = 4;
  EXPECT_EQ(cost(cascades).layers, 4);
  EXPECT_DOUBLE_EQ(cost(cascades).shadowMs, 4 * base.shadowMs);
  Method sdsm = cascades;  // one layer per slice as well
  sdsm.fit = Fit::Sdsm;
  EXPECT_EQ(cost(sdsm).layers, 4);
  EXPECT_DOUBLE_EQ(cost(sdsm).shadowMs, cost(cascades).shadowMs);
  // Deterministic: the same inputs, the same bits.
  EXPECT_EQ(cost(pcf5).estimatedMs, cost(pcf5).estimatedMs);
}

TEST(TunePlan, RefusesBadArgumentsNamingThem) {
  struct Case {
    std::function<void(TuneSpec&)> edit;
    std::string message;
  };
  const std::vector<Case> cases = {
      {[](TuneSpec& s) { s.maxError = NAN; }, "--max-error/--budget-ms: error: neither given"},
      {[](TuneSpec& s) { s.budgetMs = 10; }, "--max-error/--budget-ms: error: both given"},
      {[](TuneSpec& s) { s.maxError = -1; }, "--max-error: error: got -1"},
      {[](TuneSpec& s) { s.keys = {"bias.slop"}; },
       "--keys bias.slop: error: unknown key \"bias.slop\"; expected one of"},
      {[](TuneSpec& s) { s.keys = {"cull"}; }, "--keys cull: error: \"cull\" cannot be tuned"},
      {[](TuneSpec& s) {
         s.keys = {"map.size", "map.size"};
       },
       "\"map.size\" given twice"},
      {[](TuneSpec& s) { s.ranges = {"bias.slope=2:1"}; }, "--range bias.slope=2:1: error: empty range 2:1 (lo > hi)"},
      {[](TuneSpec& s) { s.ranges = {"map.size=300:500"}; }, "--range map.size=300:500: error: empty range"},
      {[](TuneSpec& s) { s.ranges = {"fit=sphere"}; }, "--range fit=sphere: error: \"fit\" is not a tuned key"},
      {[](TuneSpec& s) { s.ranges = {"map.size=8:64"}; }, "--range map.size=8:64: map.size: error: got \"8\""},
      {[](TuneSpec& s) { s.ranges = {"filter=none,box"}; }, "--range filter=none,box"},
      {[](TuneSpec& s) { s.keys = {"filter.size"}; }, "\"filter.size\" matters only with filter=pcf"},
      {[](TuneSpec& s) { s.fixed = {parseSetArgument("map.size=512")}; }, "\"map.size\" is both tuned and fixed"},
      {[](TuneSpec& s) { s.scenes = {"grazin"}; }, "grazin"},
  };
  for (const auto& c : cases) {
    TuneSpec spec = threeScenes();
    spec.maxError = 0.002;
    c.edit(spec);
    const std::string what = inputErrorOf([&] { planTune(spec); });
    EXPECT_NE(what.find(c.message), std::string::npos) << "got: " << what << "\nexpected: " << c.message;
  }
}

// bias.adaptive is a categorical key (false, true): the search tries both, and the dense grid
// doubles with it.
TEST(TunePlan, AdaptiveBiasIsACategoricalKeyOfTwoValues) {
  TuneSpec spec = threeScenes();
  spec.maxError = 0.01;
  spec.keys = {"bias.adaptive", "bias.slope"};
  const TunePlan plan = planTune(spec);
  EXPECT_EQ(plan.gridConfigurations, 2u * 17u);
  spec.keys = {"bias.slope"};
  EXPECT_EQ(planTune(spec).gridConfigurations, 17u);
}

// tune names each configuration as run and sweep do (config_name.h): the method keys off their
// defaults and the fixed scene: values, so its rows gate against theirs.
TEST(TuneSearch, NamesConfigurationsLikeRunAndSweep) {
  const std::string dir = tempDir("names");
  TuneSpec spec;
  spec.scenes = {"grazing"};
  spec.keys = {"bias.slope"};
  spec.ranges = {"bias.slope=0,1.5,3"};
  spec.fixed = {parseSetArgument("scene:/camera/width=240")};
  spec.maxError = 0.5;
  TunePlan plan = planTune(spec);
  FakeRunner runner;
  const TuneResult r = runTune(plan, runner, quiet(dir, /*grid=*/true));
  std::set<std::string> names;
  for (const auto& e : r.evaluations) {
    std::vector<std::string> sets = {"scene:/camera/width=240"};
    for (const auto& [k, v] : e.values) sets.push_back(k + "=" + v);
    EXPECT_EQ(e.config, applySetArguments("", sets).config);
    names.insert(e.config);
  }
  EXPECT_EQ(names, (std::set<std::string>{"bias.slope=0,scene:/camera/width=240", "scene:/camera/width=240",
                                          "bias.slope=3,scene:/camera/width=240"}));
  fs::remove_all(dir);
}

}  // namespace tune_search_test
