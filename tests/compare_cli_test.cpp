// `shadowlab compare` and `shadowlab run` through the real binary: exit codes, messages, and
// that a refused input writes nothing.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <OpenImageIO/imageio.h>
#include <sys/wait.h>
#include <unistd.h>

#include "shadowlab/compare/compare.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/io.h"
#include "support/cli.h"

namespace shadowlab {
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

}  // namespace
}  // namespace shadowlab
