// End to end on the bundled scenes: reference (Embree) + raster (Vulkan, lavapipe) + compare.
// Each deliberate failure must show up as its own class. Resolutions are lowered (scene
// overrides) to keep the whole executable well under a minute on two cores.
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>

#include <gtest/gtest.h>
#include <unistd.h>

#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace shadowlab::compare_end_to_end_test {
namespace {

constexpr int kWidth = 480, kHeight = 270;

// One rasterizer for the whole executable (device start-up is the slow part); null when there is
// no Vulkan device, with the reason kept for the skip message.
Rasterizer* rasterizer(std::string* why) {
  static std::unique_ptr<Rasterizer> instance;
  static std::string reason;
  static bool tried = false;
  if (!tried) {
    tried = true;
    try {
      instance = std::make_unique<Rasterizer>();
    } catch (const std::exception& e) {
      reason = e.what();
    }
  }
  *why = reason;
  return instance.get();
}

#define REQUIRE_RASTERIZER(r)                                                                             \
  std::string why;                                                                                        \
  Rasterizer* r = rasterizer(&why);                                                                       \
  if (!r) {                                                                                               \
    std::fprintf(stderr, "\n*** SKIPPING: no Vulkan device for the rasterizer: %s ***\n\n", why.c_str()); \
    GTEST_SKIP() << "no Vulkan device for the rasterizer: " << why;                                       \
  }

Scene smallScene(const std::string& name) {
  return loadScene(resolveScenePath(name), {{"/camera/width", kWidth}, {"/camera/height", kHeight}});
}

Method method(const std::map<std::string, std::string>& settings) {
  Method m;
  for (const auto& [k, v] : settings) applyMethodSetting(m, k, v, "test");
  validateMethod(m, "test");
  return m;
}

// A private cache folder for this executable, removed at exit.
struct TempCache {
  std::string dir =
      (std::filesystem::temp_directory_path() / ("shadowlab-e2e-cache-" + std::to_string(::getpid()))).string();
  ReferenceCache cache{dir};
  ~TempCache() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};
ReferenceCache& cache() {
  static TempCache c;
  return c.cache;
}

struct Shares {
  Metrics m;
  std::string text;
};

Shares run(Rasterizer& r, const std::string& scene, const std::map<std::string, std::string>& settings) {
  const Scene s = smallScene(scene);
  const RunResult result = runPipeline(s, method(settings), r, cache());
  Shares out{result.metrics, ""};
  out.text = scene + ": " + result.metrics.toJson().dump();
  return out;
}

// "Dominated by" = that class holds more than half of the errors, and there are errors.
void expectDominated(const Shares& s, uint64_t classCount, const char* name, double minErrorRate) {
  EXPECT_GT(s.m.errorRate, minErrorRate) << s.text;
  EXPECT_GT(2 * classCount, s.m.errors) << name << " is not the majority of the errors: " << s.text;
}

TEST(CompareEndToEnd, ZeroBiasOnGrazingIsAcne) {
  REQUIRE_RASTERIZER(r);
  const Shares s = run(*r, "grazing", {{"bias.slope", "0"}, {"bias.constant", "0"}, {"bias.compare", "0"}});
  expectDominated(s, s.m.count(PixelClass::Acne), "acne", 0.05);
  // With the default (sensible) bias the acne is gone.
  const Shares ok = run(*r, "grazing", {});
  EXPECT_LT(ok.m.rate(PixelClass::Acne), 0.01 * s.m.rate(PixelClass::Acne)) << ok.text;
}

TEST(CompareEndToEnd, HugeBiasOnContactAndThinWallIsLeak) {
  REQUIRE_RASTERIZER(r);
  // 0.1 of the map's normalized depth is several world units here: far more than the crate's
  // height and the wall's thickness.
  for (const char* scene : {"contact", "thin_wall"}) {
    const Shares s = run(*r, scene, {{"bias.compare", "0.1"}});
    expectDominated(s, s.m.count(PixelClass::Leak), "leak", 0.005);
    EXPECT_LT(100 * s.m.count(PixelClass::Acne), s.m.count(PixelClass::Leak))
        << "a huge bias leaves (almost) no acne: " << s.text;
  }
}

TEST(CompareEndToEnd, TinyMapOnSphereOnPlaneIsAliasing) {
  REQUIRE_RASTERIZER(r);
  const Shares s = run(*r, "sphere_on_plane", {{"map.size", "32"}});
  expectDominated(s, s.m.count(PixelClass::Aliasing), "aliasing", 0.001);
  EXPECT_GT(s.m.mMedian, 10.0) << "a 32x32 map must have a large texel footprint: " << s.text;
}

// The sized light's scene against its soft truth (the reference's light samples): PCSS follows
// the penumbra, so its error over the truth's penumbra is below a fixed Poisson kernel with the same
// 32 taps and below a 5x5 PCF; the fixed kernels' errors are mostly "penumbra too hard".
TEST(CompareEndToEnd, PcssFollowsTheSoftTruthBetterThanFixedKernels) {
  REQUIRE_RASTERIZER(r);
  auto penumbraMae = [](const Shares& s) { return s.m.toJson().at("penumbra_mae").get<double>(); };
  const Shares pcss = run(*r, "soft_post", {{"filter", "pcss"}, {"map.size", "512"}});
  const Shares poisson = run(*r, "soft_post", {{"filter", "poisson"}, {"filter.taps", "32"}, {"map.size", "512"}});
  const Shares pcf = run(*r, "soft_post", {{"filter", "pcf"}, {"filter.size", "5"}, {"map.size", "512"}});
  ASSERT_GT(pcss.m.toJson().at("penumbra_pixels").get<double>(), 1000) << pcss.text;
  EXPECT_LT(penumbraMae(pcss), 0.7 * penumbraMae(poisson)) << pcss.text << "\n" << poisson.text;
  EXPECT_LT(penumbraMae(pcss), 0.7 * penumbraMae(pcf)) << pcss.text << "\n" << pcf.text;
  expectDominated(pcf, pcf.m.count(PixelClass::PenumbraHard), "penumbra_hard", 0.005);
  EXPECT_LT(pcss.m.count(PixelClass::PenumbraHard), pcf.m.count(PixelClass::PenumbraHard) / 4) << pcss.text;
}

TEST(CompareEndToEnd, ErrorFallsAsTheMapGrows) {
  REQUIRE_RASTERIZER(r);
  double previous = 2.0;
  double first = 0.0;
  for (const char* size : {"256", "1024", "4096"}) {
    const Shares s = run(*r, "sphere_on_plane", {{"map.size", size}});
    if (first == 0.0) first = s.m.errorRate;
    EXPECT_LT(s.m.errorRate, previous) << "map.size " << size << ": " << s.text;
    previous = s.m.errorRate;
  }
  EXPECT_LT(previous, 0.6 * first) << "4096 is not clearly better than 256";
}

TEST(CompareEndToEnd, FramesComparedWithThemselvesHaveZeroError) {
  REQUIRE_RASTERIZER(r);
  const Scene s = smallScene("contact");
  const RunResult result = runPipeline(s, method({{"bias.compare", "0.1"}}), *r, cache());
  ASSERT_GT(result.metrics.errors, 0u);  // the pair itself disagrees...
  for (const Frame* f : {&result.reference, &result.raster}) {
    const Metrics m = compareFrames(*f, *f);  // ...each frame with itself does not
    EXPECT_EQ(m.errors, 0u);
    EXPECT_EQ(m.count(PixelClass::GeometryMismatch), 0u);
    EXPECT_EQ(m.mae, 0.0);
    EXPECT_EQ(m.shadowIou, 1.0);
    uint64_t hits = 0;
    for (float h : f->get("hit")) hits += h >= 0.5f;
    EXPECT_EQ(m.pixelsCompared, hits);
  }
}

TEST(CompareEndToEnd, ReferenceCacheTracesOnce) {
  REQUIRE_RASTERIZER(r);
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("shadowlab-e2e-cache-once-" + std::to_string(::getpid()))).string();
  std::filesystem::remove_all(dir);
  ReferenceCache c(dir);
  const Scene s = smallScene("sphere_on_plane");
  const RunResult a = runPipeline(s, Method{}, *r, c);
  const RunResult b = runPipeline(s, Method{}, *r, c);
  EXPECT_TRUE(a.referenceTraced);
  EXPECT_FALSE(b.referenceTraced);
  EXPECT_EQ(a.metrics.toJson().dump(), b.metrics.toJson().dump());
  std::filesystem::remove_all(dir);
}

// The cache holds the Compare channel set under the /2 key. An entry written under the /1 key (every
// channel) is never read: it has another name. A file at the /2 name that lacks a Compare channel (or
// names another scene) is traced again and replaced, never compared against. No rasterizer needed.
TEST(CompareEndToEnd, ReferenceCacheHoldsTheCompareSetUnderVersionTwo) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("shadowlab-e2e-cache-v2-" + std::to_string(::getpid()))).string();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  ReferenceCache c(dir);
  const Scene s = loadScene(resolveScenePath("sphere_on_plane"), {{"/camera/width", 64}, {"/camera/height", 36}});
  ReferenceOptions all;
  all.channels = ReferenceChannels::All;
  // A /1 entry as the previous build wrote it, with its vis planted all lit: read, it would be wrong.
  Frame old = renderReference(s, all);
  std::fill(old.get("light.sun.vis").begin(), old.get("light.sun.vis").end(), 1.0f);
  const std::string oldKey = "shadowlab.reference/1;scene=" + s.hash + ";camera=" + s.camera.hash() + ";spp=1";
  const std::string oldPath = dir + "/" + hashHex(fnv1a64(oldKey.data(), oldKey.size())) + ".exr";
  writeFrameExr(old, oldPath);
  const std::string path = dir + "/" + referenceHash(s, all) + ".exr";
  ASSERT_NE(oldPath, path);

  bool traced = false;
  const Frame first = c.get(s, all, &traced);  // asks for All: the cache still holds Compare
  EXPECT_TRUE(traced);
  EXPECT_EQ(first.names, referenceChannelNames(s, ReferenceChannels::Compare));
  EXPECT_EQ(first.meta.at("channels"), "compare");
  const Frame truth = renderReference(s, all);
  EXPECT_EQ(first.get("light.sun.vis"), truth.get("light.sun.vis"));
  EXPECT_NE(first.get("light.sun.vis"), old.get("light.sun.vis"));
  EXPECT_TRUE(std::filesystem::exists(oldPath));  // left alone
  const Frame second = c.get(s, {}, &traced);
  EXPECT_FALSE(traced);
  EXPECT_EQ(second.data, first.data);

  // A /2-named file without occluder_dist: traced again, replaced by a complete entry.
  Frame partial = first;
  partial.names.pop_back();
  partial.data.pop_back();
  writeFrameExr(partial, path);
  const Frame third = c.get(s, {}, &traced);
  EXPECT_TRUE(traced);
  EXPECT_EQ(third.data, first.data);
  EXPECT_EQ(readFrameExr(path).names, first.names);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace shadowlab::compare_end_to_end_test
