// Sweep specification -> plan: grid parsing, validation before anything is written, expansion
// order, canonical config text, sweep files with their error places. No renderer involved.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

#include <filesystem>
#include <fstream>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/sweep_frontier.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/json_reader.h"
#include "support/input_error.h"

namespace sweep_plan_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::inputErrorOf;

namespace {

std::string tempDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_sweep_plan_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

std::string writeText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

SweepSpec specWithGrid(std::vector<std::string> grid) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  for (const auto& g : grid) spec.grid.push_back(parseGridArgument(g));
  return spec;
}

}  // namespace

TEST(SweepPlan, GridArgumentSplitsKeyAndValues) {
  SweepAxis a = parseGridArgument("map.size=256, 512 ,1024");
  EXPECT_EQ(a.key, "map.size");
  ASSERT_EQ(a.values.size(), 3u);
  EXPECT_EQ(a.values[0], "256");
  EXPECT_EQ(a.values[1], "512");
  EXPECT_EQ(a.values[2], "1024");
}

TEST(SweepPlan, MalformedGridArgumentsNameTheArgument) {
  EXPECT_EQ(inputErrorOf([] { parseGridArgument("map.size"); }),
            "--grid map.size: error: no '=' found; expected key=v1,v2,... (e.g. map.size=512,1024)");
  EXPECT_EQ(inputErrorOf([] { parseGridArgument("map.size="); }),
            "--grid map.size=: error: empty list of values for \"map.size\"; expected key=v1,v2,...");
  EXPECT_NE(inputErrorOf([] { parseGridArgument("map.size=256,,512"); }).find("value 2 of \"map.size\" is empty"),
            std::string::npos);
  EXPECT_NE(inputErrorOf([] { parseGridArgument("=1,2"); }).find("empty key"), std::string::npos);
}

// The sweep-size limit: 1000 map sizes x 101 slopes = 101,000 configurations, over the 100,000
// a plan holds; the message says the limit and why.
TEST(SweepPlan, GridAboveTheConfigurationLimitIsRefused) {
  std::string sizes = "map.size=", slopes = "bias.slope=";
  for (int k = 0; k < 1000; ++k) sizes += (k ? "," : "") + std::to_string(16 + k);
  for (int k = 0; k <= 100; ++k) slopes += (k ? "," : "") + std::to_string(k * 0.01);
  const std::string e = inputErrorOf([&] { planSweep(specWithGrid({sizes, slopes})); });
  EXPECT_NE(e.find("the grid has more than 100000 configurations"), std::string::npos) << e;
  EXPECT_NE(e.find("held in memory"), std::string::npos) << e;
  EXPECT_NO_THROW(planSweep(specWithGrid({sizes, "bias.slope=0,1"})));  // 2,000: fine
}

TEST(SweepPlan, UnknownKeyAndBadValuesAreRejected) {
  std::string unknown = inputErrorOf([] { planSweep(specWithGrid({"map.sise=256,512"})); });
  EXPECT_NE(unknown.find("--grid map.sise=256,512: error: unknown key \"map.sise\""), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("map.size"), std::string::npos) << "the message lists the valid keys: " << unknown;

  std::string nonNumeric = inputErrorOf([] { planSweep(specWithGrid({"map.size=256,big"})); });
  EXPECT_NE(nonNumeric.find("--grid map.size=256,big"), std::string::npos) << nonNumeric;
  EXPECT_NE(nonNumeric.find("\"big\""), std::string::npos) << nonNumeric;

  std::string badEnum = inputErrorOf([] { planSweep(specWithGrid({"filter=pcf,blur"})); });
  EXPECT_NE(badEnum.find("\"blur\""), std::string::npos) << badEnum;

  std::string dup = inputErrorOf([] { planSweep(specWithGrid({"bias.slope=0.5,0.50"})); });
  EXPECT_NE(dup.find("value \"0.5\" of \"bias.slope\" appears twice"), std::string::npos) << dup;

  std::string twice = inputErrorOf([] { planSweep(specWithGrid({"map.size=256", "map.size=512"})); });
  EXPECT_NE(twice.find("is swept twice"), std::string::npos) << twice;

  SweepSpec both = specWithGrid({"map.size=256,512"});
  both.fixed.push_back(parseSetArgument("map.size=1024"));
  EXPECT_NE(inputErrorOf([&] { planSweep(both); }).find("both swept and fixed"), std::string::npos);

  // A cross-field rule (pcf needs an odd kernel) is checked for every configuration.
  SweepSpec even = specWithGrid({"filter.size=3,4"});
  even.fixed.push_back(parseSetArgument("filter=pcf"));
  EXPECT_NE(inputErrorOf([&] { planSweep(even); }).find("filter.size"), std::string::npos);

  SweepSpec light = specWithGrid({"map.size=256"});
  light.light = "moon";
  EXPECT_NE(inputErrorOf([&] { planSweep(light); }).find("no light named \"moon\"; expected one of sun"),
            std::string::npos);
}

TEST(SweepPlan, ExpandsTheGridLastAxisFastestWithSortedCanonicalConfigs) {
  SweepPlan plan = planSweep(specWithGrid({"map.size=512,256", "bias.slope=0,1.50"}));
  ASSERT_EQ(plan.configs.size(), 4u);
  ASSERT_EQ(plan.jobs.size(), 4u);
  // Keys sorted in the text; values canonical; the order of the grid is kept. 1.50 is bias.slope's
  // default: not named (config_name.h).
  EXPECT_EQ(plan.configs[0].config, "bias.slope=0,map.size=512");
  EXPECT_EQ(plan.configs[1].config, "map.size=512");
  EXPECT_EQ(plan.configs[2].config, "bias.slope=0,map.size=256");
  EXPECT_EQ(plan.configs[3].config, "map.size=256");
  EXPECT_EQ(plan.configs[1].method.mapSize, 512);
  EXPECT_FLOAT_EQ(plan.configs[1].method.biasSlope, 1.5f);
  EXPECT_EQ(plan.configs[3].method.mapSize, 256);
  EXPECT_EQ(plan.jobs[0].sceneName, "sphere_on_plane");
  EXPECT_EQ(plan.jobs[0].light, "sun");
  // Method keys only: the scene is loaded once.
  EXPECT_EQ(plan.variants.size(), 1u);
}

TEST(SweepPlan, FixedSettingsApplyToEveryConfigurationAndAreNamed) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.fixed.push_back(parseSetArgument("filter=pcf"));
  spec.fixed.push_back(parseSetArgument("filter.size=5"));
  SweepPlan plan = planSweep(spec);
  ASSERT_EQ(plan.configs.size(), 1u);
  EXPECT_EQ(plan.configs[0].config, "filter=pcf,filter.size=5");
  EXPECT_EQ(plan.configs[0].method.filter, Filter::Pcf);
  EXPECT_EQ(plan.configs[0].method.filterSize, 5);
}

TEST(SweepPlan, SceneKeysLoadOneVariantPerValue) {
  SweepPlan plan = planSweep(specWithGrid({"scene:/lights/0/elevation_deg=60,20", "map.size=256,512"}));
  ASSERT_EQ(plan.configs.size(), 4u);
  EXPECT_EQ(plan.configs[0].config, "map.size=256,scene:/lights/0/elevation_deg=60");
  EXPECT_EQ(plan.variants.size(), 2u);
  EXPECT_NE(plan.variants[0].hash, plan.variants[1].hash) << "the override must reach the loaded scene";
  EXPECT_EQ(plan.jobs[0].variantIndex, plan.jobs[1].variantIndex);
  EXPECT_NE(plan.jobs[0].variantIndex, plan.jobs[2].variantIndex);
  // Light direction from elevation 60 vs 20 degrees: -y component sin(60) vs sin(20).
  EXPECT_NEAR(-plan.variants[plan.jobs[0].variantIndex].lights[0].direction.y, std::sin(60.0 * M_PI / 180.0), 1e-5);
  EXPECT_NEAR(-plan.variants[plan.jobs[2].variantIndex].lights[0].direction.y, std::sin(20.0 * M_PI / 180.0), 1e-5);

  std::string bad = inputErrorOf([] { planSweep(specWithGrid({"scene:lights=1"})); });
  EXPECT_NE(bad.find("no valid JSON pointer"), std::string::npos) << bad;
}

TEST(SweepPlan, SweepFileReadsScenesGridAndSettings) {
  std::string dir = tempDir("file");
  std::string path = writeText(dir + "/sweep.json", R"({
    // comments are allowed
    "description": "two sizes, two biases",
    "scenes": ["sphere_on_plane"],
    "grid": {"map.size": [256, 512], "bias.slope": [0, 2.0]},
    "set": {"filter": "hw2x2"},
    "spp": 1
  })");
  SweepSpec spec;
  loadSweepFile(path, spec);
  SweepPlan plan = planSweep(spec);
  ASSERT_EQ(plan.configs.size(), 4u);
  EXPECT_EQ(plan.configs[0].config, "bias.slope=0,filter=hw2x2,map.size=256");
  EXPECT_EQ(plan.configs[1].config, "bias.slope=2,filter=hw2x2,map.size=256");
  EXPECT_EQ(plan.configs[0].method.filter, Filter::Hw2x2);
  fs::remove_all(dir);
}

TEST(SweepPlan, SweepFileErrorsNameFileAndPlace) {
  std::string dir = tempDir("fileerr");
  // Syntax error: line:col of the offending token (line 3, the missing comma before "grid").
  std::string syntax = writeText(dir + "/syntax.json", "{\n  \"scenes\": [\"sphere_on_plane\"]\n  \"grid\": {}\n}\n");
  std::string e1 = inputErrorOf([&] {
    SweepSpec s;
    loadSweepFile(syntax, s);
  });
  EXPECT_EQ(e1.rfind(syntax + ":3:", 0), 0u) << e1;

  std::string emptyList = writeText(dir + "/empty.json", R"({"grid": {"map.size": []}})");
  std::string e2 = inputErrorOf([&] {
    SweepSpec s;
    loadSweepFile(emptyList, s);
  });
  EXPECT_EQ(e2, emptyList + ": /grid/map.size: error: empty list of values; expected at least one");

  std::string unknownKey = writeText(dir + "/unknown.json", R"({"grid": {"map.sizes": [256]}})");
  std::string e3 = inputErrorOf([&] {
    SweepSpec s;
    loadSweepFile(unknownKey, s);
  });
  EXPECT_NE(e3.find(unknownKey + ": /grid/map.sizes: error: unknown key \"map.sizes\""), std::string::npos) << e3;

  std::string badValue = writeText(dir + "/value.json", R"({"grid": {"map.size": [256, "huge"]}})");
  std::string e4 = inputErrorOf([&] {
    SweepSpec s;
    loadSweepFile(badValue, s);
    s.scenes = {"sphere_on_plane"};
    planSweep(s);
  });
  EXPECT_NE(e4.find(badValue + ": /grid/map.size/1"), std::string::npos) << e4;
  EXPECT_NE(e4.find("\"huge\""), std::string::npos) << e4;

  std::string topKey = writeText(dir + "/top.json", R"({"scenes": ["sphere_on_plane"], "grids": {}})");
  std::string e5 = inputErrorOf([&] {
    SweepSpec s;
    loadSweepFile(topKey, s);
  });
  EXPECT_NE(e5.find(topKey + ": /grids: error: unknown key \"grids\""), std::string::npos) << e5;

  std::string e6 = inputErrorOf([&] {
    SweepSpec s;
    loadSweepFile(dir + "/missing.json", s);
  });
  EXPECT_NE(e6.find(dir + "/missing.json"), std::string::npos) << e6;
  fs::remove_all(dir);
}

TEST(SweepPlan, CanonicalValueText) {
  EXPECT_EQ(canonicalValueText(nlohmann::json(256)), "256");
  EXPECT_EQ(canonicalValueText(nlohmann::json(0.5)), "0.5");
  EXPECT_EQ(canonicalValueText(jsonFloat(0.1f)), "0.1");  // a method's float, as methodToJson writes it
  EXPECT_EQ(canonicalValueText(nlohmann::json(-0.0)), "0");
  EXPECT_EQ(canonicalValueText(nlohmann::json("pcf")), "pcf");
  EXPECT_EQ(canonicalValueText(nlohmann::json(true)), "true");
}

TEST(SweepPlan, DefaultCacheDirSitsBesideTheOutputFolder) {
  ::unsetenv("SHADOWLAB_CACHE");
  EXPECT_EQ(defaultSweepCacheDir("/tmp/x/sweep1"), "/tmp/x/.shadowlab-cache");
  EXPECT_EQ(defaultSweepCacheDir("/tmp/x/sweep1/"), "/tmp/x/.shadowlab-cache");
  ::setenv("SHADOWLAB_CACHE", "/tmp/elsewhere", 1);
  EXPECT_EQ(defaultSweepCacheDir("/tmp/x/sweep1"), "/tmp/elsewhere");
  ::unsetenv("SHADOWLAB_CACHE");
}

// scene:failure sweeps the value each scene's declared "failure" pointer names: the sun's elevation
// in grazing, the wall's thickness in thin_wall, within one grid.
TEST(SweepPlan, SceneFailureKeySweepsEachScenesOwnFailurePointer) {
  SweepSpec spec = specWithGrid({"scene:failure=30,0.05"});
  spec.scenes = {"grazing", "thin_wall"};
  SweepPlan plan = planSweep(spec);
  ASSERT_EQ(plan.configs.size(), 2u);
  EXPECT_EQ(plan.configs[0].config, "scene:failure=30");
  EXPECT_EQ(plan.configs[1].config, "scene:failure=0.05");
  ASSERT_EQ(plan.jobs.size(), 4u);
  const Scene& grazing30 = plan.variants[plan.jobs[0].variantIndex];
  const Scene& thin005 = plan.variants[plan.jobs[3].variantIndex];
  EXPECT_EQ(grazing30.name, "grazing");
  EXPECT_EQ(grazing30.failurePointer, "/lights/0/elevation_deg");
  // The sun at 30 degrees: the direction's y is -sin(30 deg).
  EXPECT_NEAR(grazing30.lights[0].direction.y, -0.5f, 1e-6f);
  EXPECT_EQ(thin005.name, "thin_wall");
  EXPECT_EQ(thin005.failurePointer, "/objects/1/size/0");
  // The wall (object 1, a box 0.05 thick along x): its x extent.
  float lo = 1e9f, hi = -1e9f;
  for (const auto& p : thin005.objects[1].positions) {
    lo = std::min(lo, p.x);
    hi = std::max(hi, p.x);
  }
  EXPECT_NEAR(hi - lo, 0.05f, 1e-6f);
  // Unchanged elsewhere: grazing's thickness-valued configuration still moved only the sun.
  const Scene& grazing005 = plan.variants[plan.jobs[1].variantIndex];
  EXPECT_NEAR(grazing005.lights[0].direction.y, -std::sin(0.05f * 3.14159265f / 180.0f), 1e-6f);
}

TEST(SweepPlan, SceneFailureKeyNeedsADeclaredFailureAndNoSecondNameForIt) {
  const std::string dir = tempDir("failure");
  const std::string plain = writeText(dir + "/plain.json", R"({
    "camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 64, "height": 48},
    "objects": [{"type": "plane", "size": [10, 10]}],
    "lights": [{"type": "directional", "elevation_deg": 45}]})");
  SweepSpec spec = specWithGrid({"scene:failure=30,20"});
  spec.scenes = {"grazing", plain};
  EXPECT_EQ(inputErrorOf([&] { planSweep(spec); }),
            plain +
                ": error: the scene declares no \"failure\", so scene:failure names nothing in it; expected a scene "
                "with \"failure\" (scenes/FORMAT.md) or a JSON pointer: scene:/path/to/value");
  // The same value under two names is ambiguous.
  SweepSpec twice = specWithGrid({"scene:failure=30,20"});
  twice.scenes = {"grazing"};
  twice.fixed.push_back(parseSetArgument("scene:/lights/0/elevation_deg=10"));
  EXPECT_NE(
      inputErrorOf([&] { planSweep(twice); })
          .find("scene:failure is /lights/0/elevation_deg in this scene, which scene:/lights/0/elevation_deg also "
                "sets; expected one of them"),
      std::string::npos);
  fs::remove_all(dir);
}

// A union of grids: "grid" as an array of grid objects, each expanded as a product on its own.
// A key one block does not sweep carries the base method's value there; a configuration two blocks
// share is run once; sweptAxes gives one axis per key for the report.
TEST(SweepPlan, UnionOfGridsExpandsEachBlockAndJoinsThem) {
  std::string dir = tempDir("union");
  std::string path = writeText(dir + "/union.json", R"({
    "scenes": ["sphere_on_plane"],
    "grid": [
      {"map.size": [512, 1024], "filter": ["none", "pcf"]},
      {"map.size": [1024], "fit": ["sphere", "lispsm"]}
    ],
    "set": {"bias.slope": 2}
  })");
  SweepSpec spec;
  loadSweepFile(path, spec);
  SweepPlan plan = planSweep(spec);
  std::vector<std::string> configs;
  for (const auto& c : plan.configs) configs.push_back(c.config);
  // Block 1's fit=sphere,map.size=1024 is block 0's filter=none,map.size=1024: not repeated.
  // Names hold the keys off their defaults (none and sphere are), bias.slope=2 set in every one.
  EXPECT_EQ(configs, (std::vector<std::string>{"bias.slope=2,map.size=512", "bias.slope=2,filter=pcf,map.size=512",
                                               "bias.slope=2,map.size=1024", "bias.slope=2,filter=pcf,map.size=1024",
                                               "bias.slope=2,fit=lispsm,map.size=1024"}));
  EXPECT_EQ(plan.configs[4].method.fit, Fit::Lispsm);
  EXPECT_EQ(plan.configs[4].method.filter, Filter::None);
  EXPECT_EQ(plan.configs[1].method.filter, Filter::Pcf);
  for (const auto& c : plan.configs) EXPECT_EQ(c.method.biasSlope, 2.0f) << c.config;
  EXPECT_EQ(plan.jobs.size(), 5u);
  const std::vector<SweepAxis> axes = sweptAxes(plan);
  ASSERT_EQ(axes.size(), 3u);
  EXPECT_EQ(axes[0].key, "map.size");
  EXPECT_EQ(axes[0].values, (std::vector<nlohmann::json>{"512", "1024"}));
  EXPECT_EQ(axes[1].key, "filter");
  EXPECT_EQ(axes[2].key, "fit");
  EXPECT_EQ(axes[2].values, (std::vector<nlohmann::json>{"sphere", "lispsm"}));

  // A --grid axis replaces the key's axes in every block (app/cmd_sweep.cpp does this) and is
  // swept in all of them.
  SweepSpec again = spec;
  again.grid.erase(
      std::remove_if(again.grid.begin(), again.grid.end(), [](const SweepAxis& a) { return a.key == "map.size"; }),
      again.grid.end());
  again.grid.push_back(parseGridArgument("map.size=256"));
  EXPECT_EQ(planSweep(again).configs.size(), 3u);  // none, pcf; sphere is block 0's none; lispsm

  // Errors name the block: a key twice in one block, a block that is not an object, an empty union,
  // and a scene: key some blocks leave out (it has no base value).
  std::string twice = writeText(dir + "/twice.json", R"({"scenes": ["sphere_on_plane"],
    "grid": [{"map.size": [512]}, {"map.size": [256], "filter": ["pcf"]}, {"filter": ["none"], "fit": ["tight"]}]})");
  SweepSpec ok;
  loadSweepFile(twice, ok);
  EXPECT_EQ(planSweep(ok).configs.size(), 3u) << "the same key in two blocks is fine";
  std::string notObject = writeText(dir + "/notobject.json", R"({"grid": [{"map.size": [512]}, [1, 2]]})");
  EXPECT_EQ(inputErrorOf([&] {
              SweepSpec s;
              loadSweepFile(notObject, s);
            }),
            notObject + ": /grid/1: error: got an array; expected a grid object {\"key\": [v1, v2, ...]}");
  std::string empty = writeText(dir + "/empty.json", R"({"grid": []})");
  EXPECT_EQ(inputErrorOf([&] {
              SweepSpec s;
              loadSweepFile(empty, s);
            }),
            empty + ": /grid: error: empty list of grids; expected at least one grid object");
  std::string sceneKey = writeText(dir + "/scenekey.json", R"({"scenes": ["sphere_on_plane"],
    "grid": [{"scene:/lights/0/elevation_deg": [30, 60]}, {"map.size": [512]}]})");
  const std::string e = inputErrorOf([&] {
    SweepSpec s;
    loadSweepFile(sceneKey, s);
    planSweep(s);
  });
  EXPECT_NE(e.find("\"scene:/lights/0/elevation_deg\" is swept in another grid of the union but not in this one"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("/grid/1"), std::string::npos) << e;
  fs::remove_all(dir);
}

// A grid of a union may name its scenes: its configurations run on those scenes only, and a
// scene: key it sweeps alone need not be swept elsewhere (a sized light's radius on the one scene
// that has one). A configuration another grid also produces runs wherever either grid runs it.
TEST(SweepPlan, AGridOfAUnionRunsOnItsNamedScenesOnly) {
  std::string dir = tempDir("blockscenes");
  std::string path = writeText(dir + "/blocks.json", R"({
    "scenes": ["sphere_on_plane", "contact"],
    "grid": [
      {"scenes": ["contact"], "map.size": [512], "filter": ["none", "poisson"]},
      {"map.size": [512, 1024]},
      {"scenes": ["contact"], "filter": ["pcf"], "scene:/lights/0/elevation_deg": [60, 30, 15]}
    ]
  })");
  SweepSpec spec;
  loadSweepFile(path, spec);
  SweepPlan plan = planSweep(spec);
  std::vector<std::string> configs;
  for (const auto& c : plan.configs) configs.push_back(c.config);
  EXPECT_EQ(configs, (std::vector<std::string>{
                         "map.size=512", "filter=poisson,map.size=512", "map.size=1024",
                         "filter=pcf,scene:/lights/0/elevation_deg=60", "filter=pcf,scene:/lights/0/elevation_deg=30",
                         "filter=pcf,scene:/lights/0/elevation_deg=15"}));
  // map.size=512 came first from contact's grid; the unrestricted grid makes it run everywhere.
  EXPECT_TRUE(plan.configs[0].onlyScenes.empty());
  ASSERT_EQ(plan.configs[1].onlyScenes.size(), 1u);
  std::map<std::string, std::vector<std::string>> jobs;
  for (const auto& j : plan.jobs) jobs[j.sceneName].push_back(j.config);
  EXPECT_EQ(jobs["sphere_on_plane"], (std::vector<std::string>{"map.size=512", "map.size=1024"}));
  EXPECT_EQ(jobs["contact"].size(), 6u);
  // The elevation is read from contact's own light only.
  for (const auto& j : plan.jobs)
    if (j.config == "filter=pcf,scene:/lights/0/elevation_deg=15") {
      EXPECT_EQ(j.sceneName, "contact");
      EXPECT_NEAR(plan.variants[j.variantIndex].lights[0].direction.y, -std::sin(15.0 * M_PI / 180.0), 1e-6);
    }
  // Frontiers along the elevation: contact's pcf configuration only, over its three values.
  std::vector<ResultRow> rows;
  for (const auto& j : plan.jobs) {
    ResultRow r;
    r.scene = j.sceneName;
    r.config = j.config;
    r.light = "sun";
    r.metrics["error_rate"] = j.config.find("=15") != std::string::npos ? 0.2 : 0.001;
    rows.push_back(r);
  }
  const nlohmann::json fr = computeFrontiers(plan, rows, "error_rate", 0.01);
  ASSERT_EQ(fr.size(), 1u) << fr.dump();
  EXPECT_EQ(fr[0]["scene"], "contact");
  // The grid's other keys take the base method's values there (map.size 2048).
  EXPECT_EQ(fr[0]["method"], "filter=pcf,map.size=2048");
  EXPECT_EQ(fr[0]["points"].size(), 3u);
  EXPECT_EQ(fr[0]["breaks_at"], 15.0);

  // Errors: "scenes" in a single grid object, not a list, a grid of scenes only, an unknown scene,
  // and a requested scene that no grid runs.
  auto errorOfFile = [&](const std::string& name, const std::string& text) {
    const std::string f = writeText(dir + "/" + name, text);
    return inputErrorOf([&] {
      SweepSpec s;
      loadSweepFile(f, s);
      planSweep(s);
    });
  };
  EXPECT_NE(errorOfFile("single.json", R"({"grid": {"scenes": ["contact"], "map.size": [512]}})")
                .find("/grid/scenes: error: \"scenes\" inside a single grid object"),
            std::string::npos);
  EXPECT_NE(errorOfFile("notlist.json", R"({"grid": [{"scenes": "contact", "map.size": [512]}]})")
                .find("/grid/0/scenes: error: got a string; expected an array of scene names or paths"),
            std::string::npos);
  EXPECT_NE(errorOfFile("onlyscenes.json", R"({"grid": [{"map.size": [512]}, {"scenes": ["contact"]}]})")
                .find("/grid/1: error: got a grid object without axes"),
            std::string::npos);
  EXPECT_NE(errorOfFile("unknown.json", R"({"grid": [{"scenes": ["no_such_scene"], "map.size": [512]}]})")
                .find("/grid/0/scenes: error: scene \"no_such_scene\" not found"),
            std::string::npos);
  EXPECT_NE(errorOfFile("none.json", R"({"scenes": ["sphere_on_plane", "contact"],
                                          "grid": [{"scenes": ["contact"], "map.size": [512]}]})")
                .find("no configuration of the grid runs on this scene"),
            std::string::npos);
  fs::remove_all(dir);
}

}  // namespace sweep_plan_test
