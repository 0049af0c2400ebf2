// The adapter protocol (adapters/README.md) end to end through the CLI: manifests and their keys
// checked before anything runs, shadowlab's own rasterizer behind the protocol (adapters/
// shadowlab-raster) giving the built-in path's metrics bit for bit, and each way an adapter can fail
// (a nonzero exit, a time-out, a missing, short, NaN, out-of-range or upside-down frame, an
// error.txt) ending the command with exit 3, naming the adapter and the configuration, its output
// kept in a log, nothing scored, and a resumed sweep rendering the failed row again.
//
// The failing renderer is a small Python program written here (python3 is a dependency of the
// report): it copies frames the test made from the truth, or fails the way its `mode` key says.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/io.h"
#include "support/cli.h"

namespace adapter_protocol_test {

namespace {

namespace fs = std::filesystem;
using shadowlab::testing::freshTempDir;
using shadowlab::testing::runShadowlab;
using shadowlab::testing::slurp;

// A small frame of a scene with a clear shadow edge: the alignment check has edges to tell by.
const std::string kScene = "sphere_on_plane --set scene:/camera/width=240 --set scene:/camera/height=135";

void write(const fs::path& p, const std::string& text) {
  std::ofstream f(p);
  f << text;
}

nlohmann::json readJson(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

// The fake renderer. FAKE_FIXTURES holds vis.png and coverage.png (the truth's own shadow term)
// and the bad frames; `mode` picks what it does for a frame.
const char* kFakeProgram = R"PY(
import json, os, shutil, sys, time
request = json.load(open(sys.argv[1]))
fixtures = os.environ["FAKE_FIXTURES"]
for frame in request["frames"]:
    out, mode = frame["out"], frame["keys"]["mode"]
    print("fake: frame", frame["id"], mode, file=sys.stderr, flush=True)
    if mode == "exit":
        print("fake: giving up", file=sys.stderr)
        sys.exit(7)
    if mode == "sleep":
        time.sleep(60)
    if mode == "missing":
        continue
    if mode == "error" or (mode == "flaky" and not os.path.exists(os.path.join(fixtures, "fixed"))):
        open(os.path.join(out, "error.txt"), "w").write("no WebGL context\n")
        continue
    vis = {"good": "vis.png", "flaky": "vis.png", "short": "short.png", "nan": "nan.exr", "range": "range.exr",
           "flip": "flip.png"}[mode]
    shutil.copy(os.path.join(fixtures, vis), os.path.join(out, "vis.exr" if vis.endswith(".exr") else "vis.png"))
    if mode != "short":
        coverage = "flip_coverage.png" if mode == "flip" else "coverage.png"
        shutil.copy(os.path.join(fixtures, coverage), os.path.join(out, "coverage.png"))
    json.dump({"name": "fake 1.0", "frame_ms": 7.5, "settings": frame["keys"]}, open(os.path.join(out, "renderer.json"), "w"))
)PY";

class AdapterProtocol : public ::testing::Test {
 protected:
  fs::path dir;
  fs::path manifest;  // the fake's adapter.json
  std::string env;    // FAKE_FIXTURES=... for runShadowlab's prefix

  void SetUp() override {
    dir = freshTempDir(std::string("adapter_protocol_") +
                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir / "fake");
    fs::create_directories(dir / "fixtures");
    write(dir / "fake" / "fake.py", kFakeProgram);
    writeManifest(60, 30);
    env = "FAKE_FIXTURES='" + (dir / "fixtures").string() + "' ";
  }

  void writeManifest(double start, double perFrame) {
    manifest = dir / "fake" / "adapter.json";
    const nlohmann::json m = {
        {"shadowlab_adapter", 1},
        {"name", "fake"},
        {"description", "a renderer that copies the truth or fails on purpose"},
        {"command", {"python3", "./fake.py", "{request}"}},
        {"timeout_s", {{"start", start}, {"per_frame", perFrame}}},
        {"frame", "png"},
        {"keys",
         {{{"name", "mode"},
           {"type", "enum"},
           {"default", "good"},
           {"values", {"good", "flaky", "exit", "sleep", "missing", "error", "short", "nan", "range", "flip"}},
           {"help", "what the fake does"}},
          {{"name", "size"}, {"type", "int"}, {"default", 16}, {"min", 16}, {"max", 64}, {"help", "ignored"}}}}};
    write(manifest, m.dump(2));
  }

  // The truth's shadow term and coverage as a renderer would write them, and the bad frames.
  void makeFixtures() {
    const auto r = runShadowlab("reference " + kScene + " -o '" + (dir / "truth").string() + "'", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const shadowlab::Frame truth = shadowlab::readFrameExr((dir / "truth" / "reference.exr").string());
    const std::vector<float>& vis = truth.get("light.sun.vis");
    const std::vector<float>& hit = truth.get("hit");
    const int w = truth.width, h = truth.height;
    const fs::path f = dir / "fixtures";
    shadowlab::writeGreyPng16((f / "vis.png").string(), w, h, vis);
    shadowlab::writeGreyPng16((f / "coverage.png").string(), w, h, hit);
    std::vector<float> flipped(vis.size());
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) flipped[size_t(y) * w + x] = vis[size_t(h - 1 - y) * w + x];
    shadowlab::writeGreyPng16((f / "flip.png").string(), w, h, flipped);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) flipped[size_t(y) * w + x] = hit[size_t(h - 1 - y) * w + x];
    shadowlab::writeGreyPng16((f / "flip_coverage.png").string(), w, h, flipped);
    shadowlab::writeGreyPng16((f / "short.png").string(), 10, 10, std::vector<float>(100, 1.0f));
    for (const auto& [name, bad] : {std::pair{"nan.exr", std::nanf("")}, std::pair{"range.exr", 2.0f}}) {
      shadowlab::Frame frame;
      frame.width = w;
      frame.height = h;
      std::vector<float> v = vis;
      v[size_t(h / 2) * w + w / 2] = bad;
      frame.add("vis") = v;
      shadowlab::writeFrameExr(frame, (f / name).string());
    }
  }

  shadowlab::testing::CliRun runFake(const std::string& sets, const std::string& out) {
    return runShadowlab("run " + kScene + " --set renderer='" + manifest.string() + "' " + sets + " --cache '" +
                            (dir / "cache").string() + "' -o '" + (dir / out).string() + "'",
                        dir, env);
  }
};

TEST_F(AdapterProtocol, ManifestErrorsNameTheFileAndThePlace) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"shadowlab_adapter": 1, "name": "x", "frame": "png", "keys": []})", "/command: error: missing"},
      {R"({"shadowlab_adapter": 1, "name": "x", "command": ["run"], "frame": "png", "keys": []})",
       "/command: error: got an array of 1 value; expected an argument holding {request}"},
      {R"({"shadowlab_adapter": 2, "name": "x", "command": ["r", "{request}"], "frame": "png", "keys": []})",
       "/shadowlab_adapter: error: got 2; expected 1"},
      {R"({"shadowlab_adapter": 1, "name": "X Y", "command": ["r", "{request}"], "frame": "png", "keys": []})",
       "/name: error: got \"X Y\""},
      {R"({"shadowlab_adapter": 1, "name": "x", "command": ["r", "{request}"], "frame": "jpeg", "keys": []})",
       "/frame: error: got \"jpeg\""},
      {R"({"shadowlab_adapter": 1, "name": "x", "command": ["r", "{request}"], "frame": "png", "color": 1, "keys": []})",
       "/color: error: unknown field \"color\""},
      {R"({"shadowlab_adapter": 1, "name": "x", "command": ["r", "{request}"], "frame": "png",
          "keys": [{"name": "size", "type": "int", "default": 99, "min": 16, "max": 64, "help": "h"}]})",
       "/keys/0/default: error: got 99; expected an integer 16..64"},
      {R"({"shadowlab_adapter": 1, "name": "x", "command": ["r", "{request}"], "frame": "png",
          "keys": [{"name": "t", "type": "enum", "default": "a", "values": [], "help": "h"}]})",
       "/keys/0/values: error: got an array of 0 values; expected an array of 1..64 strings"},
      {R"({"shadowlab_adapter": 1, "name": "x", "command": ["r", "{request}"], "frame": "png",
          "timeout_s": {"start": -1}, "keys": []})",
       "/timeout_s/start: error: got -1"},
      {R"({"shadowlab_adapter": 1, "name": "x", "command": ["r", "{request}"], "frame": "png", "keys": [)",
       "adapter.json:1:"},
  };
  for (const auto& [text, expected] : cases) {
    write(dir / "adapter.json", text);
    const auto r = runShadowlab("methods --renderer '" + (dir / "adapter.json").string() + "'", dir);
    EXPECT_EQ(r.code, 2) << text;
    EXPECT_NE(r.err.find(expected), std::string::npos) << text << "\n" << r.err;
  }
  const auto missing =
      runShadowlab("run contact --set renderer=no_such_adapter -o '" + (dir / "o").string() + "'", dir);
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("adapters/no_such_adapter/adapter.json: error: no such file"), std::string::npos)
      << missing.err;
  EXPECT_FALSE(fs::exists(dir / "o"));
}

TEST_F(AdapterProtocol, MethodKeysAreCheckedAgainstTheManifest) {
  const auto listed = runShadowlab("methods --renderer '" + manifest.string() + "'", dir);
  ASSERT_EQ(listed.code, 0) << listed.err;
  EXPECT_NE(listed.out.find("fake.mode"), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("expected an integer 16..64"), std::string::npos) << listed.out;
  const auto bundled = runShadowlab("methods --renderer three --json", dir);
  ASSERT_EQ(bundled.code, 0) << bundled.err;
  EXPECT_EQ(nlohmann::json::parse(bundled.out)["renderer"]["name"], "three");

  struct Case {
    std::string sets, expected;
  };
  const std::vector<Case> cases = {
      {"--set fake.nope=1", "fake.nope: error: not declared by"},
      {"--set fake.size=65", "fake.size: error: got \"65\"; expected an integer 16..64"},
      {"--set fake.size=17.5", "expected an integer 16..64"},
      {"--set fake.mode=wild", "expected one of good, flaky"},
      {"--set other.size=20", "other.size: error: not a key of renderer="},
      {"--set technique=" + std::string(SHADOWLAB_SOURCE_DIR) + "/examples/techniques/pcf.glsl",
       "technique: error: set beside renderer="},
  };
  for (const Case& c : cases) {
    const auto r = runFake(c.sets, "o");
    EXPECT_EQ(r.code, 2) << c.sets;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.sets << "\n" << r.err;
    EXPECT_FALSE(fs::exists(dir / "o")) << c.sets;
  }
  // An adapter is a program: a method or sweep file may name a bundled one only; a path runs when
  // the command line names it. Refused before anything runs.
  write(dir / "method.json", nlohmann::json{{"renderer", manifest.string()}}.dump());
  const auto fromFile = runShadowlab("run " + kScene + " --method '" + (dir / "method.json").string() + "' --cache '" +
                                         (dir / "cache").string() + "' -o '" + (dir / "o").string() + "'",
                                     dir, env);
  EXPECT_EQ(fromFile.code, 2) << fromFile.err;
  EXPECT_NE(fromFile.err.find("from a file; expected a bundled adapter's name"), std::string::npos) << fromFile.err;
  EXPECT_FALSE(fs::exists(dir / "cache" / "adapter-work")) << "nothing was started";
  write(dir / "sweep.json", nlohmann::json{{"scenes", {"contact"}}, {"set", {{"renderer", manifest.string()}}},
                                           {"grid", {{"fake.size", {16, 32}}}}}
                                .dump());
  const auto sweepFile = runShadowlab("sweep --sweep '" + (dir / "sweep.json").string() + "' --no-report --cache '" +
                                          (dir / "cache").string() + "' -o '" + (dir / "sw").string() + "'",
                                      dir, env);
  EXPECT_EQ(sweepFile.code, 2) << sweepFile.err;
  EXPECT_NE(sweepFile.err.find("from a file; expected a bundled adapter's name"), std::string::npos) << sweepFile.err;
  EXPECT_FALSE(fs::exists(dir / "sw" / "adapter"));
  // A renderer's key without renderer= is an unknown key, as before adapters existed.
  const auto stray = runShadowlab("run contact --set three.bias=0 -o '" + (dir / "o").string() + "'", dir);
  EXPECT_EQ(stray.code, 2);
  EXPECT_NE(stray.err.find("unknown method key \"three.bias\""), std::string::npos) << stray.err;
  // tune takes an adapter's keys with a --range, beside --fixed renderer=.
  const auto noRange = runShadowlab("tune contact --fixed renderer='" + manifest.string() +
                                        "' --keys fake.size --max-error 0.1 -o '" + (dir / "o").string() + "'",
                                    dir);
  EXPECT_EQ(noRange.code, 2);
  EXPECT_NE(noRange.err.find("an outside renderer's key has no default range; expected --range fake.size=v1,v2,..."),
            std::string::npos)
      << noRange.err;
  const auto noRenderer = runShadowlab(
      "tune contact --keys three.bias --range three.bias=0:0.01 --max-error 0.1 -o '" + (dir / "o").string() + "'", dir);
  EXPECT_EQ(noRenderer.code, 2);
  EXPECT_NE(noRenderer.err.find("\"three.bias\" without a renderer; expected --fixed renderer=NAME"), std::string::npos)
      << noRenderer.err;
  const auto raster = runShadowlab("raster contact --set renderer=three -o '" + (dir / "o").string() + "'", dir);
  EXPECT_EQ(raster.code, 2);
  EXPECT_NE(raster.err.find("raster draws with the built-in rasterizer"), std::string::npos) << raster.err;
}

TEST_F(AdapterProtocol, APerfectFrameIsScoredWithTheRenderersOwnTime) {
  makeFixtures();
  const auto r = runFake("--set fake.size=32", "good");
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const nlohmann::json m = readJson(dir / "good" / "metrics.json");
  EXPECT_EQ(m["config"],
            "fake.size=32,renderer=" + manifest.string() + ",scene:/camera/height=135,scene:/camera/width=240");
  EXPECT_EQ(m["timings"]["renderer_frame_ms"], 7.5);
  EXPECT_GT(m["timings"]["adapter_ms"].get<double>(), 0.0);
  EXPECT_GT(m["metrics"]["pixels_compared"].get<double>(), 20000);
  // The truth's own shadow term, written as 16 bits: only where the 16-bit code rounds a
  // fractional edge pixel across the lit decision can it differ.
  EXPECT_LT(m["metrics"]["error_rate"].get<double>(), 1e-3);
  EXPECT_EQ(m["method"]["fake.mode"], "good");
  EXPECT_EQ(m["method"]["fake.size"], 32);
  EXPECT_NE(slurp(dir / "good" / "adapter.log").find("fake: frame 0 good"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir / "good" / "renderer.json"));

  // The gate guards the renderer's settings: the same configuration rendered worse (a block of
  // lit ground drawn shadowed, as a broken update would) is a regression, exit 1.
  const shadowlab::Frame truth = shadowlab::readFrameExr((dir / "truth" / "reference.exr").string());
  std::vector<float> worse = truth.get("light.sun.vis");
  size_t planted = 0;
  for (int y = 100; y < 130; ++y)
    for (int x = 10; x < 70; ++x) {
      float& v = worse[size_t(y) * truth.width + x];
      planted += v > 0.5f ? 1 : 0;
      v = 0.0f;
    }
  ASSERT_GT(planted, 1000u);
  shadowlab::writeGreyPng16((dir / "fixtures" / "vis.png").string(), truth.width, truth.height, worse);
  const auto again = runFake("--set fake.size=32", "worse");
  ASSERT_EQ(again.code, 0) << again.err;
  const auto gate = runShadowlab("gate '" + (dir / "worse" / "metrics.json").string() + "' --baseline '" +
                                     (dir / "good" / "metrics.json").string() + "'",
                                 dir);
  EXPECT_EQ(gate.code, 1) << gate.out << gate.err;
  EXPECT_NE(gate.out.find("FAIL"), std::string::npos) << gate.out;
  const auto same = runShadowlab("gate '" + (dir / "good" / "metrics.json").string() + "' --baseline '" +
                                     (dir / "good" / "metrics.json").string() + "'",
                                 dir);
  EXPECT_EQ(same.code, 0) << same.out << same.err;
}

TEST_F(AdapterProtocol, EveryFailureIsTheAdaptersExit3WithItsLog) {
  makeFixtures();
  writeManifest(5, 2);  // the sleeping mode is stopped after 7 s
  struct Case {
    std::string mode, expected;
  };
  const std::vector<Case> cases = {
      {"exit", "the adapter exited with status 7"}, {"sleep", "the adapter timed out after 7 s"},
      {"missing", "wrote no renderer.json"},        {"error", "could not render it: no WebGL context"},
      {"short", "its frame is refused:"},           {"nan", "its frame is refused: "},
      {"range", "its frame is refused: "},          {"flip", "upside down"},
  };
  for (const Case& c : cases) {
    const auto r = runFake("--set fake.mode=" + c.mode, "o_" + c.mode);
    EXPECT_EQ(r.code, 3) << c.mode << "\n" << r.err;
    EXPECT_NE(r.err.find("renderer fake (" + manifest.string() + "), configuration fake.mode=" + c.mode),
              std::string::npos)
        << c.mode << "\n"
        << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.mode << "\n" << r.err;
    EXPECT_FALSE(fs::exists(dir / ("o_" + c.mode))) << c.mode << ": nothing is written for a failed frame";
    // The log the message names holds what the program printed.
    const size_t at = r.err.find("(its output: ");
    ASSERT_NE(at, std::string::npos) << r.err;
    const std::string log = r.err.substr(at + 13, r.err.find(')', at) - at - 13);
    EXPECT_NE(slurp(log).find("fake: frame 0 " + c.mode), std::string::npos) << log;
  }
  // nan and range name the file, the pixel and what is wrong with it.
  const auto nan = runFake("--set fake.mode=nan", "o");
  EXPECT_NE(nan.err.find("vis.exr: channel vis pixel (120, 67): error: got nan; expected a finite number"),
            std::string::npos)
      << nan.err;
  const auto range = runFake("--set fake.mode=range", "o");
  EXPECT_NE(range.err.find("(120, 67)"), std::string::npos) << range.err;
  EXPECT_NE(range.err.find("got 2"), std::string::npos) << range.err;
}

TEST_F(AdapterProtocol, ASweepRendersAScenesRowsInOneBatchAndRetriesAFailedRowOnResume) {
  makeFixtures();
  const std::string sweep = "sweep " + kScene + " --set renderer='" + manifest.string() +
                            "' --grid fake.mode=good,flaky --grid fake.size=16,32 --no-report --cache '" +
                            (dir / "cache").string() + "' -o '" + (dir / "sw").string() + "'";
  const auto first = runShadowlab(sweep, dir, env);
  EXPECT_EQ(first.code, 3) << first.err;
  EXPECT_NE(first.err.find("configuration fake.mode=flaky"), std::string::npos) << first.err;
  // One batch for the scene's four rows, in the grid's order.
  const nlohmann::json request = readJson(dir / "sw" / "adapter" / "sphere_on_plane" / "batch-0" / "request.json");
  ASSERT_EQ(request["frames"].size(), 4u);
  EXPECT_EQ(request["frames"][0]["keys"], (nlohmann::json{{"mode", "good"}, {"size", 16}}));
  EXPECT_EQ(request["width"], 240);
  EXPECT_FALSE(fs::exists(dir / "sw" / "adapter" / "sphere_on_plane" / "batch-1"));
  EXPECT_EQ(slurp(dir / "sw" / "rows.jsonl").find("flaky"), std::string::npos) << "a failed row is not scored";

  write(dir / "fixtures" / "fixed", "");
  const auto second = runShadowlab(sweep, dir, env);
  ASSERT_EQ(second.code, 0) << second.err;
  EXPECT_NE(second.err.find("resuming"), std::string::npos) << second.err;
  const nlohmann::json results = readJson(dir / "sw" / "results.json");
  ASSERT_EQ(results["rows"].size(), 4u);
  for (const auto& row : results["rows"]) {
    EXPECT_EQ(row["timings"]["renderer_frame_ms"], 7.5) << row["config"];
    EXPECT_LT(row["metrics"]["error_rate"].get<double>(), 1e-3) << row["config"];
  }
  // The retried rows alone went into the resumed sweep's batch.
  const nlohmann::json again = readJson(dir / "sw" / "adapter" / "sphere_on_plane" / "batch-0" / "request.json");
  EXPECT_LE(again["frames"].size(), 3u);

  // Two renderers of either frame kind in one sweep: a batch each, each compared as its kind is.
  const auto mixed = runShadowlab("sweep " + kScene + " --grid renderer='" + manifest.string() +
                                      "',shadowlab-raster --no-report --cache '" + (dir / "cache").string() + "' -o '" +
                                      (dir / "mixed").string() + "'",
                                  dir, env);
  ASSERT_EQ(mixed.code, 0) << mixed.err;
  const nlohmann::json mixedRows = readJson(dir / "mixed" / "results.json")["rows"];
  ASSERT_EQ(mixedRows.size(), 2u);
  for (const auto& row : mixedRows) {
    EXPECT_GT(row["metrics"]["pixels_compared"].get<double>(), 20000) << row["config"];
    EXPECT_LT(row["metrics"]["error_rate"].get<double>(), 0.05) << row["config"];
  }
  EXPECT_TRUE(fs::exists(dir / "mixed" / "adapter" / "sphere_on_plane" / "batch-1" / "request.json"));

  // A shard's batch holds its own rows only, in its own folder.
  const std::string sharded = sweep.substr(0, sweep.find(" -o ")) + " --shard 1/2 -o '" + (dir / "sh").string() + "'";
  const auto shard = runShadowlab(sharded, dir, env);
  ASSERT_EQ(shard.code, 0) << shard.err;
  const nlohmann::json part =
      readJson(dir / "sh" / "shards" / "1-of-2" / "adapter" / "sphere_on_plane" / "batch-0" / "request.json");
  EXPECT_EQ(part["frames"].size(), 2u);
}

// shadowlab's own rasterizer behind the protocol: the same frame, so the same metrics, bit for bit;
// only the timings differ. A sweep's batch and `run` both.
TEST(AdapterShadowlabRaster, MatchesTheBuiltInPathBitForBit) {
  const fs::path dir = freshTempDir("adapter_shadowlab_raster");
  const std::string scene = "contact --set scene:/camera/width=320 --set scene:/camera/height=180";
  const std::string cache = " --cache '" + (dir / "cache").string() + "'";
  const auto builtIn = runShadowlab("run " + scene + " --set map.size=512 --set filter=pcf --set bias.slope=0.5" +
                                        cache + " -o '" + (dir / "builtin").string() + "'",
                                    dir);
  ASSERT_EQ(builtIn.code, 0) << builtIn.err;
  const auto adapted = runShadowlab("run " + scene +
                                        " --set renderer=shadowlab-raster --set shadowlab-raster.map.size=512 --set "
                                        "shadowlab-raster.filter=pcf --set shadowlab-raster.bias.slope=0.5" +
                                        cache + " -o '" + (dir / "adapted").string() + "'",
                                    dir);
  ASSERT_EQ(adapted.code, 0) << adapted.err;
  const nlohmann::json a = readJson(dir / "builtin" / "metrics.json"), b = readJson(dir / "adapted" / "metrics.json");
  EXPECT_GT(a["metrics"]["errors"].get<double>(), 0) << "a configuration with errors to match";
  EXPECT_EQ(a["metrics"], b["metrics"]);
  EXPECT_GT(b["timings"]["renderer_frame_ms"].get<double>(), 0.0);

  // A sweep over both paths: every adapter row's metrics are its built-in twin's.
  const auto sweep = runShadowlab("sweep " + scene + " --grid map.size=256,1024 --no-report" + cache + " -o '" +
                                      (dir / "sw_builtin").string() + "'",
                                  dir);
  ASSERT_EQ(sweep.code, 0) << sweep.err;
  const auto sweepAdapted =
      runShadowlab("sweep " + scene +
                       " --set renderer=shadowlab-raster --grid shadowlab-raster.map.size=256,1024 "
                       "--no-report" +
                       cache + " -o '" + (dir / "sw_adapted").string() + "'",
                   dir);
  ASSERT_EQ(sweepAdapted.code, 0) << sweepAdapted.err;
  const nlohmann::json rowsA = readJson(dir / "sw_builtin" / "results.json")["rows"];
  const nlohmann::json rowsB = readJson(dir / "sw_adapted" / "results.json")["rows"];
  ASSERT_EQ(rowsA.size(), 2u);
  ASSERT_EQ(rowsB.size(), 2u);
  for (size_t i = 0; i < 2; ++i) EXPECT_EQ(rowsA[i]["metrics"], rowsB[i]["metrics"]) << rowsB[i]["config"];
  EXPECT_EQ(readJson(dir / "sw_adapted" / "adapter" / "contact" / "batch-0" / "request.json")["frames"].size(), 2u);

  // A light path (stability): every frame's metrics, and so the temporal ones, are the built-in's.
  const std::string path = " --light-path elevation_deg=60:20:3";
  const auto stable = runShadowlab("stability " + scene + path + " --set map.size=512 --set filter=pcf" + cache +
                                       " -o '" + (dir / "st_builtin").string() + "'",
                                   dir);
  ASSERT_EQ(stable.code, 0) << stable.err;
  const auto stableAdapted = runShadowlab("stability " + scene + path +
                                              " --set renderer=shadowlab-raster --set shadowlab-raster.map.size=512 "
                                              "--set shadowlab-raster.filter=pcf" +
                                              cache + " -o '" + (dir / "st_adapted").string() + "'",
                                          dir);
  ASSERT_EQ(stableAdapted.code, 0) << stableAdapted.err;
  const nlohmann::json sa = readJson(dir / "st_builtin" / "stability.json");
  const nlohmann::json sb = readJson(dir / "st_adapted" / "stability.json");
  EXPECT_EQ(sa["metrics"], sb["metrics"]);
  ASSERT_EQ(sb["per_frame"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(sa["per_frame"][i], sb["per_frame"][i]) << "frame " << i;
  // A fit-camera path moves what only the built-in rasterizer fits its map to.
  const auto dolly = runShadowlab("stability " + scene + " --path dolly --frames 3 --set renderer=shadowlab-raster -o '" +
                                      (dir / "st_dolly").string() + "'",
                                  dir);
  EXPECT_EQ(dolly.code, 2);
  EXPECT_NE(dolly.err.find("expected --light-path for an outside renderer"), std::string::npos) << dolly.err;
}

}  // namespace

}  // namespace adapter_protocol_test
