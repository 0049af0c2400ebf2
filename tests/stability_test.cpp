// Temporal stability (compare/stability.h): the camera path generators, the flip fraction on
// synthetic frames with a known answer, and shimmer on long_view: a fixed evaluation camera with
// the cascades' fit camera dollied along 32 frames, stabilized vs not.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/stability.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"

using namespace shadowlab;

namespace {

Camera testCamera() {
  Camera c;
  c.position = {1, 2, 10};
  c.lookAt = {1, 2, 0};  // looks down -z
  c.up = {0, 1, 0};
  return c;
}

// A frame of `n` pixels in a row: hit where obj > 0, light "sun" with the given visibilities.
Frame synthetic(const std::vector<float>& obj, const std::vector<float>& vis) {
  Frame f;
  f.width = int(obj.size());
  f.height = 1;
  // Add every channel before taking references: add() may move the planes.
  f.add("hit");
  f.add("object_id");
  f.add("light.sun.vis");
  auto& h = f.get("hit");
  auto& o = f.get("object_id");
  auto& v = f.get("light.sun.vis");
  for (size_t i = 0; i < obj.size(); ++i) {
    h[i] = obj[i] > 0 ? 1.0f : 0.0f;
    o[i] = obj[i];
    v[i] = vis[i];
  }
  return f;
}

}  // namespace

TEST(CameraPaths, DollyMovesAlongTheViewDirectionInEqualSteps) {
  Camera c = testCamera();
  std::vector<Camera> p = dollyPath(c, 5.0f, 6);
  ASSERT_EQ(p.size(), 6u);
  for (int k = 0; k < 6; ++k) {
    float z = 10.0f - 5.0f * float(k) / 5.0f;  // 1 world unit per step towards -z
    EXPECT_NEAR(p[size_t(k)].position.z, z, 1e-5f) << k;
    EXPECT_NEAR(p[size_t(k)].lookAt.z, z - 10.0f, 1e-5f) << k;  // view direction unchanged
    EXPECT_FLOAT_EQ(p[size_t(k)].position.x, 1.0f);
    EXPECT_FLOAT_EQ(p[size_t(k)].position.y, 2.0f);
    EXPECT_EQ(p[size_t(k)].width, c.width);
  }
  EXPECT_EQ(p[0].hash(), c.hash());  // frame 0 is the start camera exactly
  EXPECT_NEAR(dollyPath(c, -3.0f, 2)[1].position.z, 13.0f, 1e-5f);  // negative: backwards
  EXPECT_THROW(dollyPath(c, 1.0f, 1), InputError);
  Camera still = c;
  still.lookAt = still.position;
  EXPECT_THROW(dollyPath(still, 1.0f, 4), InputError);
}

TEST(CameraPaths, OrbitRotatesAboutLookAtKeepingTheDistance) {
  Camera c = testCamera();
  std::vector<Camera> p = orbitPath(c, 90.0f, 3);  // 0, 45, 90 degrees about +y through (1, 2, 0)
  ASSERT_EQ(p.size(), 3u);
  for (const Camera& q : p) {
    EXPECT_NEAR(glm::length(q.position - q.lookAt), 10.0f, 1e-4f);
    EXPECT_FLOAT_EQ(q.lookAt.z, 0.0f);
    EXPECT_NEAR(q.position.y, 2.0f, 1e-5f);
  }
  // +90 degrees about +y (right-handed) takes the offset (0, 0, 10) to (10, 0, 0).
  EXPECT_NEAR(p[2].position.x, 11.0f, 1e-4f);
  EXPECT_NEAR(p[2].position.z, 0.0f, 1e-4f);
  EXPECT_NEAR(p[1].position.x, 1.0f + 10.0f * std::sqrt(0.5f), 1e-4f);
  EXPECT_THROW(orbitPath(c, 10.0f, 0), InputError);
  EXPECT_THROW(orbitPath(c, NAN, 4), InputError);
}

// 8 pixels: 0 background, 1 geometry mismatch (excluded), 6 compared, of which 2 flip -> 2/6.
TEST(ShimmerRate, SyntheticFramesGiveTheExactFlipFraction) {
  Frame ref = synthetic({0, 1, 1, 1, 1, 1, 1, 2}, {0, 1, 1, 1, 0, 0, 0, 1});
  Frame a = synthetic({0, 3, 1, 1, 1, 1, 1, 2}, {0, 1, 1, 0.6f, 0, 0, 0.2f, 1});
  Frame b = synthetic({0, 3, 1, 1, 1, 1, 1, 2}, {0, 0, 1, 0.4f, 0, 0.5f, 0.2f, 1});
  uint64_t px = 0;
  // pixel 1 differs in object (excluded though its vis flips); 3 (0.6 -> 0.4) and 5 (0 -> 0.5) flip.
  EXPECT_DOUBLE_EQ(decisionFlipRate(ref, a, b, "sun", &px), 2.0 / 6.0);
  EXPECT_EQ(px, 6u);
  EXPECT_DOUBLE_EQ(decisionFlipRate(ref, a, a, "sun"), 0.0);

  // Sequence a, b, a: both pairs flip 2 of 6 -> shimmer 1/3; per frame error rates from compare.
  StabilityMetrics s = measureStability(ref, {a, b, a});
  EXPECT_EQ(s.frames, 3);
  ASSERT_EQ(s.flipRatePerPair.size(), 2u);
  EXPECT_DOUBLE_EQ(s.shimmerRate, 2.0 / 6.0);
  ASSERT_EQ(s.errorRatePerFrame.size(), 3u);
  EXPECT_DOUBLE_EQ(s.errorRatePerFrame[0], s.errorRatePerFrame[2]);
  EXPECT_GE(s.errorRateMax, s.errorRateMean);
  EXPECT_GE(s.errorRateStd, 0.0);
  EXPECT_TRUE(std::isfinite(s.toJson()["error_rate_std"].get<double>()));

  // No compared pixel at all: 0, not NaN.
  Frame empty = synthetic({0, 0}, {0, 0});
  EXPECT_DOUBLE_EQ(decisionFlipRate(empty, empty, empty, "sun"), 0.0);
  EXPECT_THROW(measureStability(ref, {a}), InputError);
  EXPECT_THROW(decisionFlipRate(ref, a, empty, "sun"), InputError);
}

namespace {

Rasterizer* rasterizer() {
  // Built in one expression: its destructor runs before Mesa's own exit handlers.
  static std::unique_ptr<Rasterizer> r = []() -> std::unique_ptr<Rasterizer> {
    try {
      return std::make_unique<Rasterizer>();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "\n*** NO VULKAN DEVICE: stability raster tests are SKIPPED: %s ***\n\n", e.what());
      return nullptr;
    }
  }();
  return r.get();
}

}  // namespace

// The evaluation camera is long_view's; the fit camera dollies forward. Stabilized cascades
// (constant-size crops snapped to whole texels) keep every texel where it was, so decisions only
// change where a pixel changes cascade; the unstabilized crops slide by fractions of a texel and
// shadow edges crawl.
TEST(Shimmer, StabilizedCascadesDoNotShimmerOnADollyAndUnstabilizedDo) {
  Rasterizer* R = rasterizer();
  if (!R) GTEST_SKIP() << "no Vulkan device (lavapipe) found: test NOT run";
  auto t0 = std::chrono::steady_clock::now();
  Scene scene = loadScene(resolveScenePath("long_view"), {{"/camera/width", 480}, {"/camera/height", 270}});
  Frame ref = renderReference(scene, ReferenceOptions{});
  const int frames = 32;
  const float distanceWorld = 4.0f;
  std::vector<Camera> path = dollyPath(scene.camera, distanceWorld, frames);

  Method m;
  m.fit = Fit::Cascades;
  m.cascadeCount = 4;
  m.mapSize = 1024;

  // A fit camera equal to the scene's renders exactly what no fit camera renders (old callers).
  m.cascadeStabilize = false;
  Frame plain = R->render(scene, m);
  Frame same = R->render(scene, m, "", nullptr, &scene.camera);
  const std::string vis = "light." + scene.lights[0].name + ".vis";
  EXPECT_EQ(plain.get(vis), same.get(vis));

  double rate[2] = {0, 0};
  for (int stabilize = 0; stabilize < 2; ++stabilize) {
    m.cascadeStabilize = stabilize == 1;
    std::vector<Frame> rasters;
    for (const Camera& fit : path) rasters.push_back(R->render(scene, m, "", nullptr, &fit));
    StabilityMetrics s = measureStability(ref, rasters);
    rate[stabilize] = s.shimmerRate;
    std::printf("  long_view 480x270, 4 x 1024 cascades, dolly %.1f units / %d frames, stabilize %d: "
                "shimmer_rate %.6g, error_rate mean %.5f max %.5f std %.5f, compared px %llu\n",
                distanceWorld, frames, stabilize, s.shimmerRate, s.errorRateMean, s.errorRateMax, s.errorRateStd,
                (unsigned long long)s.pixelsComparedPerPair[0]);
    EXPECT_GT(s.pixelsComparedPerPair[0], 50000u);  // most of the image is compared
    EXPECT_TRUE(std::isfinite(s.errorRateStd));
  }
  EXPECT_LT(rate[1], 1e-4) << "stabilized cascades must not shimmer";
  EXPECT_GT(rate[0], 1e-3) << "unstabilized cascades should shimmer clearly";
  EXPECT_GT(rate[0], 10.0 * rate[1]);
  std::printf("  [%.1f s]\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

namespace {

struct CliResult {
  int code = -1;
  std::string err;
};

CliResult runCli(const std::string& args, const std::filesystem::path& dir) {
  const std::string errFile = (dir / "stderr.txt").string();
  const std::string cmd = std::string(SHADOWLAB_BINARY) + " " + args + " >/dev/null 2>" + errFile;
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(errFile);
  r.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return r;
}

}  // namespace

// Refused inputs: exit 2, a GCC-style message naming the option, nothing written.
TEST(StabilityCli, RefusesBadInputsAndWritesNothing) {
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / ("shadowlab_stability_cli_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string out = (dir / "out").string();
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--path dolly --frames 1", "--frames: error: got 1; expected 2..1024"},
      {"--path dolly --frames 1025", "--frames: error: got 1025"},
      {"--path spiral --frames 8", "--path: error: got \"spiral\"; expected dolly or orbit"},
      {"--path dolly --frames 8 --angle-deg 5", "--angle-deg: error: given with --path dolly"},
      {"--path orbit --frames 8 --distance 5", "--distance: error: given with --path orbit"},
      {"--path orbit --frames 8 --angle-deg 1e9", "--angle-deg: error: got"},
      {"--path dolly --frames 8 --distance inf", "--distance: error: got inf"},
      {"--path dolly --frames 8 --set cascades.count=0", "cascades.count"},
  };
  for (const Case& c : cases) {
    CliResult r = runCli("stability long_view " + c.args + " -o " + out, dir);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("error:"), std::string::npos) << c.args;
    EXPECT_FALSE(fs::exists(out)) << c.args << ": a refused input must write nothing";
  }
  fs::remove_all(dir);
}

// End to end on a small scene: stability.json with the documented keys, finite numbers.
TEST(StabilityCli, WritesStabilityJson) {
  if (!rasterizer()) GTEST_SKIP() << "no Vulkan device (lavapipe) found: test NOT run";
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / ("shadowlab_stability_e2e_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string out = (dir / "out").string();
  CliResult r = runCli("stability sphere_on_plane --set fit=cascades --set cascades.stabilize=true --path orbit "
                       "--frames 3 --angle-deg 20 --cache " + (dir / "cache").string() + " -o " + out, dir);
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(out + "/stability.json");
  nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["frames"], 3);
  EXPECT_EQ(j["path"]["kind"], "orbit");
  EXPECT_EQ(j["path"]["fit_cameras"].size(), 3u);
  EXPECT_EQ(j["error_rate_per_frame"].size(), 3u);
  EXPECT_EQ(j["flip_rate_per_pair"].size(), 2u);
  for (const char* k : {"shimmer_rate", "error_rate_mean", "error_rate_max", "error_rate_std"}) {
    ASSERT_TRUE(j[k].is_number()) << k;
    EXPECT_TRUE(std::isfinite(j[k].get<double>())) << k;
  }
  fs::remove_all(dir);
}
