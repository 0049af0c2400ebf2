// Technique files through the real binary (raster/METHODS.md "Your own technique"): run, sweep,
// tune and gate take them end to end; pcf.glsl gives the built-in filter=pcf's class counts exactly;
// every bad file exits 2 naming file:line before any output exists; a file that never returns exits
// 3 within the limit it was given; an edited file is refused by resume and gate, naming both hashes.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "support/cli.h"

namespace technique_cli_test {

namespace fs = std::filesystem;
using shadowlab::testing::freshTempDir;
using shadowlab::testing::runShadowlab;
using shadowlab::testing::slurp;

namespace {

const std::string kExamples = std::string(SHADOWLAB_SOURCE_DIR) + "/examples/techniques/";
// Small frames: the classes and the pipeline are the same as at full size.
const std::string kSmall = " --set scene:/camera/width=96 --set scene:/camera/height=64";

std::string write(const fs::path& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name, std::ios::binary) << text;
  return (dir / name).string();
}

nlohmann::json readJson(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

class TechniqueCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = freshTempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    cache = " --cache '" + (dir / "cache").string() + "'";
  }
  fs::path dir;
  std::string cache;
};

}  // namespace

// pcf.glsl at technique.size=5 against filter=pcf filter.size=5: every metric, every class count,
// the same; and the technique's method JSON names it (path, stem@hash, its key).
TEST_F(TechniqueCli, PcfFileGivesTheBuiltInClassCounts) {
  const auto a = runShadowlab(
      "run contact --set filter=pcf --set filter.size=5" + kSmall + cache + " -o " + (dir / "builtin").string(), dir);
  ASSERT_EQ(a.code, 0) << a.err;
  const auto b = runShadowlab("run contact --set technique=" + kExamples + "pcf.glsl --set technique.size=5" + kSmall +
                                  cache + " -o " + (dir / "file").string(),
                              dir);
  ASSERT_EQ(b.code, 0) << b.err;
  const nlohmann::json ma = readJson(dir / "builtin/metrics.json"), mb = readJson(dir / "file/metrics.json");
  EXPECT_EQ(ma.at("metrics"), mb.at("metrics"));
  EXPECT_GT(ma.at("metrics").at("pixels_compared").get<double>(), 1000);
  const nlohmann::json& method = mb.at("method");
  EXPECT_EQ(method.at("technique"), kExamples + "pcf.glsl");
  EXPECT_EQ(method.at("technique.size"), 5);
  EXPECT_EQ(method.at("technique.hash").get<std::string>().rfind("pcf@", 0), 0u);
  EXPECT_EQ(method.at("technique.hash").get<std::string>().size(), 4u + 16u);
}

// Each bad file: exit 2, its file:line in the message, and no output folder.
TEST_F(TechniqueCli, BadFilesExit2NamingFileAndLine) {
  struct Case {
    const char* name;
    std::string text;
    std::string extraSet;
    std::string expect;  // after "file:"
  };
  const std::string ok = "float shadowVisibility(ShadowQuery q) {\n  return 1.0;\n}\n";
  const std::vector<Case> cases = {
      {"syntax.glsl", "float shadowVisibility(ShadowQuery q) {\n  float x = q.depth +;\n  return x;\n}\n", "",
       ":2:22: error: syntax error, unexpected SEMICOLON"},
      {"missing.glsl", "float lookup(ShadowQuery q) {\n  return 1.0;\n}\n", "", ":1:1: error: no function"},
      {"misspelled.glsl", "// x\nfloat shadowVisibilty(ShadowQuery q) {\n  return 1.0;\n}\n", "",
       ":2:7: error: function \"shadowVisibilty\" (did you mean"},
      {"signature.glsl", "\n\nint shadowVisibility(ShadowQuery q) {\n  return 1;\n}\n", "", ":3:1: error: got int"},
      {"params.glsl", "float shadowVisibility(vec2 uv) {\n  return 1.0;\n}\n", "", ":1:1: error: got float"},
      {"undeclared.glsl", "// shadowlab: key radius float 1.5 range 0.25..8\n" + ok, " --set technique.radiuss=2",
       "not declared by"},
      {"default.glsl", "// shadowlab: key radius float 9 range 0.25..8\n" + ok, "", ":1:32: error: default 9 outside"},
      {"range.glsl", "// shadowlab: key radius float 1 range 8..0.25\n" + ok, "", ":1:40: error: range"},
      {"type.glsl", "\n// shadowlab: key radius double 1\n" + ok, "", ":2:26: error: type \"double\""},
      {"binary.glsl", "// caf\xe9\n" + ok, "", ":1:7: error: byte 0xe9 is not UTF-8"},
      {"include.glsl", "#include \"other.glsl\"\n" + ok, "", ":1:1: error: #include"},
  };
  for (const Case& c : cases) {
    const std::string path = write(dir, c.name, c.text);
    const fs::path out = dir / (std::string("out_") + c.name);
    const auto r =
        runShadowlab("run contact --set technique=" + path + c.extraSet + kSmall + cache + " -o " + out.string(), dir);
    EXPECT_EQ(r.code, 2) << c.name << ": " << r.err;
    const std::string expected = std::string(c.name == std::string("undeclared.glsl") ? "" : path) + c.expect;
    EXPECT_NE(r.err.find(expected), std::string::npos) << c.name << ": expected \"" << expected << "\" in " << r.err;
    if (c.name == std::string("undeclared.glsl")) {
      EXPECT_NE(r.err.find(path), std::string::npos) << r.err;
    }
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
}

// A technique may use only what the harness hands it. Each hostile file: exit 2 at its
// file:line:column before any pipeline exists (a sampler of its own at set 0 crashed lavapipe with
// SIGBUS inside vkCreateGraphicsPipelines, at set 3 with SIGSEGV; a storage buffer the function
// wrote was accepted), and no output folder. The text checks name the word; what macros hide is
// refused on glslang's AST (the pasted declaration, the global written through an out argument)
// or by the compiled module's interface (gl_SampleID, an input the harness's shader has not).
TEST_F(TechniqueCli, HostileFilesExit2BeforeAnyPipeline) {
  struct Case {
    const char* name;
    std::string text;
    std::string expect;  // after "file"
  };
  const std::string fn = "float shadowVisibility(ShadowQuery q) {\n";
  const std::vector<Case> cases = {
      {"sampler_set0.glsl",
       "layout(set=0, binding=0) uniform sampler2D extra;\n" + fn + "  return texture(extra, q.uv).r;\n}\n",
       ":1:1: error: 'layout' declares a resource or an interface variable of its own"},
      {"sampler_set3.glsl",
       "\n  layout(set=3, binding=0) uniform sampler2D extra;\n" + fn + "  return texture(extra, q.uv).r;\n}\n",
       ":2:3: error: 'layout' declares a resource"},
      {"ssbo.glsl", "buffer Evil { float evil[]; };\n" + fn + "  evil[0] = q.depth;\n  return 1.0;\n}\n",
       ":1:1: error: 'buffer' declares a resource"},
      {"uniform.glsl", "uniform float u;\n" + fn + "  return u;\n}\n", ":1:1: error: 'uniform' declares a resource"},
      {"output.glsl", "out vec4 extraOut;\n" + fn + "  return 1.0;\n}\n", ":1:1: error: 'out' at file scope"},
      {"shared.glsl", "shared float s;\n" + fn + "  return 1.0;\n}\n", ":1:1: error: 'shared' declares"},
      {"discard.glsl", fn + "  if (q.depth > 0.5) discard;\n  return 1.0;\n}\n",
       ":2:22: error: 'discard' ends the harness's pixel"},
      {"demote.glsl", fn + "  demote;\n  return 1.0;\n}\n", ":2:3: error: 'demote' ends"},
      {"barrier.glsl", fn + "  memoryBarrier();\n  return 1.0;\n}\n",
       ":2:3: error: 'memoryBarrier' writes outside the function"},
      {"image.glsl", fn + "  imageStore(img, ivec2(0), vec4(0.0));\n  return 1.0;\n}\n",
       ":2:3: error: 'imageStore' writes"},
      {"atomic.glsl", fn + "  uint c = 0u;\n  atomicAdd(c, 1u);\n  return 1.0;\n}\n",
       ":3:3: error: 'atomicAdd' writes"},
      {"harness_output.glsl", fn + "  outA = vec4(1.0);\n  return 1.0;\n}\n",
       ":2:3: error: writes 'outA', which is not one of its locals"},
      {"harness_buffer.glsl", fn + "  outPlanes[0] = 1.0;\n  return 1.0;\n}\n", ":2:3: error: writes 'outPlanes'"},
      {"global.glsl", "float g;\n" + fn + "  return modf(q.depth, g);\n}\n",
       ":3:24: error: writes 'g', which is not one"},
      {"ids.glsl", fn + "  return float(texelFetch(mapIds, ivec3(0), 0).r);\n}\n",
       ":2:27: error: reads 'mapIds', which the harness does not hand a technique"},
      {"pasted.glsl",
       "#define CAT(a, b) a##b\nCAT(lay, out)(set = 0, binding = 0) CAT(uni, form) sampler2D extra;\n" + fn +
           "  return texture(extra, q.uv).r;\n}\n",
       ":4:18: error: reads 'extra', which the harness does not hand"},
      {"sample_id.glsl", fn + "  return float(gl_SampleID);\n}\n", ":2:16: error: reads 'gl_SampleID'"},
      // What the AST check lets through, the module's interface does not: an input the harness's
      // shader has not (the built-in FrontFacing).
      {"front_facing.glsl", fn + "  return gl_FrontFacing ? 1.0 : 0.0;\n}\n",
       ":2:10: error: the compiled shader has 'gl_FrontFacing' (Input, builtin 17), which the harness's resolve "
       "shader does not declare"},
  };
  for (const Case& c : cases) {
    const std::string path = write(dir, c.name, c.text);
    const fs::path out = dir / (std::string("out_") + c.name);
    const auto r = runShadowlab("run contact --set technique=" + path + kSmall + cache + " -o " + out.string(), dir);
    EXPECT_EQ(r.code, 2) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(path + c.expect), std::string::npos)
        << c.name << ": expected \"" << path + c.expect << "\" in " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
}

// Errors the harness's shader used to report, at its own lines: each named in the user's file.
// A byte-order mark is skipped (the file runs); a file over 256 KiB is refused before it is read
// (exit 2: one of 400k statements, 8.8 MB, compiled for minutes); a file whose macros expand past
// the compile's limits ends with exit 3 naming the file and the limits, in seconds, not minutes.
TEST_F(TechniqueCli, ErrorsAtTheUsersFileAndBoundedCompiles) {
  struct Case {
    const char* name;
    std::string text;
    int code;
    std::string expect;  // after "file"
  };
  const std::string fn = "float shadowVisibility(ShadowQuery q) {\n";
  std::string big = fn;
  while (big.size() <= 256 * 1024) big += "  q.depth = q.depth * 1.0001 + 0.5;\n";
  big += "  return q.depth;\n}\n";
  std::string bomb = "#define A0 q.depth = q.depth * 1.0001 + 0.5;\n";
  for (int i = 1; i <= 8; ++i)
    bomb += "#define A" + std::to_string(i) + std::string(" A") + std::to_string(i - 1) + " A" + std::to_string(i - 1) +
            " A" + std::to_string(i - 1) + " A" + std::to_string(i - 1) + " A" + std::to_string(i - 1) + " A" +
            std::to_string(i - 1) + " A" + std::to_string(i - 1) + " A" + std::to_string(i - 1) + "\n";
  bomb += fn + "  A8\n  return q.depth;\n}\n";
  const std::vector<Case> cases = {
      {"unclosed.glsl", fn + "  if (q.depth > 0.5) {\n    return 0.0;\n  return 1.0;\n}\n", 2,
       ":1:39: error: '{' is never closed; expected a '}' before the end of the file"},
      {"closes_nothing.glsl", fn + "  return 1.0;\n}\n}\n", 2, ":4:1: error: '}' closes nothing"},
      {"main.glsl", fn + "  return 1.0;\n}\nvoid main() {}\n", 2, ":4:6: error: defines main()"},
      {"endif.glsl", fn + "  return 1.0;\n}\n#endif\n", 2, ":4:1: error: #endif closes no #if of this file"},
      {"if.glsl", "#ifdef X\n" + fn + "  return 1.0;\n}\n", 2, ":1:1: error: #if is never closed"},
      {"line.glsl", "#line 40\n" + fn + "  return 1.0;\n}\n", 2, ":1:1: error: #line in a technique file"},
      {"nul.glsl", fn + std::string("  return 1.0;\0\n}\n", 15), 2, ":2:14: error: byte 0x00 is not UTF-8"},
      {"big.glsl", big, 2,
       ": error: " + std::to_string(big.size()) + " bytes; expected a technique file of at most 256 KiB"},
      {"bom.glsl", "\xEF\xBB\xBF" + fn + "  return 1.0;\n}\n", 0, ""},
      // A macro named like the harness's parameters (Lookup L) ends with the file.
      {"macro.glsl", "#define L 2.0\n" + fn + "  return q.depth < L ? 1.0 : 0.0;\n}\n", 0, ""},
      // Syntax errors at the token glslang stopped at, not column 1.
      {"operands.glsl", fn + "  float a = 1.0;\n  float b = a * 2.0 q.depth;\n  return b;\n}\n", 2,
       ":3:21: error: syntax error, unexpected IDENTIFIER"},
      {"for.glsl", fn + "  float a = 1.0;\n  for (int i = 0; i < 3 i++) a += 1.0;\n  return a;\n}\n", 2,
       ":3:25: error: syntax error, unexpected IDENTIFIER"},
      {"undeclared.glsl", fn + "  float radius = 1.0;\n  return q.depth * r;\n}\n", 2, ":3:20: error: 'r': undeclared"},
      // A function the harness defines after the file: at the file's definition.
      {"collision.glsl", "float techniqueVisibility(Lookup L) {\n  return 1.0;\n}\n" + fn + "  return 1.0;\n}\n", 2,
       ":1:7: error: the harness's resolve.frag does not compile with this file"},
      {"bomb.glsl", bomb, 3, ": error: compiling the technique "},
  };
  for (const Case& c : cases) {
    const std::string path = write(dir, c.name, c.text);
    const fs::path out = dir / (std::string("out_") + c.name);
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = runShadowlab("run contact --set technique=" + path + kSmall + cache + " -o " + out.string(), dir);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.code, c.code) << c.name << ": " << r.err;
    if (c.code == 0) continue;
    EXPECT_NE(r.err.find(path + c.expect), std::string::npos)
        << c.name << ": expected \"" << path + c.expect << "\" in " << r.err;
    // The place is the user's file; the harness's line may follow as glslang's words.
    EXPECT_LT(r.err.find(path + ":"), r.err.find("resolve.frag:")) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
    if (c.code == 3) std::printf("%s: exit 3 after %.1f s: %s\n", c.name, seconds, r.err.c_str());
  }
}

// A file that does not end in practice, even on llvmpipe, which ends a shader's loops by itself
// after 65535 iterations (a `while (true)` returns there, and nested loops share that budget): each
// iteration is 1024 dependent steps written out (S1024, whose result the next step and the return
// value use), and the loops' bound is read from the query (16 x map.size = 32768 at map 2048), so
// the compiler can neither unroll nor drop them. At 65535 iterations a pixel that is over 6e7 steps
// per pixel: minutes of CPU for a 96 x 64 frame.
const char* const kLoopingTechnique =
    "#define S1 v = fract(v * 1.618034 + 0.31);\n"
    "#define S8 S1 S1 S1 S1 S1 S1 S1 S1\n"
    "#define S64 S8 S8 S8 S8 S8 S8 S8 S8\n"
    "#define S512 S64 S64 S64 S64 S64 S64 S64 S64\n"
    "#define S1024 S512 S512\n"
    "float shadowVisibility(ShadowQuery q) {\n"
    "  int n = int(q.mapSize) * 16;\n"
    "  float v = q.depth;\n"
    "  for (int i = 0; i < n; ++i)\n"
    "    for (int j = 0; j < n; ++j) { S1024 }\n"
    "  return v;\n"
    "}\n";

// A file that never returns: exit 3 within the limit (plus the command's own work), the message
// naming the limit, and nothing written (the output folder, created before the render, removed).
TEST_F(TechniqueCli, LoopingFileExits3WithinTheLimit) {
  const std::string path = write(dir, "loop.glsl", kLoopingTechnique);
  // The reference at 96x64 takes a fraction of a second: the time below is mostly the render's.
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = runShadowlab(
      "run contact --set technique=" + path + " --gpu-timeout-s 2" + kSmall + cache + " -o " + (dir / "out").string(),
      dir);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("the device did not finish the submitted passes within 2 s (--gpu-timeout-s)"),
            std::string::npos)
      << r.err;
  EXPECT_LT(seconds, 20.0);
  EXPECT_FALSE(fs::exists(dir / "out")) << "a half-written output folder";
  std::printf("run with the looping file: exit %d after %.2f s (limit 2 s)\n", r.code, seconds);
}

// --gpu-timeout-s on every command that renders: each ends the looping file with exit 3 within its
// limit (the default, 120 s, would outlast this test's ctest timeout), nothing written; a bad value
// is exit 2 with the same message everywhere, before any output; a sweep file's gpu_timeout_s too.
TEST_F(TechniqueCli, EveryRenderingCommandTakesTheGpuTimeout) {
  const std::string path = write(dir, "loop.glsl", kLoopingTechnique);
  const std::string env = "SHADOWLAB_CACHE='" + (dir / "cache").string() + "' ";
  const std::string sizes = " --set scene:/camera/width=96 --set scene:/camera/height=64";
  struct Command {
    const char* name;
    std::string args;  // before " --gpu-timeout-s V -o DIR"
  };
  const std::vector<Command> commands = {
      {"raster", "raster contact --set technique=" + path + sizes},
      {"stability",
       "stability contact --set technique=" + path + " --light-path elevation_deg=45:30:2" + sizes + cache},
      {"sweep", "sweep contact --set technique=" + path + sizes + " --no-report"},
      {"tune", "tune contact --fixed technique=" + path +
                   " --fixed scene:/camera/width=96 --fixed scene:/camera/height=64 --keys bias.slope --range "
                   "bias.slope=0,1 --max-error 0.5 --no-report"},
  };
  for (const Command& c : commands) {
    const fs::path out = dir / (std::string("out_") + c.name);
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = runShadowlab(c.args + " --gpu-timeout-s 2 -o " + out.string(), dir, env);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.code, 3) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find("within 2 s (--gpu-timeout-s)"), std::string::npos) << c.name << ": " << r.err;
    EXPECT_LT(seconds, 30.0) << c.name;
    EXPECT_FALSE(fs::exists(out / "results.json")) << c.name;
    EXPECT_FALSE(fs::exists(out / "metrics.json")) << c.name;
    EXPECT_FALSE(fs::exists(out / "raster.exr")) << c.name;
    EXPECT_FALSE(fs::exists(out / "stability.json")) << c.name;
    std::printf("%s with the looping file: exit %d after %.2f s (limit 2 s)\n", c.name, r.code, seconds);
    for (const char* bad : {"-1", "nan", "2e6"}) {
      const fs::path badOut = dir / (std::string("bad_") + c.name);
      const auto b = runShadowlab(c.args + " --gpu-timeout-s " + bad + " -o " + badOut.string(), dir, env);
      EXPECT_EQ(b.code, 2) << c.name << " " << bad << ": " << b.err;
      EXPECT_NE(b.err.find("--gpu-timeout-s: error: got "), std::string::npos) << c.name << ": " << b.err;
      EXPECT_NE(b.err.find("; expected seconds, a number 0..1e6"), std::string::npos) << c.name << ": " << b.err;
      EXPECT_FALSE(fs::exists(badOut)) << c.name << " " << bad;
    }
  }
  // The sweep file's key: the same limit, and the same check at its JSON pointer.
  const std::string sweepFile = write(dir, "loop_sweep.json",
                                      "{\"scenes\": [\"contact\"], \"gpu_timeout_s\": 2, \"set\": {\"technique\": \"" +
                                          path + "\", \"scene:/camera/width\": 96, \"scene:/camera/height\": 64}}\n");
  const auto t0 = std::chrono::steady_clock::now();
  const auto sf =
      runShadowlab("sweep --sweep " + sweepFile + " --no-report -o " + (dir / "out_file").string(), dir, env);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(sf.code, 3) << sf.err;
  EXPECT_NE(sf.err.find("within 2 s"), std::string::npos) << sf.err;
  EXPECT_LT(seconds, 30.0);
  const std::string badFile = write(dir, "bad_sweep.json", "{\"scenes\": [\"contact\"], \"gpu_timeout_s\": -3}\n");
  const auto bf = runShadowlab("sweep --sweep " + badFile + " --no-report -o " + (dir / "out_bad").string(), dir, env);
  EXPECT_EQ(bf.code, 2) << bf.err;
  EXPECT_NE(bf.err.find(badFile + ": /gpu_timeout_s: error: got -3; expected seconds, a number 0..1e6"),
            std::string::npos)
      << bf.err;
  EXPECT_FALSE(fs::exists(dir / "out_bad"));
}

// tune --range technique.<key>=lo:hi: a float key over lo:hi in 4 intervals (or lo:hi:n), an int
// key over every integer between; lo or hi outside the file's declared range is exit 2 naming the
// key and the file's declaration, before any output.
TEST_F(TechniqueCli, TuneRangesOverTechniqueKeys) {
  const std::string env = "SHADOWLAB_CACHE='" + (dir / "cache").string() + "' ";
  const std::string file = kExamples + "poisson_ign.glsl";
  const std::string base =
      "tune contact --fixed technique=" + file +
      " --fixed scene:/camera/width=96 --fixed scene:/camera/height=64 --max-error 0.5 --no-report";
  const auto t = runShadowlab(base + " --keys technique.radius,technique.taps --range technique.radius=0.5:4" +
                                  " --range technique.taps=2:4 -o " + (dir / "tune").string(),
                              dir, env);
  ASSERT_EQ(t.code, 0) << t.out << t.err;
  const nlohmann::json tune = readJson(dir / "tune/tune.json");
  std::map<std::string, nlohmann::json> values;
  for (const auto& k : tune.at("keys")) values[k.at("key").get<std::string>()] = k.at("values");
  EXPECT_EQ(values["technique.radius"], nlohmann::json::parse(R"(["0.5", "1.375", "2.25", "3.125", "4"])"))
      << values["technique.radius"];
  EXPECT_EQ(values["technique.taps"], nlohmann::json::parse(R"(["2", "3", "4"])")) << values["technique.taps"];
  const nlohmann::json tuned = readJson(dir / "tune/tuned.json");
  const double radius = tuned.at("technique.radius").get<double>();
  EXPECT_TRUE(radius == 0.5 || radius == 1.375 || radius == 2.25 || radius == 3.125 || radius == 4) << radius;

  // Counted intervals.
  const auto c = runShadowlab(
      base + " --keys technique.radius --range technique.radius=1:2:2 -o " + (dir / "tune2").string(), dir, env);
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_EQ(readJson(dir / "tune2/tune.json").at("keys").at(0).at("values"),
            nlohmann::json::parse(R"(["1", "1.5", "2"])"));

  struct Bad {
    std::string keys, range, expect;
  };
  const std::vector<Bad> bads = {
      {"technique.radius", "technique.radius=0.1:4",
       "--range technique.radius=0.1:4: error: lo 0.1 is outside technique.radius's declared range 0.25..8 (" + file +
           ":5); expected lo:hi within it"},
      {"technique.radius", "technique.radius=1:9",
       "hi 9 is outside technique.radius's declared range 0.25..8 (" + file + ":5)"},
      {"technique.taps", "technique.taps=0:4",
       "lo 0 is outside technique.taps's declared range 1..16 (" + file + ":6)"},
      {"technique.taps", "technique.taps=2:4:2", "expected lo:hi with finite numbers"},
      {"technique.radius", "technique.radius=3:1", "expected lo < hi"},
  };
  for (const Bad& b : bads) {
    const fs::path out = dir / "bad";
    const auto r = runShadowlab(base + " --keys " + b.keys + " --range " + b.range + " -o " + out.string(), dir, env);
    EXPECT_EQ(r.code, 2) << b.range << ": " << r.err;
    EXPECT_NE(r.err.find(b.expect), std::string::npos) << b.range << ": expected \"" << b.expect << "\" in " << r.err;
    EXPECT_FALSE(fs::exists(out)) << b.range;
  }
}

// A sweep over the three examples (and a declared key), results naming each by stem@hash; an edited
// file is refused on resume, naming both hashes; tune searches a declared key; gate passes the same
// file and refuses an edited one.
TEST_F(TechniqueCli, SweepTuneGateEndToEnd) {
  const fs::path copy = dir / "mine.glsl";
  fs::copy_file(kExamples + "poisson_ign.glsl", copy);
  const std::string grid = " --grid technique=" + kExamples + "pcf.glsl," + kExamples + "pcss.glsl," + copy.string();
  const std::string env = "SHADOWLAB_CACHE='" + (dir / "cache").string() + "' ";
  const auto s =
      runShadowlab("sweep contact" + grid + kSmall + " --no-report -o " + (dir / "sweep").string(), dir, env);
  ASSERT_EQ(s.code, 0) << s.err;
  const nlohmann::json results = readJson(dir / "sweep/results.json");
  std::set<std::string> ids;
  for (const auto& row : results.at("rows"))
    ids.insert(row.at("method").at("technique.hash").get<std::string>().substr(0, 4));
  EXPECT_EQ(ids, (std::set<std::string>{"pcf@", "pcss", "mine"}));
  const std::string csv = slurp(dir / "sweep/results.csv");
  EXPECT_NE(csv.find("technique.hash"), std::string::npos);
  EXPECT_NE(csv.find("technique.light_size"), std::string::npos);

  // Gate: the same sweep against itself passes.
  const auto g = runShadowlab(
      "gate " + (dir / "sweep/results.json").string() + " --baseline " + (dir / "sweep/results.json").string(), dir);
  EXPECT_EQ(g.code, 0) << g.out << g.err;

  // Edit the file: resume refuses, naming both hashes.
  const std::string oldId = [&] {
    for (const auto& row : results.at("rows"))
      if (row.at("method").at("technique") == copy.string())
        return row.at("method").at("technique.hash").get<std::string>();
    return std::string();
  }();
  ASSERT_FALSE(oldId.empty());
  std::ofstream(copy, std::ios::app) << "// edited\n";
  const auto again =
      runShadowlab("sweep contact" + grid + kSmall + " --no-report -o " + (dir / "sweep").string(), dir, env);
  EXPECT_EQ(again.code, 2) << again.err;
  EXPECT_NE(again.err.find(oldId), std::string::npos) << again.err;
  EXPECT_NE(again.err.find("mine@"), std::string::npos) << again.err;

  // A fresh sweep with the edited file, gated against the old results: refused, naming both.
  const auto fresh =
      runShadowlab("sweep contact" + grid + kSmall + " --no-report -o " + (dir / "sweep2").string(), dir, env);
  ASSERT_EQ(fresh.code, 0) << fresh.err;
  const auto g2 = runShadowlab(
      "gate " + (dir / "sweep2/results.json").string() + " --baseline " + (dir / "sweep/results.json").string(), dir);
  EXPECT_EQ(g2.code, 2) << g2.out << g2.err;
  EXPECT_NE(g2.err.find(oldId), std::string::npos) << g2.err;
  // On purpose: --technique-changed gates the edited file against the old metrics (a comment changed
  // nothing: they pass).
  const auto g3 = runShadowlab("gate " + (dir / "sweep2/results.json").string() + " --baseline " +
                                   (dir / "sweep/results.json").string() + " --technique-changed",
                               dir);
  EXPECT_EQ(g3.code, 0) << g3.out << g3.err;

  // Tune over a declared key of a technique fixed by --fixed.
  const auto t = runShadowlab("tune contact --fixed technique=" + kExamples + "poisson_ign.glsl" +
                                  " --fixed scene:/camera/width=96 --fixed scene:/camera/height=64" +
                                  " --keys technique.radius --range technique.radius=0.5,2,6 --max-error 0.5" +
                                  " --no-report -o " + (dir / "tune").string(),
                              dir, env);
  ASSERT_EQ(t.code, 0) << t.out << t.err;
  const nlohmann::json tuned = readJson(dir / "tune/tuned.json");
  EXPECT_EQ(tuned.at("technique"), kExamples + "poisson_ign.glsl");
  EXPECT_TRUE(tuned.contains("technique.radius"));
}

// stability takes a technique (its stability.json names it); a grid of a key one file of the grid
// does not declare is exit 2 naming that file, before any output.
TEST_F(TechniqueCli, StabilityAndAGridOfUndeclaredKeys) {
  const auto st =
      runShadowlab("stability grazing --set technique=" + kExamples + "pcss.glsl --light-path elevation_deg=45:30:3" +
                       kSmall + cache + " -o " + (dir / "stab").string(),
                   dir);
  ASSERT_EQ(st.code, 0) << st.err;
  EXPECT_EQ(readJson(dir / "stab/stability.json").at("method").at("technique.hash").get<std::string>().substr(0, 5),
            "pcss@");
  const auto g =
      runShadowlab("sweep contact --grid technique=" + kExamples + "poisson_ign.glsl," + kExamples +
                       "pcf.glsl --grid technique.taps=4,12" + kSmall + " --no-report -o " + (dir / "grid").string(),
                   dir, "SHADOWLAB_CACHE='" + (dir / "cache").string() + "' ");
  EXPECT_EQ(g.code, 2) << g.err;
  EXPECT_NE(g.err.find("technique.taps: error: not declared by " + kExamples + "pcf.glsl"), std::string::npos) << g.err;
  EXPECT_FALSE(fs::exists(dir / "grid"));
}

}  // namespace technique_cli_test
