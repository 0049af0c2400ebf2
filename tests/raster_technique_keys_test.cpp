// A technique file's method keys without a GPU (scenes/technique.h, method.cpp): declared keys in
// any order, their ranges and types, keys the file does not declare, the filter it replaces, the
// method JSON naming the file by stem@hash and refusing an edited one.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <fstream>
#include <string>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/technique.h"
#include "support/cli.h"

namespace raster_technique_keys_test {

using namespace shadowlab;

namespace {

const std::string kExamples = std::string(SHADOWLAB_SOURCE_DIR) + "/examples/techniques/";

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(RasterTechniqueKeys, DeclarationsOfTheExamples) {
  const TechniqueFile& t = loadTechniqueFile(kExamples + "poisson_ign.glsl");
  ASSERT_EQ(t.params.size(), 2u);
  EXPECT_EQ(t.params[0].name, "radius");
  EXPECT_EQ(t.params[0].type, TechniqueParam::Type::Float);
  EXPECT_EQ(t.params[0].defaultValue, 1.5);
  EXPECT_EQ(t.params[0].lo, 0.25);
  EXPECT_EQ(t.params[0].hi, 8);
  EXPECT_EQ(t.params[1].name, "taps");
  EXPECT_EQ(t.params[1].type, TechniqueParam::Type::Int);
  EXPECT_EQ(t.stem, "poisson_ign");
  EXPECT_EQ(t.hash.size(), 16u);
  EXPECT_FALSE(t.readsPlaneSlope);
  EXPECT_EQ(techniqueParamBits(t.params[1], 12), 12u);
  EXPECT_EQ(techniqueParamBits(t.params[0], 1.0), 0x3f800000u);
}

// technique.<name> before technique= is checked once the method is whole; the JSON carries every
// declared key (set or default) and the stem@hash.
TEST(RasterTechniqueKeys, SetInAnyOrderAndWrittenToJson) {
  Method m;
  applyMethodSetting(m, "technique.radius", "3", "--set");
  applyMethodSetting(m, "technique", kExamples + "poisson_ign.glsl", "--set");
  validateMethod(m, "--set");
  const nlohmann::json j = methodToJson(m);
  EXPECT_EQ(j.at("technique.radius"), 3.0);
  EXPECT_EQ(j.at("technique.taps"), 12);
  EXPECT_EQ(j.at("technique.hash"), "poisson_ign@" + loadTechniqueFile(kExamples + "poisson_ign.glsl").hash);
  // Round trip: the JSON applied back gives the same method.
  Method back;
  for (const auto& [k, v] : j.items()) applyMethodJson(back, k, v, "rt");
  validateMethod(back, "rt");
  EXPECT_EQ(methodToJson(back), j);
}

TEST(RasterTechniqueKeys, ErrorsNameTheFile) {
  const std::string file = kExamples + "poisson_ign.glsl";
  auto withKey = [&](const std::string& key, const std::string& value) {
    return errorOf([&] {
      Method m;
      applyMethodSetting(m, "technique", file, "--set");
      applyMethodSetting(m, key, value, "--set");
      validateMethod(m, "--set");
    });
  };
  EXPECT_EQ(withKey("technique.radiuss", "2"), "--set: technique.radiuss: error: not declared by " + file +
                                                   "; expected one of its keys: technique.radius, technique.taps");
  EXPECT_EQ(withKey("technique.radius", "9"),
            "--set: technique.radius: error: got 9; expected a number 0.25..8 (" + file + ":5)");
  EXPECT_EQ(withKey("technique.taps", "2.5"),
            "--set: technique.taps: error: got 2.5; expected an integer 1..16 (" + file + ":6)");
  EXPECT_EQ(withKey("filter", "pcf"),
            "--set: filter: error: got pcf beside technique=" + file + "; expected none (the technique is the filter)");
  EXPECT_EQ(errorOf([] {
              Method m;
              applyMethodSetting(m, "technique.radius", "2", "--set");
              validateMethod(m, "--set");
            }),
            "--set: technique.radius: error: set without a technique; expected technique=file.glsl");
  EXPECT_NE(errorOf([] {
              Method m;
              applyMethodSetting(m, "technique", "/nonexistent/x.glsl", "--set");
            }).find("/nonexistent/x.glsl: error: cannot open file"),
            std::string::npos);
}

// A method JSON pinning technique.hash (a tuned.json) refuses the file once edited, naming both.
TEST(RasterTechniqueKeys, EditedFileIsRefusedByItsPinnedHash) {
  const auto dir = shadowlab::testing::freshTempDir("raster_technique_keys");
  const std::string path = (dir / "mine.glsl").string();
  std::filesystem::copy_file(kExamples + "pcf.glsl", path);
  Method m;
  applyMethodSetting(m, "technique", path, "--set");
  const nlohmann::json j = methodToJson(m);
  const std::string oldId = j.at("technique.hash");
  std::ofstream(path, std::ios::app) << "// edited\n";
  const std::string newId = "mine@" + loadTechniqueFile(path).hash;
  ASSERT_NE(oldId, newId);
  const std::string e = errorOf([&] {
    Method back;
    for (const auto& [k, v] : j.items()) applyMethodJson(back, k, v, "tuned.json");
    validateMethod(back, "tuned.json");
  });
  EXPECT_EQ(e, "tuned.json: technique.hash: error: got " + oldId + ", but " + path + " is now " + newId +
                   "; expected the file the method was measured with (edited since?)");
}

// The checks that need no compiler, each at its line and column (the CLI test runs them end to end).
TEST(RasterTechniqueKeys, FileChecksAtLineAndColumn) {
  const auto dir = shadowlab::testing::freshTempDir("raster_technique_files");
  auto errorFor = [&](const std::string& name, const std::string& text) {
    const std::string p = (dir / name).string();
    std::ofstream(p, std::ios::binary) << text;
    const std::string e = errorOf([&] { loadTechniqueFile(p); });
    return e.rfind(p, 0) == 0 ? e.substr(p.size()) : e;
  };
  const std::string ok = "float shadowVisibility(ShadowQuery q) { return 1.0; }\n";
  EXPECT_EQ(errorFor("a.glsl", "// shadowlab: key r float 1 range 0..2 extra\n" + ok),
            ":1:40: error: got \"extra\" after the range; expected the end of the line");
  EXPECT_EQ(errorFor("b.glsl", "// shadowlab: key r float 1\n// shadowlab: key r int 1\n" + ok),
            ":2:19: error: key \"r\" declared twice (first on line 1)");
  EXPECT_EQ(errorFor("c.glsl", "// shadowlab: key Radius float 1\n" + ok),
            ":1:19: error: key name \"Radius\"; expected lowercase letters, digits and _ (a GLSL identifier)");
  EXPECT_EQ(errorFor("d.glsl", "  #  version 450\n" + ok).substr(0, 21), ":1:1: error: #version");
  EXPECT_EQ(errorFor("e.glsl", std::string("float x;\0", 9) + ok),
            ":1:9: error: byte 0x00 is not UTF-8 text; "
            "expected a GLSL source file (UTF-8, no NUL bytes)");
  // A comment mentioning #include or another function is not code.
  EXPECT_EQ(errorFor("f.glsl", "/* #include \"x\"\nfloat shadowVisibilty(ShadowQuery q) {} */\n" + ok), "(no error)");
}

}  // namespace raster_technique_keys_test
