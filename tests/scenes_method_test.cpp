// Method keys: files, --set text and JSON values share one table; every rejection names the
// origin and the key (or the JSON pointer in files) with what was found and what was expected.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/method.h"

namespace scenes_method_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

std::string badInputDir() { return std::string(SHADOWLAB_SOURCE_DIR) + "/tests/bad_input"; }

std::string errorOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError thrown)";
}

std::string setError(const std::string& key, const std::string& value) {
  Method m;
  return errorOf([&] { applyMethodSetting(m, key, value, "--set"); });
}

fs::path tempFile(const std::string& name, const std::string& text) {
  fs::path dir = fs::temp_directory_path() / ("shadowlab_scenes_method_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  writeFileAtomic((dir / name).string(), text);
  return dir / name;
}

// methodToJson(m), after checking that it reads back into the same Method.
nlohmann::json roundTripped(const Method& m) {
  nlohmann::json j = methodToJson(m);
  Method back;
  for (const auto& [k, v] : j.items()) applyMethodJson(back, k, v, "rt");
  EXPECT_EQ(methodToJson(back), j);
  return j;
}

}  // namespace

TEST(ScenesMethod, KeysInDocumentationOrder) {
  EXPECT_EQ(methodKeys(), (std::vector<std::string>{"map.size",
                                                    "map.format",
                                                    "cull",
                                                    "fit",
                                                    "cascades.count",
                                                    "cascades.lambda",
                                                    "cascades.blend",
                                                    "cascades.stabilize",
                                                    "sdsm.lambda",
                                                    "sdsm.snap",
                                                    "lispsm.n_scale",
                                                    "psm.slide_back",
                                                    "tsm.focus",
                                                    "tsm.focus_distance",
                                                    "bias.constant",
                                                    "bias.slope",
                                                    "bias.clamp",
                                                    "bias.compare",
                                                    "bias.normal",
                                                    "bias.receiver_plane",
                                                    "bias.adaptive",
                                                    "bias.adaptive_epsilon",
                                                    "filter",
                                                    "filter.size",
                                                    "filter.taps",
                                                    "filter.radius",
                                                    "filter.blur",
                                                    "vsm.min_variance",
                                                    "vsm.bleed_reduction",
                                                    "evsm.exponent_pos",
                                                    "evsm.exponent_neg",
                                                    "msm.moment_bias",
                                                    "pcss.blocker_taps",
                                                    "pcss.filter_taps",
                                                    "pcss.min_filter",
                                                    "pcss.max_penumbra",
                                                    "pcss.rotate",
                                                    "dpcf.taps",
                                                    "dpcf.max_penumbra",
                                                    "dpcf.rotate",
                                                    "projector.reverse_guard",
                                                    "technique",
                                                    "renderer"}));
}

TEST(ScenesMethod, SetEveryKeyFromText) {
  Method m;
  applyMethodSetting(m, "map.size", "4096", "--set");
  applyMethodSetting(m, "map.format", "d32f", "--set");
  applyMethodSetting(m, "cull", "front", "--set");
  applyMethodSetting(m, "fit", "tight", "--set");
  applyMethodSetting(m, "bias.constant", "-2.5", "--set");
  applyMethodSetting(m, "bias.slope", "3e-1", "--set");
  applyMethodSetting(m, "bias.clamp", "0.01", "--set");
  applyMethodSetting(m, "bias.compare", "0.001", "--set");
  applyMethodSetting(m, "bias.normal", "1.5", "--set");
  applyMethodSetting(m, "bias.adaptive", "true", "--set");
  applyMethodSetting(m, "bias.adaptive_epsilon", "0.01", "--set");
  EXPECT_TRUE(m.biasAdaptive);
  EXPECT_FLOAT_EQ(m.biasAdaptiveEpsilon, 0.01f);
  EXPECT_THROW(applyMethodSetting(m, "bias.adaptive_epsilon", "-0.1", "--set"), InputError);
  applyMethodSetting(m, "bias.receiver_plane", "1", "--set");
  applyMethodSetting(m, "filter", "poisson", "--set");
  applyMethodSetting(m, "filter.size", "7", "--set");
  applyMethodSetting(m, "filter.taps", "32", "--set");
  applyMethodSetting(m, "filter.radius", "2.25", "--set");
  applyMethodSetting(m, "projector.reverse_guard", "false", "--set");
  applyMethodSetting(m, "name", "mine", "--set");
  EXPECT_EQ(m.mapSize, 4096);
  EXPECT_EQ(m.mapFormat, DepthFormat::D32F);
  EXPECT_EQ(m.cull, CullMode::Front);
  EXPECT_EQ(m.fit, Fit::Tight);
  EXPECT_FLOAT_EQ(m.biasConstant, -2.5f);
  EXPECT_FLOAT_EQ(m.biasSlope, 0.3f);
  EXPECT_FLOAT_EQ(m.biasClamp, 0.01f);
  EXPECT_FLOAT_EQ(m.biasCompare, 0.001f);
  EXPECT_FLOAT_EQ(m.biasNormal, 1.5f);
  EXPECT_TRUE(m.biasReceiverPlane);
  EXPECT_EQ(m.filter, Filter::Poisson);
  EXPECT_EQ(m.filterSize, 7);
  EXPECT_EQ(m.filterTaps, 32);
  EXPECT_FLOAT_EQ(m.filterRadius, 2.25f);
  EXPECT_FALSE(m.projectorReverseGuard);
  EXPECT_EQ(m.name, "mine");
  validateMethod(m, "--set");

  // Bools: true/false/1/0 in both forms.
  applyMethodSetting(m, "bias.receiver_plane", "0", "--set");
  EXPECT_FALSE(m.biasReceiverPlane);
  applyMethodJson(m, "bias.receiver_plane", 1, "grid");
  EXPECT_TRUE(m.biasReceiverPlane);
  applyMethodJson(m, "bias.receiver_plane", false, "grid");
  EXPECT_FALSE(m.biasReceiverPlane);
}

TEST(ScenesMethod, JsonRoundTrip) {
  Method m;
  m.name = "rt";
  m.mapSize = 512;
  m.mapFormat = DepthFormat::D16;
  m.cull = CullMode::None;
  m.filter = Filter::Bilinear4;
  m.biasSlope = 0.125f;
  m.biasNormal = 2.0f;
  m.projectorReverseGuard = false;
  nlohmann::json j = methodToJson(m);
  // every key but technique and renderer (written only when set), and name
  EXPECT_EQ(j.size(), methodKeys().size() - 1);
  Method back;
  for (const auto& [k, v] : j.items()) applyMethodJson(back, k, v, "rt");
  EXPECT_EQ(methodToJson(back), j);
  EXPECT_EQ(j["map.format"], "d16");
  EXPECT_EQ(j["filter"], "bilinear4");
}

TEST(ScenesMethod, TextErrorsAreExact) {
  EXPECT_EQ(setError("map.size", "abc"),
            "--set: map.size: error: got \"abc\"; expected an integer 16..16384 (16384: the largest 2D image every "
            "Vulkan device must support, lavapipe's limit)");
  EXPECT_EQ(setError("map.size", "8"),
            "--set: map.size: error: got \"8\"; expected an integer 16..16384 (16384: the largest 2D image every "
            "Vulkan device must support, lavapipe's limit)");
  EXPECT_EQ(setError("map.size", "1024.5"),
            "--set: map.size: error: got \"1024.5\"; expected an integer 16..16384 (16384: the largest 2D image every "
            "Vulkan device must support, lavapipe's limit)");
  EXPECT_EQ(setError("filter", "pcff"),
            "--set: filter: error: got \"pcff\"; expected one of none, hw2x2, bilinear4, pcf, poisson, vsm, evsm2, "
            "evsm4, msm, pcss, dpcf");
  EXPECT_EQ(setError("map.format", "d8"), "--set: map.format: error: got \"d8\"; expected one of d16, d24, d32f");
  EXPECT_EQ(setError("bias.receiver_plane", "yes"),
            "--set: bias.receiver_plane: error: got \"yes\"; expected true, false, 1 or 0");
  EXPECT_EQ(setError("filter.size", "-3"), "--set: filter.size: error: got \"-3\"; expected an integer 3..15");
  EXPECT_EQ(setError("filter.taps", "-1"), "--set: filter.taps: error: got \"-1\"; expected an integer 1..64");
  EXPECT_EQ(setError("filter.radius", "0"),
            "--set: filter.radius: error: got \"0\"; expected a number > 0 and <= 32 (map texels)");
  EXPECT_EQ(setError("bias.normal", "-1"),
            "--set: bias.normal: error: got \"-1\"; expected a number 0..64 (map texels)");
  EXPECT_NE(
      setError("nope", "1").find("--set: nope: error: unknown method key \"nope\"; expected one of name, map.size,"),
      std::string::npos);
  // NaN and infinity in every spelling strtod accepts.
  for (const char* v : {"nan", "NaN", "inf", "-inf", "infinity", "1e999", "0x1p3", ""})
    EXPECT_NE(setError("bias.slope", v).find("--set: bias.slope: error: got \""), std::string::npos) << v;
}

// Bytes that are not UTF-8 (a --set argument may hold any): an input error quoting them as U+FFFD,
// not nlohmann's type_error 316 escaping from the message builder (found by fuzz_method).
TEST(ScenesMethod, ValueThatIsNotUtf8IsAnInputError) {
  EXPECT_EQ(setError("fit", "cascad\xffhes"),
            "--set: fit: error: got \"cascad\xef\xbf\xbdhes\"; expected one of sphere, tight, cascades, lispsm, psm, "
            "tsm, sdsm");
  EXPECT_NE(setError("map.size", "\xff\xfe").find("--set: map.size: error: got \""), std::string::npos);
}

TEST(ScenesMethod, JsonErrors) {
  Method m;
  EXPECT_EQ(errorOf([&] { applyMethodJson(m, "map.size", "2048", "grid.json: /grid/map.size/1"); }),
            "grid.json: /grid/map.size/1: map.size: error: got \"2048\"; expected an integer 16..16384 (16384: the "
            "largest 2D image every Vulkan device must support, lavapipe's limit)");
  EXPECT_EQ(errorOf([&] { applyMethodJson(m, "bias.slope", std::numeric_limits<double>::infinity(), "g"); }),
            "g: bias.slope: error: got inf (a number too large for a double); expected a finite number -1e6..1e6");
  EXPECT_EQ(errorOf([&] { applyMethodJson(m, "cull", 3, "g"); }),
            "g: cull: error: got 3; expected one of back, front, none");
  EXPECT_EQ(errorOf([&] { applyMethodJson(m, "bias.receiver_plane", 2, "g"); }),
            "g: bias.receiver_plane: error: got 2; expected true, false, 1 or 0");
  // An integral float is an integer; a fractional one is not.
  applyMethodJson(m, "map.size", 1024.0, "g");
  EXPECT_EQ(m.mapSize, 1024);
  EXPECT_NE(errorOf([&] { applyMethodJson(m, "map.size", 1024.5, "g"); }).find("got 1024.5"), std::string::npos);
}

TEST(ScenesMethod, ValidateCrossField) {
  Method m;
  m.filterSize = 4;
  EXPECT_EQ(errorOf([&] { validateMethod(m, "x.json"); }),
            "x.json: filter.size: error: got 4; expected an odd integer 3..15");
  m.filterSize = 5;
  validateMethod(m, "x.json");
}

TEST(ScenesMethodFile, LoadsWithCommentsAndDefaultsTheName) {
  fs::path p = tempFile("pcf5.json", R"(// a comment
  { "map.size": 1024, /* inline */ "filter": "pcf", "filter.size": 5, "bias.slope": 2 })");
  Method m = loadMethodFile(p.string());
  EXPECT_EQ(m.name, "pcf5");  // unnamed file: the file stem
  EXPECT_EQ(m.mapSize, 1024);
  EXPECT_EQ(m.filter, Filter::Pcf);
  EXPECT_EQ(m.filterSize, 5);
  EXPECT_FLOAT_EQ(m.biasSlope, 2.0f);
  EXPECT_EQ(m.mapFormat, DepthFormat::D24);  // untouched keys keep their defaults
  fs::path named = tempFile("n.json", R"({"name": "soft", "filter": "hw2x2"})");
  EXPECT_EQ(loadMethodFile(named.string()).name, "soft");
}

// Each tests/bad_input/method_*.json states its expected message in a "// expect: " line.
TEST(ScenesMethodFile, BadInputsAreRejectedWithTheirMessage) {
  int count = 0;
  for (const auto& e : fs::directory_iterator(badInputDir())) {
    std::string name = e.path().filename().string();
    if (name.rfind("method_", 0) != 0) continue;
    ++count;
    std::string text = readFile(e.path().string());
    std::smatch match;
    ASSERT_TRUE(std::regex_search(text, match, std::regex("// expect: ([^\n]*)"))) << name << " has no // expect: line";
    std::string msg = errorOf([&] { loadMethodFile(e.path().string()); });
    EXPECT_EQ(msg.rfind(e.path().string(), 0), 0u) << "the message must start with the file path: " << msg;
    EXPECT_NE(msg.find(match[1].str()), std::string::npos)
        << name << "\n  got:      " << msg << "\n  expected: " << match[1];
  }
  EXPECT_GE(count, 8);
}

TEST(ScenesMethodFile, MissingFile) {
  std::string msg = errorOf([] { loadMethodFile("/nonexistent/m.json"); });
  EXPECT_EQ(msg.rfind("/nonexistent/m.json: error: cannot open file", 0), 0u) << msg;
}

// The cascade keys: defaults as documented in raster/METHODS.md, ranges enforced with the key
// named, and the JSON round trip keeps them.
TEST(ScenesMethod, CascadeKeys) {
  Method d;
  EXPECT_EQ(d.cascadeCount, 4);
  EXPECT_FLOAT_EQ(d.cascadeLambda, 0.75f);
  EXPECT_FLOAT_EQ(d.cascadeBlend, 0.0f);
  EXPECT_FALSE(d.cascadeStabilize);
  Method m;
  applyMethodSetting(m, "fit", "cascades", "--set");
  applyMethodSetting(m, "cascades.count", "8", "--set");
  applyMethodSetting(m, "cascades.lambda", "0.5", "--set");
  applyMethodSetting(m, "cascades.blend", "0.1", "--set");
  applyMethodSetting(m, "cascades.stabilize", "true", "--set");
  EXPECT_EQ(m.fit, Fit::Cascades);
  EXPECT_EQ(m.cascadeCount, 8);
  EXPECT_FLOAT_EQ(m.cascadeLambda, 0.5f);
  EXPECT_FLOAT_EQ(m.cascadeBlend, 0.1f);
  EXPECT_TRUE(m.cascadeStabilize);
  nlohmann::json j = roundTripped(m);
  EXPECT_EQ(j["fit"], "cascades");
  EXPECT_EQ(j["cascades.count"], 8);
  EXPECT_EQ(setError("cascades.count", "0"),
            "--set: cascades.count: error: got \"0\"; expected an integer 1..8 (the resolve shader's 8 light layers, "
            "resolve_abi.h)");
  EXPECT_EQ(setError("cascades.count", "9"),
            "--set: cascades.count: error: got \"9\"; expected an integer 1..8 (the resolve shader's 8 light layers, "
            "resolve_abi.h)");
  EXPECT_EQ(setError("cascades.lambda", "1.5"),
            "--set: cascades.lambda: error: got \"1.5\"; expected a number 0..1 (0 uniform, 1 logarithmic splits)");
  EXPECT_EQ(
      setError("cascades.blend", "0.6"),
      "--set: cascades.blend: error: got \"0.6\"; expected a number 0..0.5 (fraction of a cascade's depth range)");
  EXPECT_EQ(setError("cascades.stabilize", "maybe"),
            "--set: cascades.stabilize: error: got \"maybe\"; expected true, false, 1 or 0");
  Method hand;
  hand.cascadeCount = 0;
  EXPECT_THROW(validateMethod(hand, "code"), InputError);
}

// fit=sdsm: the kind (in every fit listing, code 6), its keys sdsm.lambda (1 by default, apart
// from cascades.lambda) and sdsm.snap (off by default), the JSON round trip, and both as cascaded
// fits (cascades.count layers).
TEST(ScenesMethod, SdsmKeys) {
  EXPECT_FALSE(Method().sdsmSnap);
  EXPECT_EQ(Method().sdsmLambda, 1.0f);
  EXPECT_EQ(Method().cascadeLambda, 0.75f);
  const KindInfo<Fit>* kind = findKind(fitKinds(), "sdsm");
  ASSERT_NE(kind, nullptr);
  EXPECT_EQ(int(kind->kind), 6);
  EXPECT_NE(kindKeys(fitKinds()).find("tsm, sdsm"), std::string::npos);
  Method m;
  applyMethodSetting(m, "fit", "sdsm", "--set");
  applyMethodSetting(m, "sdsm.snap", "true", "--set");
  applyMethodSetting(m, "sdsm.lambda", "0.5", "--set");
  EXPECT_EQ(m.fit, Fit::Sdsm);
  EXPECT_TRUE(m.sdsmSnap);
  EXPECT_EQ(m.sdsmLambda, 0.5f);
  EXPECT_EQ(m.cascadeLambda, 0.75f);
  validateMethod(m, "--set");
  nlohmann::json j = roundTripped(m);
  EXPECT_EQ(j["fit"], "sdsm");
  EXPECT_EQ(j["sdsm.snap"], true);
  EXPECT_EQ(j["sdsm.lambda"], 0.5);
  EXPECT_EQ(setError("sdsm.lambda", "1.5"),
            "--set: sdsm.lambda: error: got \"1.5\"; expected a number 0..1 (0 uniform, 1 logarithmic splits)");
  applyMethodJson(m, "sdsm.snap", 0, "grid");
  EXPECT_FALSE(m.sdsmSnap);
  EXPECT_EQ(setError("sdsm.snap", "yes"), "--set: sdsm.snap: error: got \"yes\"; expected true, false, 1 or 0");
  EXPECT_TRUE(isCascadedFit(Fit::Sdsm));
  EXPECT_TRUE(isCascadedFit(Fit::Cascades));
  for (Fit f : {Fit::Sphere, Fit::Tight, Fit::Lispsm, Fit::Psm, Fit::Tsm}) EXPECT_FALSE(isCascadedFit(f));
}

// fit=lispsm and its one key: the default 1 (n_opt itself), a positive finite scale, and the
// JSON round trip; 0, negatives, NaN and infinity are refused with the key named.
TEST(ScenesMethod, LispsmKeys) {
  Method d;
  EXPECT_FLOAT_EQ(d.lispsmNScale, 1.0f);
  Method m;
  applyMethodSetting(m, "fit", "lispsm", "--set");
  applyMethodSetting(m, "lispsm.n_scale", "2.5", "--set");
  EXPECT_EQ(m.fit, Fit::Lispsm);
  EXPECT_FLOAT_EQ(m.lispsmNScale, 2.5f);
  validateMethod(m, "--set");
  nlohmann::json j = roundTripped(m);
  EXPECT_EQ(j["fit"], "lispsm");
  EXPECT_EQ(j["lispsm.n_scale"], 2.5);
  const std::string expected = "expected a number > 0 and <= 1e6 (1: the optimal n of Wimmer et al.)";
  EXPECT_EQ(setError("lispsm.n_scale", "0"), "--set: lispsm.n_scale: error: got \"0\"; " + expected);
  EXPECT_EQ(setError("lispsm.n_scale", "-1"), "--set: lispsm.n_scale: error: got \"-1\"; " + expected);
  EXPECT_EQ(setError("lispsm.n_scale", "nan"), "--set: lispsm.n_scale: error: got \"nan\"; " + expected);
  EXPECT_EQ(setError("lispsm.n_scale", "inf"), "--set: lispsm.n_scale: error: got \"inf\"; " + expected);
  EXPECT_EQ(setError("lispsm.n_scale", "2e6"), "--set: lispsm.n_scale: error: got \"2e6\"; " + expected);
  EXPECT_EQ(setError("fit", "pssm"),
            "--set: fit: error: got \"pssm\"; expected one of sphere, tight, cascades, lispsm, psm, tsm, sdsm");
  Method json;
  EXPECT_EQ(errorOf([&] { applyMethodJson(json, "lispsm.n_scale", 0.0, "grid"); }),
            "grid: lispsm.n_scale: error: got 0.0; " + expected);
  // A file: the JSON pointer names the key.
  fs::path file = tempFile("nscale.json", R"({"fit": "lispsm", "lispsm.n_scale": -0.5})");
  EXPECT_EQ(errorOf([&] { loadMethodFile(file.string()); }),
            file.string() + ": /lispsm.n_scale: error: got -0.5; " + expected);
  fs::remove_all(file.parent_path());
  // A hand-built Method with a NaN scale is refused by the cross-field check.
  Method hand;
  hand.lispsmNScale = std::nanf("");
  EXPECT_THROW(validateMethod(hand, "code"), InputError);
  hand.lispsmNScale = 0.0f;
  EXPECT_THROW(validateMethod(hand, "code"), InputError);
}

// fit=psm and its one key: the default 0 (the paper's PSM: the virtual camera slides back only as
// far as the casters need), a share of the visible depth range up to 1000, the JSON round trip;
// negatives, NaN, infinity and more than 1000 are refused with the key named.
TEST(ScenesMethod, PsmKeys) {
  Method d;
  EXPECT_FLOAT_EQ(d.psmSlideBack, 0.0f);
  Method m;
  applyMethodSetting(m, "fit", "psm", "--set");
  applyMethodSetting(m, "psm.slide_back", "0.25", "--set");
  EXPECT_EQ(m.fit, Fit::Psm);
  EXPECT_FLOAT_EQ(m.psmSlideBack, 0.25f);
  validateMethod(m, "--set");
  nlohmann::json j = roundTripped(m);
  EXPECT_EQ(j["fit"], "psm");
  EXPECT_EQ(j["psm.slide_back"], 0.25);
  const std::string expected = "expected a number 0..1000 (units of the visible view-depth range; 0: the paper's PSM)";
  for (const char* bad : {"-0.1", "nan", "inf", "1001"})
    EXPECT_EQ(setError("psm.slide_back", bad),
              std::string("--set: psm.slide_back: error: got \"") + bad + "\"; " + expected);
  fs::path file = tempFile("slide.json", R"({"fit": "psm", "psm.slide_back": -1})");
  EXPECT_EQ(errorOf([&] { loadMethodFile(file.string()); }),
            file.string() + ": /psm.slide_back: error: got -1; " + expected);
  fs::remove_all(file.parent_path());
  Method hand;
  hand.psmSlideBack = std::nanf("");
  EXPECT_THROW(validateMethod(hand, "code"), InputError);
  hand.psmSlideBack = -1.0f;
  EXPECT_THROW(validateMethod(hand, "code"), InputError);
}

// fit=tsm and its two keys (the 80 % rule's target line and the focus region's end): defaults 0.8
// and 0.5, the JSON round trip, and the open ends refused with the key named.
TEST(ScenesMethod, TsmKeys) {
  Method d;
  EXPECT_FLOAT_EQ(d.tsmFocus, 0.8f);
  EXPECT_FLOAT_EQ(d.tsmFocusDistance, 0.5f);
  Method m;
  applyMethodSetting(m, "fit", "tsm", "--set");
  applyMethodSetting(m, "tsm.focus", "0.7", "--set");
  applyMethodSetting(m, "tsm.focus_distance", "1", "--set");
  EXPECT_EQ(m.fit, Fit::Tsm);
  validateMethod(m, "--set");
  nlohmann::json j = roundTripped(m);
  EXPECT_EQ(j["fit"], "tsm");
  EXPECT_FLOAT_EQ(j["tsm.focus"].get<float>(), 0.7f);
  EXPECT_EQ(j["tsm.focus_distance"], 1.0);
  const std::string focus = "expected a number > 0 and < 1 (the map line the focus region ends on; 0.8: the 80 % rule)";
  for (const char* bad : {"0", "1", "-0.5", "nan", "2"})
    EXPECT_EQ(setError("tsm.focus", bad), std::string("--set: tsm.focus: error: got \"") + bad + "\"; " + focus);
  const std::string distance = "expected a number > 0 and <= 1 (share of the view depth range)";
  for (const char* bad : {"0", "1.5", "inf"})
    EXPECT_EQ(setError("tsm.focus_distance", bad),
              std::string("--set: tsm.focus_distance: error: got \"") + bad + "\"; " + distance);
  Method hand;
  hand.tsmFocus = 1.0f;
  EXPECT_THROW(validateMethod(hand, "code"), InputError);
  hand.tsmFocus = 0.8f;
  hand.tsmFocusDistance = 0.0f;
  EXPECT_THROW(validateMethod(hand, "code"), InputError);
}

// Method values are floats; written as the float's exact value widened to a double they read
// 0.0005000000237487257. methodToJson (metrics.json, results.json/csv, raster.json, tuned.json)
// writes the shortest decimal that reads back to the same float, as a person would write it.
TEST(ScenesMethod, JsonNumbersAreTheShortestTextOfTheFloat) {
  const std::string text = methodToJson(Method{}).dump();
  for (const char* written : {"\"bias.compare\":0.0005,", "\"tsm.focus\":0.8,", "\"cascades.lambda\":0.75,",
                              "\"vsm.min_variance\":1e-06", "\"msm.moment_bias\":3e-05,", "\"bias.slope\":1.5,"})
    EXPECT_NE(text.find(written), std::string::npos) << written << " in " << text;
  EXPECT_EQ(text.find("0.0005000000237487257"), std::string::npos) << text;
  EXPECT_EQ(text.find("0.800000011920929"), std::string::npos) << text;
  EXPECT_EQ(jsonFloat(0.1f).get<double>(), 0.1);
  EXPECT_EQ(jsonFloat(1.0f / 3.0f).dump(), "0.33333334");
  EXPECT_EQ(jsonFloat(16777216.0f).dump(), "16777216.0");
  EXPECT_TRUE(jsonFloat(std::nanf("")).is_null()) << "no number in JSON is NaN";
  // Every value reads back to the same float, bit for bit.
  Method odd;
  odd.biasSlope = 1.0f / 3.0f;
  odd.biasCompare = 7.3e-7f;
  odd.tsmFocus = std::nextafter(0.8f, 1.0f);
  const nlohmann::json j = nlohmann::json::parse(methodToJson(odd).dump());
  Method back;
  for (const auto& key : methodKeys())
    if (j.contains(key)) applyMethodJson(back, key, j.at(key), "test");  // technique: written only when set
  EXPECT_EQ(methodToJson(back), methodToJson(odd));
  EXPECT_EQ(back.biasSlope, odd.biasSlope);
  EXPECT_EQ(back.biasCompare, odd.biasCompare);
  EXPECT_EQ(back.tsmFocus, odd.tsmFocus);
}

// filter=pcss and filter=dpcf and their keys: defaults, text and JSON, the round trip, the ranges
// (with the key named) and the cross-check of pcss.max_penumbra against pcss.min_filter.
TEST(ScenesMethod, SoftFilterKeys) {
  const Method d;
  EXPECT_EQ(d.pcssBlockerTaps, 16);
  EXPECT_EQ(d.pcssFilterTaps, 32);
  EXPECT_FLOAT_EQ(d.pcssMinFilter, 1.5f);
  EXPECT_FLOAT_EQ(d.pcssMaxPenumbra, 16.0f);
  EXPECT_TRUE(d.pcssRotate);
  EXPECT_EQ(d.dpcfTaps, 16);
  EXPECT_FLOAT_EQ(d.dpcfMaxPenumbra, 8.0f);
  EXPECT_TRUE(d.dpcfRotate);
  ASSERT_NE(findKind(filterKinds(), "pcss"), nullptr);
  ASSERT_NE(findKind(filterKinds(), "dpcf"), nullptr);
  EXPECT_EQ(int(findKind(filterKinds(), "pcss")->kind), 9);
  EXPECT_EQ(int(findKind(filterKinds(), "dpcf")->kind), 10);
  Method m;
  applyMethodSetting(m, "filter", "pcss", "--set");
  applyMethodSetting(m, "pcss.blocker_taps", "24", "--set");
  applyMethodSetting(m, "pcss.filter_taps", "48", "--set");
  applyMethodSetting(m, "pcss.min_filter", "2", "--set");
  applyMethodSetting(m, "pcss.max_penumbra", "40", "--set");
  applyMethodSetting(m, "pcss.rotate", "false", "--set");
  applyMethodSetting(m, "dpcf.taps", "12", "--set");
  applyMethodSetting(m, "dpcf.max_penumbra", "6.5", "--set");
  applyMethodSetting(m, "dpcf.rotate", "0", "--set");
  validateMethod(m, "--set");
  EXPECT_EQ(m.filter, Filter::Pcss);
  nlohmann::json j = roundTripped(m);
  EXPECT_EQ(j["filter"], "pcss");
  EXPECT_EQ(j["pcss.blocker_taps"], 24);
  EXPECT_EQ(j["pcss.filter_taps"], 48);
  EXPECT_EQ(j["pcss.min_filter"], 2.0);
  EXPECT_EQ(j["pcss.max_penumbra"], 40.0);
  EXPECT_EQ(j["pcss.rotate"], false);
  EXPECT_EQ(j["dpcf.taps"], 12);
  EXPECT_EQ(j["dpcf.max_penumbra"], 6.5);
  EXPECT_EQ(j["dpcf.rotate"], false);
  EXPECT_EQ(setError("pcss.blocker_taps", "-1"),
            "--set: pcss.blocker_taps: error: got \"-1\"; expected an integer 1..64 (the Poisson disc's 64 points, "
            "resolve_abi.h kMaxTaps)");
  EXPECT_EQ(setError("pcss.filter_taps", "65"),
            "--set: pcss.filter_taps: error: got \"65\"; expected an integer 1..64 (the Poisson disc's 64 points, "
            "resolve_abi.h kMaxTaps)");
  EXPECT_EQ(setError("dpcf.taps", "0"),
            "--set: dpcf.taps: error: got \"0\"; expected an integer 1..64 (the Poisson disc's 64 points, "
            "resolve_abi.h kMaxTaps)");
  EXPECT_EQ(setError("pcss.min_filter", "0"),
            "--set: pcss.min_filter: error: got \"0\"; expected a number > 0 and <= 32 (map texels)");
  EXPECT_EQ(setError("pcss.max_penumbra", "nan"),
            "--set: pcss.max_penumbra: error: got \"nan\"; expected a number > 0 and <= 64 (map texels, at least "
            "pcss.min_filter)");
  EXPECT_EQ(setError("dpcf.max_penumbra", "0.5"),
            "--set: dpcf.max_penumbra: error: got \"0.5\"; expected a number 1..64 (map texels)");
  EXPECT_EQ(setError("pcss.rotate", "2"), "--set: pcss.rotate: error: got \"2\"; expected true, false, 1 or 0");
  // The kernel's radius is clamped to [min_filter, max_penumbra]: an empty interval is refused.
  Method bad;
  bad.pcssMinFilter = 8.0f;
  bad.pcssMaxPenumbra = 4.0f;
  try {
    validateMethod(bad, "m.json");
    ADD_FAILURE() << "accepted max_penumbra < min_filter";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "m.json: pcss.max_penumbra: error: got 4.0; expected a number >= pcss.min_filter (8.0)");
  }
  bad = Method();
  bad.dpcfTaps = 0;
  EXPECT_THROW(validateMethod(bad, "m.json"), InputError);
}

}  // namespace scenes_method_test
