// `shadowlab compare` and `shadowlab run` through the real binary: exit codes, messages, and
// that a refused input writes nothing.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>
#include <OpenImageIO/imageio.h>
#include <sys/wait.h>
#include <unistd.h>

#include "shadowlab/compare/compare.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/raster/resolve_abi.h"
#include "shadowlab/scenes/io.h"
#include "support/cli.h"

namespace shadowlab::compare_cli_test {
namespace {

namespace fs = std::filesystem;

using Result = testing::CliRun;
using testing::slurp;

class CompareCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab-compare-cli-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& rel) const { return (dir_ / rel).string(); }
  Result shadowlab(const std::string& args) const {
    return testing::runShadowlab(args, dir_, "cd '" + dir_.string() + "' && SHADOWLAB_CACHE='" + path("cache") + "' ");
  }
  fs::path dir_;
};

// A plane lit on the left half, shadowed on the right; the raster copy has `acne` pixels shadowed
// by their own texel on the left.
Frame syntheticFrame(int w, int h, bool raster, int acne, const std::string& sceneHash = "1111222233334444") {
  Frame f;
  f.width = w;
  f.height = h;
  f.meta["scene"] = "synthetic";
  f.meta["scene_hash"] = sceneHash;
  f.meta["lights"] = {"sun"};
  f.meta["kind"] = raster ? "raster" : "reference";
  auto& hit = f.add("hit", 1.0f);
  auto& id = f.add("object_id", 1.0f);
  auto& vis = f.add("light.sun.vis", 0.0f);
  (void)hit;
  (void)id;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w / 2; ++x) vis[size_t(y) * w + x] = 1.0f;
  if (raster) {
    f.meta["light"] = "sun";
    f.meta["method"] = {{"name", "synthetic_method"}, {"map.size", 64}};
    f.add("light.sun.in_map", 1.0f);
    f.add("light.sun.occluder_id", 1.0f);
    f.add("light.sun.m", 1.0f);
    // add() may move every plane: look both up again after the last one.
    auto& rasterVis = f.get("light.sun.vis");
    auto& occ = f.get("light.sun.occluder_id");
    for (int k = 0; k < acne; ++k) {
      const size_t i = size_t(1 + k / (w / 4)) * w + k % (w / 4);
      rasterVis[i] = 0.0f;
      occ[i] = 1.0f;
    }
  }
  return f;
}

TEST_F(CompareCli, ComparesSyntheticFramesAndWritesAllOutputs) {
  fs::create_directories(path("ref"));
  fs::create_directories(path("ras"));
  writeFrameExr(syntheticFrame(96, 64, false, 0), path("ref/reference.exr"));
  writeFrameExr(syntheticFrame(96, 64, true, 37), path("ras/raster.exr"));
  writeFileAtomic(path("ras/raster.json"),
                  R"({"shadow_gpu_ms": 1.5, "camera_gpu_ms": 2.5, "readback_ms": 0.5, "device": "x"})");
  const Result r = shadowlab("compare ref ras -o out");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(slurp(path("out/metrics.json")));
  EXPECT_EQ(j.at("schema"), "shadowlab.metrics/1");
  EXPECT_EQ(j.at("scene"), "synthetic");
  EXPECT_EQ(j.at("config"), "map.size=64");  // the one name of a configuration: its method keys off their defaults
  EXPECT_EQ(j.at("light"), "sun");
  EXPECT_EQ(j.at("metrics").at("acne"), 37);
  EXPECT_EQ(j.at("metrics").at("errors"), 37);
  EXPECT_EQ(j.at("metrics").at("pixels_compared"), 96 * 64);
  EXPECT_EQ(j.at("timings").at("shadow_gpu_ms"), 1.5);
  EXPECT_TRUE(j.at("timings").contains("compare_ms"));
  for (const char* png : {"out/errors.png", "out/triptych.png"}) {
    auto in = OIIO::ImageInput::open(path(png));
    ASSERT_TRUE(in) << png;
    EXPECT_EQ(in->spec().nchannels, 3);
    if (std::string(png) == "out/triptych.png") EXPECT_GT(in->spec().width, 3 * 96);
    else EXPECT_EQ(in->spec().width, 96);
    EXPECT_GT(in->spec().height, 64);  // the legend strip
  }
}

// A raster.json from before the timing glossary (compare/TIMINGS.md): its total_ms was the render
// call's wall time, so the message names render_wall_ms; nothing is written.
TEST_F(CompareCli, RenamedRasterTimingExits2NamingTheNewName) {
  fs::create_directories(path("ref"));
  fs::create_directories(path("ras"));
  writeFrameExr(syntheticFrame(16, 8, false, 0), path("ref/reference.exr"));
  writeFrameExr(syntheticFrame(16, 8, true, 0), path("ras/raster.exr"));
  writeFileAtomic(path("ras/raster.json"), R"({"shadow_gpu_ms": 1.5, "total_ms": 9.0, "device": "x"})");
  const Result r = shadowlab("compare ref ras -o out");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("ras/raster.json: /total_ms: error: \"total_ms\" was renamed; use \"render_wall_ms\""),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
}

TEST_F(CompareCli, MissingInputExits2AndWritesNothing) {
  fs::create_directories(path("ref"));
  writeFrameExr(syntheticFrame(16, 8, false, 0), path("ref/reference.exr"));
  const Result r = shadowlab("compare ref nowhere -o out");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ref/reference.exr"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("error:"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
  const Result both = shadowlab("compare nothing nowhere -o out");
  EXPECT_EQ(both.code, 2);
  EXPECT_FALSE(fs::exists(path("out")));
}

TEST_F(CompareCli, SizeOrSceneMismatchExits2AndWritesNothing) {
  fs::create_directories(path("ref"));
  fs::create_directories(path("small"));
  fs::create_directories(path("other"));
  writeFrameExr(syntheticFrame(64, 48, false, 0), path("ref/reference.exr"));
  writeFrameExr(syntheticFrame(32, 24, true, 0), path("small/raster.exr"));
  writeFrameExr(syntheticFrame(64, 48, true, 0, "9999999999999999"), path("other/raster.exr"));
  const Result r = shadowlab("compare ref small -o out");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("64x48 vs 32x24"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ref/reference.exr"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("small/raster.exr"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
  const Result h = shadowlab("compare ref other -o out");
  EXPECT_EQ(h.code, 2) << h.err;
  EXPECT_NE(h.err.find("scene_hash"), std::string::npos) << h.err;
  EXPECT_FALSE(fs::exists(path("out")));
  const Result l = shadowlab("compare ref ref/reference.exr --light moon -o out");
  EXPECT_EQ(l.code, 2) << l.err;
  EXPECT_NE(l.err.find("moon"), std::string::npos) << l.err;
  EXPECT_FALSE(fs::exists(path("out")));
}

// Frames from files meet the value rules before a pixel is classified (frame_check.h): a NaN,
// an infinity or a value outside its channel's range, in either frame, is exit 2 naming the file,
// the channel and the first such pixel (x, y), and nothing is written. Without the check a raster
// vis of NaN or -1 counts as acne, one of 2 or Inf as lit.
TEST_F(CompareCli, NonFiniteOrOutOfRangeValuesExit2NamingChannelAndPixel) {
  fs::create_directories(path("ref"));
  fs::create_directories(path("ras"));
  const int w = 32, h = 16;
  writeFrameExr(syntheticFrame(w, h, false, 0), path("ref/reference.exr"));
  writeFrameExr(syntheticFrame(w, h, true, 0), path("ras/raster.exr"));
  ASSERT_EQ(shadowlab("compare ref ras -o good").code, 0);
  struct Case {
    bool inRaster;
    std::string channel;
    float value;
    std::string got, expected;
  };
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<Case> cases = {
      {true, "light.sun.vis", nan, "nan", "a number in [0, 1]"},
      {true, "light.sun.vis", -1.0f, "-1", "a number in [0, 1]"},
      {true, "light.sun.vis", 2.0f, "2", "a number in [0, 1]"},
      {true, "light.sun.vis", inf, "inf", "a number in [0, 1]"},
      {true, "light.sun.m", -inf, "-inf", "a finite number >= 0"},
      {true, "light.sun.occluder_id", 1.5f, "1.5", "an integer in [0, 16777216]"},
      {false, "light.sun.vis", nan, "nan", "a number in [0, 1]"},
      {false, "hit", nan, "nan", "a number in [0, 1]"},
      {false, "object_id", -2.0f, "-2", "an integer in [0, 16777216]"},
      {false, "light.sun.vis", 1e-7f - 1e-7f * 2, "-1e-07", "a number in [0, 1]"},
  };
  for (const Case& c : cases) {
    Frame f = syntheticFrame(w, h, c.inRaster, 0);
    // Two bad pixels: the message names the first in row order, (7, 3), and counts both.
    f.get(c.channel)[size_t(3) * w + 7] = c.value;
    f.get(c.channel)[size_t(9) * w + 2] = c.value;
    const std::string file = c.inRaster ? "ras/raster.exr" : "ref/reference.exr";
    fs::remove_all(path("bad"));
    fs::create_directories(path("bad"));
    writeFrameExr(f, path("bad/" + fs::path(file).filename().string()));
    const Result r = c.inRaster ? shadowlab("compare ref bad -o out") : shadowlab("compare bad ras -o out");
    EXPECT_EQ(r.code, 2) << c.channel << " " << c.got << "\n" << r.out << r.err;
    EXPECT_EQ(r.err, "bad/" + fs::path(file).filename().string() + ": " + c.channel + " pixel (7, 3): error: got " +
                         c.got + "; expected " + c.expected + " (first of 2 such pixels)\n");
    EXPECT_FALSE(fs::exists(path("out"))) << c.channel;
  }
  // occluder_dist's "unoccluded" -1 and every value of a renderer's own channel that is finite pass.
  Frame ref = syntheticFrame(w, h, false, 0);
  ref.add("light.sun.occluder_dist", -1.0f);
  ref.add("my_renderer.depth", -5.0f);
  writeFrameExr(ref, path("ref/reference.exr"));
  EXPECT_EQ(shadowlab("compare ref ras -o out").code, 0);
}

TEST_F(CompareCli, RunRefusesBadInputBeforeWriting) {
  const Result s = shadowlab("run sphere_on_plane --set map.size=0 -o out");
  EXPECT_EQ(s.code, 2) << s.err;
  EXPECT_NE(s.err.find("map.size"), std::string::npos) << s.err;
  const Result l = shadowlab("run sphere_on_plane --light moon -o out");
  EXPECT_EQ(l.code, 2) << l.err;
  EXPECT_NE(l.err.find("moon"), std::string::npos) << l.err;
  const Result m = shadowlab("run no_such_scene -o out");
  EXPECT_EQ(m.code, 2) << m.err;
  EXPECT_FALSE(fs::exists(path("out")));
  EXPECT_FALSE(fs::exists(path("cache")));  // nothing traced either
}

TEST_F(CompareCli, RunCachesTheReferenceAndKeepsImages) {
  try {
    Rasterizer probe;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\n*** SKIPPING: no Vulkan device for the rasterizer: %s ***\n\n", e.what());
    GTEST_SKIP() << "no Vulkan device: " << e.what();
  }
  const Result a = shadowlab("run sphere_on_plane --set map.size=512 --set bias.slope=2 -o a --keep-images");
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_NE(a.out.find("reference: traced"), std::string::npos) << a.out;
  const Result b = shadowlab("run sphere_on_plane --set bias.slope=2 --set map.size=512 -o b");
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(b.out.find("reference: cached"), std::string::npos) << b.out;
  const nlohmann::json ja = nlohmann::json::parse(slurp(path("a/metrics.json")));
  const nlohmann::json jb = nlohmann::json::parse(slurp(path("b/metrics.json")));
  EXPECT_EQ(ja.at("config"), "bias.slope=2,map.size=512");  // sorted by key, canonical values
  EXPECT_EQ(ja.at("metrics"), jb.at("metrics"));
  EXPECT_GT(ja.at("metrics").at("pixels_compared").get<uint64_t>(), 100000u);
  EXPECT_TRUE(fs::exists(path("a/reference.exr")));
  EXPECT_TRUE(fs::exists(path("a/raster.exr")));
  EXPECT_TRUE(fs::exists(path("a/errors.png")));
  EXPECT_TRUE(fs::exists(path("a/triptych.png")));
  EXPECT_FALSE(fs::exists(path("b/reference.exr")));
  // The kept frames compare to the same numbers through `shadowlab compare`.
  const Result c = shadowlab("compare a a -o c");
  ASSERT_EQ(c.code, 0) << c.err;
  const nlohmann::json jc = nlohmann::json::parse(slurp(path("c/metrics.json")));
  EXPECT_EQ(jc.at("metrics"), ja.at("metrics"));
}

TEST_F(CompareCli, CompareOfNothingExits2AndWritesTheMarkedOutputs) {
  // Both frames all background (a camera that sees only sky): no pixel to score. The outputs are
  // written (they show it), the metrics say so and hold no rate, and the command exits 2.
  fs::create_directories(path("ref"));
  fs::create_directories(path("ras"));
  Frame reference = syntheticFrame(48, 32, false, 0), raster = syntheticFrame(48, 32, true, 0);
  for (Frame* f : {&reference, &raster}) std::fill(f->get("hit").begin(), f->get("hit").end(), 0.0f);
  writeFrameExr(reference, path("ref/reference.exr"));
  writeFrameExr(raster, path("ras/raster.exr"));
  const Result r = shadowlab("compare ref ras -o out");
  EXPECT_EQ(r.code, 2) << r.out << r.err;
  EXPECT_EQ(r.err,
            "ref/reference.exr and ras/raster.exr: error: nothing to compare: the camera sees no surface (all "
            "1536 pixels are background in both frames: sky, or only zero-area triangles); metrics.json says "
            "\"nothing_compared\": true and its rates are null; expected a camera that sees a surface both "
            "renderers agree on\n");
  const nlohmann::json m = nlohmann::json::parse(slurp(path("out/metrics.json"))).at("metrics");
  EXPECT_EQ(m.at("pixels_compared"), 0);
  EXPECT_EQ(m.at("nothing_compared"), true);
  EXPECT_TRUE(m.at("error_rate").is_null());
  EXPECT_TRUE(m.at("shadow_iou").is_null());
  EXPECT_TRUE(fs::exists(path("out/errors.png")));
  EXPECT_TRUE(fs::exists(path("out/triptych.png")));
}

bool haveRasterizer() {
  try {
    Rasterizer probe;
    return true;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "\n*** SKIPPING: no Vulkan device for the rasterizer: %s ***\n\n", e.what());
    return false;
  }
}

// A camera that sees no surface is one rule for every command that compares a scene (the reference
// cache's check, run_pipeline.h): exit 2 with the same message naming the scene, before any raster
// work and without an output. Before, run exited 2, tune 1 ("nothing fits nan ms") and sweep 0.
TEST_F(CompareCli, CameraThatSeesOnlySkyExits2WithOneMessageFromRunSweepAndTune) {
  if (!haveRasterizer()) GTEST_SKIP() << "no Vulkan device";
  // The camera looks up, 35 to 75 degrees above the horizon: every ray misses the ground.
  writeFileAtomic(path("sky.json"), R"({
    "camera": {"position": [0, 2, 5], "look_at": [0, 8, 2], "vfov_deg": 40, "width": 64, "height": 36},
    "objects": [{"type": "plane", "name": "ground", "size": [20, 20]}],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 40, "azimuth_deg": 30}]
  })");
  const std::string message =
      "sky.json: /camera: error: scene \"sky\": the camera sees no surface (all 2304 pixels of the reference miss "
      "the geometry: sky, or only zero-area triangles); expected a camera that sees part of the scene\n";
  for (const char* command : {"run sky.json -o out", "sweep sky.json --grid map.size=256,512 -o out",
                              "tune sky.json --max-error 0.01 -o out", "tune sky.json --budget-ms 5 -o out"}) {
    const Result r = shadowlab(command);
    EXPECT_EQ(r.code, 2) << command << "\n" << r.out << r.err;
    ASSERT_GE(r.err.size(), message.size()) << command << "\n" << r.err;
    EXPECT_EQ(r.err.substr(r.err.size() - message.size()), message) << command << "\n" << r.err;
    EXPECT_FALSE(fs::exists(path("out/metrics.json"))) << command;
    EXPECT_FALSE(fs::exists(path("out/results.json"))) << command;
    // No half-written output: the folder the command made (its journal, log and lock) is gone.
    EXPECT_FALSE(fs::exists(path("out"))) << command;
    EXPECT_EQ(r.out.find("nothing fits"), std::string::npos) << command << "\n" << r.out;
    fs::remove_all(path("out"));
  }
}

TEST_F(CompareCli, RunCountsFootprintsAtTheCap) {
  if (!haveRasterizer()) GTEST_SKIP() << "no Vulkan device";
  // The shader's cap and singular ratio are compare's.
  static_assert(raster::abi::kFootprintCap == kFootprintCapPx);
  static_assert(raster::abi::kFootprintSingularRatio == kFootprintSingularRatio);
  // A point light lying in the ground plane: the ground is edge-on to it, so its map-space
  // Jacobian is singular and the rasterizer caps m at 1e6 on every ground pixel (rounding leaves
  // its singular values' ratio at 1e-7 .. 1e-6, under kFootprintSingularRatio, where an absolute
  // threshold once left m between 2e5 and 1e6 on a third of them). The block stands up from the
  // ground and keeps a finite, small footprint.
  writeFileAtomic(path("grazing_point.json"), R"({
    "camera": {"position": [0, 4, 6], "look_at": [0, 0, 0], "vfov_deg": 50, "width": 96, "height": 54},
    "objects": [{"type": "plane", "name": "ground", "size": [20, 20]},
                {"type": "box", "name": "block", "size": [1, 1, 1], "transform": {"translate": [0, 0.5, 0]}}],
    "lights": [{"type": "point", "name": "bulb", "position": [2.5, 0, 1.5]}]
  })");
  const Result r = shadowlab("run grazing_point.json -o out --keep-images");
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  const nlohmann::json m = nlohmann::json::parse(slurp(path("out/metrics.json"))).at("metrics");
  // Recount from the frames: compared pixels (hit in both, same object) whose m is at the cap, and
  // the nearest-rank statistics of the others.
  const Frame reference = readFrameExr(path("out/reference.exr"));
  const Frame raster = readFrameExr(path("out/raster.exr"));
  const std::vector<float>& mPlane = raster.get("light.bulb.m");
  const float ground = raster.get("object_id")[raster.pixelCount() - size_t(raster.width) / 2];  // bottom centre
  uint64_t compared = 0, capped = 0, cappedOffGround = 0, groundCompared = 0;
  std::vector<float> rest;
  for (size_t i = 0; i < raster.pixelCount(); ++i) {
    if (!(reference.get("hit")[i] >= 0.5f && raster.get("hit")[i] >= 0.5f &&
          reference.get("object_id")[i] == raster.get("object_id")[i]))
      continue;
    ++compared;
    groundCompared += raster.get("object_id")[i] == ground;
    if (mPlane[i] >= 1e6f) {
      ++capped;
      cappedOffGround += raster.get("object_id")[i] != ground;
    } else {
      rest.push_back(mPlane[i]);
    }
  }
  ASSERT_FALSE(rest.empty());
  std::sort(rest.begin(), rest.end());
  auto rank = [&](double p) { return double(rest[size_t(std::ceil(p * double(rest.size()))) - 1]); };
  EXPECT_EQ(m.at("pixels_compared").get<uint64_t>(), compared);
  EXPECT_EQ(m.at("m_capped").get<uint64_t>(), capped);
  EXPECT_GT(capped, compared / 2);      // most of the frame is ground
  EXPECT_EQ(capped, groundCompared);   // all of it
  EXPECT_EQ(cappedOffGround, 0u);      // the block's faces are not edge-on
  EXPECT_EQ(m.at("m_median").get<double>(), rank(0.5));
  EXPECT_EQ(m.at("m_p95").get<double>(), rank(0.95));
  EXPECT_EQ(m.at("m_max").get<double>(), double(rest.back()));
  EXPECT_LT(m.at("m_max").get<double>(), 100.0);  // the block's own footprint, not an edge-on plane's
  EXPECT_NE(r.out.find("note: " + std::to_string(capped) + " of " + std::to_string(compared) +
                       " compared pixels have the texel footprint m at its cap 1000000"),
            std::string::npos)
      << r.out;
  // `compare` on the kept frames says the same.
  const Result c = shadowlab("compare out out -o cmp");
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("note: " + std::to_string(capped) + " of"), std::string::npos) << c.out;
}

TEST_F(CompareCli, ReadmeGateLinesWorkVerbatimInOrder) {
  if (!haveRasterizer()) GTEST_SKIP() << "no Vulkan device";
  // README.md's "Commands": the `run` line, then its gate lines in the README's order, verbatim
  // (the part after `$B `, without the comment), in a fresh folder.
  std::istringstream readme(slurp(fs::path(SHADOWLAB_SOURCE_DIR) / "README.md"));
  std::string line, runLine;
  std::vector<std::string> gateLines;
  bool inCommands = false;
  while (std::getline(readme, line)) {
    if (line.rfind("## ", 0) == 0) inCommands = line == "## Commands";
    if (!inCommands) continue;
    const size_t comment = line.find("   #");
    std::string command = line.substr(0, comment);
    while (!command.empty() && command.back() == ' ') command.pop_back();
    if (command.rfind("$B run ", 0) == 0) runLine = command.substr(3);
    if (command.rfind("$B gate out/run/", 0) == 0) gateLines.push_back(command.substr(3));
  }
  ASSERT_FALSE(runLine.empty()) << "README.md's Commands section has no `$B run` line";
  ASSERT_GE(gateLines.size(), 2u) << "README.md's Commands section has no gate lines for out/run";
  const Result run = shadowlab(runLine);
  ASSERT_EQ(run.code, 0) << runLine << "\n" << run.err;
  // Gating before any baseline exists says how to make one.
  std::string plain;
  for (const std::string& g : gateLines)
    if (g.find("--update-baseline") == std::string::npos) plain = g;
  ASSERT_FALSE(plain.empty());
  const Result first = shadowlab(plain);
  EXPECT_EQ(first.code, 2) << first.err;
  EXPECT_NE(first.err.find("--update-baseline"), std::string::npos) << first.err;
  for (const std::string& g : gateLines) {
    const Result r = shadowlab(g);
    EXPECT_EQ(r.code, 0) << g << "\n" << r.out << r.err;
  }
  EXPECT_TRUE(fs::exists(path("out/base/metrics.json")));
}

}  // namespace
}  // namespace shadowlab::compare_cli_test
