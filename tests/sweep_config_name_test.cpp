// The one name of a configuration (config_name.h) and the --set / --grid / sweep-file readers
// that feed it: run's --set, a sweep's grid and fixed settings name the same configuration the same
// way; scene: values take any JSON value and their errors name the argument; a key given twice is
// refused; reference samples per pixel have one range. No renderer involved.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "shadowlab/compare/config_name.h"
#include "shadowlab/compare/set_arguments.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "support/cli.h"
#include "support/input_error.h"

namespace sweep_config_name_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::inputErrorOf;

namespace {

std::string tempDir(const std::string& name) {
  return shadowlab::testing::freshTempDir("shadowlab_config_name_" + name).string();
}

std::string writeText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

std::vector<std::string> configsOf(const SweepPlan& plan) {
  std::vector<std::string> out;
  for (const auto& c : plan.configs) out.push_back(c.config);
  return out;
}

}  // namespace

// A name says what the configuration is, not how it was asked for: the method keys that differ
// from their defaults and every scene: value, sorted by key.
TEST(ConfigName, NamesTheKeysThatDifferFromTheDefaultsAndEverySceneValue) {
  EXPECT_EQ(configName(Method{}, {}), "default");
  Method m;
  m.mapSize = 256;
  m.biasCompare = 0.0f;
  m.filter = Filter::Pcf;
  EXPECT_EQ(configName(m, {{"/camera/width", 320}}), "bias.compare=0,filter=pcf,map.size=256,scene:/camera/width=320");
  m = Method{};
  m.name = "mine";  // a method file's name is not part of it
  m.biasSlope = 1.5f;
  EXPECT_EQ(configName(m, {}), "default");
  m.vsmMinVariance = 2e-6f;
  m.tsmFocus = 0.7f;
  EXPECT_EQ(configName(m, {}), "tsm.focus=0.7,vsm.min_variance=2e-06");
  // The JSON form (a row's "method") names it alike; a key it lacks counts as the default.
  EXPECT_EQ(configName(methodToJson(m), {}), configName(m, {}));
  EXPECT_EQ(configName(nlohmann::json{{"map.size", 512}}, {}), "map.size=512");
  EXPECT_EQ(configName(nlohmann::json{{"bias.slope", double(0.1f)}}, {}), "bias.slope=0.1");
}

TEST(ConfigName, CanonicalValueTextIsTheShortestTextThatReadsBack) {
  EXPECT_EQ(canonicalValueText(nlohmann::json(256)), "256");
  EXPECT_EQ(canonicalValueText(nlohmann::json(2.0)), "2");
  EXPECT_EQ(canonicalValueText(nlohmann::json(0.0005)), "0.0005");
  EXPECT_EQ(canonicalValueText(nlohmann::json(1e-6)), "1e-06");
  // %.6g made these two one name; they are two values.
  EXPECT_EQ(canonicalValueText(nlohmann::json(0.1234567)), "0.1234567");
  EXPECT_EQ(canonicalValueText(nlohmann::json(0.1234568)), "0.1234568");
  EXPECT_EQ(canonicalValueText(nlohmann::json::parse("[4, 10.0, 6.5]")), "[4,10,6.5]");
  EXPECT_EQ(canonicalValueText(nlohmann::json::parse(R"(["a", true])")), R"(["a",true])");
}

// The issue's case: `run --set scene:/camera/height=120 --set map.size=256` and a sweep that fixes
// the scene value and sweeps map.size (next to its default 2048) name the rows the same way.
TEST(ConfigName, RunAndSweepNameTheSameConfigurationAlike) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid.push_back(parseGridArgument("map.size=256,2048"));
  spec.fixed.push_back(parseSetArgument("scene:/camera/height=120"));
  const SweepPlan plan = planSweep(spec);
  EXPECT_EQ(configsOf(plan),
            (std::vector<std::string>{"map.size=256,scene:/camera/height=120", "scene:/camera/height=120"}));
  EXPECT_EQ(applySetArguments("", {"scene:/camera/height=120", "map.size=256"}).config, plan.configs[0].config);
  EXPECT_EQ(applySetArguments("", {"map.size=2048", "scene:/camera/height=120"}).config, plan.configs[1].config);
  EXPECT_EQ(applySetArguments("", {"scene:/camera/height=120.0"}).config, plan.configs[1].config);

  // A method file's keys count like --set ones: its name does not.
  const std::string dir = tempDir("file");
  const std::string method = writeText(dir + "/pcf.json", R"({"name": "pcf5", "filter": "pcf", "filter.size": 5})");
  EXPECT_EQ(applySetArguments(method, {}).config, "filter=pcf,filter.size=5");
  SweepSpec fixed;
  fixed.scenes = {"sphere_on_plane"};
  fixed.fixed.push_back(parseSetArgument("filter=pcf"));
  fixed.fixed.push_back(parseSetArgument("filter.size=5"));
  EXPECT_EQ(configsOf(planSweep(fixed)), (std::vector<std::string>{"filter=pcf,filter.size=5"}));
  fs::remove_all(dir);
}

// A grid point that is the same configuration as an earlier one is run once: 1.5 is bias.slope's
// default, so "bias.slope=1.5" and nothing swept are one row.
TEST(ConfigName, TheSameConfigurationIsOneRow) {
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.grid.push_back(parseGridArgument("map.size=256"));
  spec.grid.push_back(parseGridArgument("bias.slope=0,1.5"));
  EXPECT_EQ(configsOf(planSweep(spec)), (std::vector<std::string>{"bias.slope=0,map.size=256", "map.size=256"}));
}

// --set scene:/pointer=JSON: a whole vector (or any JSON value) can be set, on the command line, in
// a --grid list (commas inside brackets do not split it) and in a sweep file's "set".
TEST(ConfigName, SceneValuesTakeAnyJsonValue) {
  const SetArguments a = applySetArguments("", {"scene:/camera/look_at=[1, 0.5, 2]"});
  ASSERT_EQ(a.sceneOverrides.size(), 1u);
  EXPECT_EQ(a.sceneOverrides[0].value, nlohmann::json::parse("[1,0.5,2]"));
  EXPECT_EQ(a.config, "scene:/camera/look_at=[1,0.5,2]");
  const Scene scene = loadScene(resolveScenePath("contact"), a.sceneOverrides);
  EXPECT_EQ(scene.camera.lookAt, glm::vec3(1, 0.5f, 2));

  const SweepAxis axis = parseGridArgument("scene:/camera/look_at=[1,0.5,2],[0, 0, 0]");
  ASSERT_EQ(axis.values.size(), 2u);
  EXPECT_EQ(axis.values[1], "[0, 0, 0]");
  SweepSpec spec;
  spec.scenes = {"contact"};
  spec.grid.push_back(axis);
  const SweepPlan plan = planSweep(spec);
  EXPECT_EQ(configsOf(plan),
            (std::vector<std::string>{"scene:/camera/look_at=[1,0.5,2]", "scene:/camera/look_at=[0,0,0]"}));
  EXPECT_EQ(plan.variants.size(), 2u);

  const std::string dir = tempDir("vector");
  const std::string file =
      writeText(dir + "/s.json", R"({"scenes": ["contact"], "set": {"scene:/camera/look_at": [1, 0.5, 2]}})");
  SweepSpec fromFile;
  loadSweepFile(file, fromFile);
  EXPECT_EQ(configsOf(planSweep(fromFile)), (std::vector<std::string>{"scene:/camera/look_at=[1,0.5,2]"}));
  // A method key still takes a number, string or boolean only.
  const std::string bad = writeText(dir + "/bad.json", R"({"set": {"map.size": [256]}})");
  EXPECT_EQ(inputErrorOf([&] {
              SweepSpec s;
              loadSweepFile(bad, s);
            }),
            bad + ": /set/map.size: error: got an array; expected a number, string or boolean");
  fs::remove_all(dir);
}

// A scene value the scene refuses is the argument's fault: the error names the --set (or the sweep
// file's place), then where in which scene file the value landed.
TEST(ConfigName, SceneValueErrorsNameTheArgument) {
  const std::string scenePath = resolveScenePath("contact");
  const SetArguments zero = applySetArguments("", {"scene:/camera/width=0"});
  const std::string e1 = inputErrorOf([&] { loadScene(scenePath, zero.sceneOverrides); });
  EXPECT_EQ(e1.rfind("--set scene:/camera/width=0: error: got 0; expected ", 0), 0u) << e1;
  EXPECT_NE(e1.find("(" + scenePath + ": /camera/width)"), std::string::npos) << e1;

  const SetArguments missing = applySetArguments("", {"scene:/camera/widht=10"});
  const std::string e2 = inputErrorOf([&] { loadScene(scenePath, missing.sceneOverrides); });
  EXPECT_EQ(e2.rfind("--set scene:/camera/widht=10: error: ", 0), 0u) << e2;
  EXPECT_NE(e2.find(scenePath), std::string::npos) << e2;

  // A grid value is named by its place in the sweep file.
  const std::string dir = tempDir("blame");
  const std::string file =
      writeText(dir + "/s.json", R"({"scenes": ["contact"], "grid": {"scene:/camera/width": [64, -3]}})");
  SweepSpec spec;
  loadSweepFile(file, spec);
  const std::string e3 = inputErrorOf([&] { planSweep(spec); });
  EXPECT_EQ(e3.rfind(file + ": /grid/scene:~1camera~1width/1: error: got -3; expected ", 0), 0u) << e3;
  // An error elsewhere in the scene still names the scene file.
  const SetArguments fine = applySetArguments("", {"scene:/camera/width=64"});
  EXPECT_NO_THROW(loadScene(scenePath, fine.sceneOverrides));
  fs::remove_all(dir);
}

TEST(ConfigName, AKeySetTwiceIsRefused) {
  EXPECT_EQ(inputErrorOf([] {
              applySetArguments("", {"map.size=256", "filter=pcf", "map.size=512"});
            }),
            "--set map.size=512: error: \"map.size\" is set again (first by --set map.size=256); expected each key "
            "once");
  EXPECT_EQ(inputErrorOf([] {
              applySetArguments("", {"scene:/camera/width=64", "scene:/camera/width=64"});
            }),
            "--set scene:/camera/width=64: error: \"scene:/camera/width\" is set again (first by --set "
            "scene:/camera/width=64); expected each key once");
}

// One range of reference samples per pixel, from the reference's own limit.
TEST(ConfigName, SamplesPerPixelHaveOneRange) {
  EXPECT_EQ(kMaxSpp, 1024);
  EXPECT_NO_THROW(checkSpp(1, "--spp"));
  EXPECT_NO_THROW(checkSpp(kMaxSpp, "--spp"));
  EXPECT_EQ(inputErrorOf([] { checkSpp(0, "--spp"); }),
            "--spp: error: got 0; expected an integer 1..1024 (reference samples per pixel)");
  const std::string dir = tempDir("spp");
  for (const char* value : {"2000", "0", "1.5", "\"4\""}) {
    const std::string file = writeText(dir + "/s.json", std::string(R"({"spp": )") + value + "}");
    const std::string e = inputErrorOf([&] {
      SweepSpec s;
      loadSweepFile(file, s);
    });
    EXPECT_EQ(e.rfind(file + ": /spp: error: got " + std::string(value) + "; expected an integer 1..1024", 0), 0u) << e;
  }
  SweepSpec spec;
  spec.scenes = {"sphere_on_plane"};
  spec.spp = 4096;  // a spec built in code is checked by the plan too
  EXPECT_EQ(inputErrorOf([&] { planSweep(spec); }),
            "--spp: error: got 4096; expected an integer 1..1024 (reference samples per pixel)");
  fs::remove_all(dir);
}

}  // namespace sweep_config_name_test
