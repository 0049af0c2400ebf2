// fit=sdsm against the Embree ground truth (renderReference) on long_view: at the same map memory
// as fit=cascades (4 layers of 1024^2) with logarithmic splits its slices and crops hold only what
// the camera sees, so m_p95 (pixels per texel) drops below hand-set cascades' (lambda 0.75 or 1),
// and every visible pixel finds its point inside the map of the layer it picks (the samples are
// the pixels themselves). Also with sdsm.snap and a blend
// band, and with a fit camera other than the scene's (the samples follow the fit camera).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/camera_path.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"
#include "support/reference_score.h"

namespace raster_sdsm_reference_test {

using namespace shadowlab;

namespace {

using SdsmVsReference = shadowlab::testing::ValidatedRasterTest;
using shadowlab::testing::Score;
using shadowlab::testing::score;

// Hit pixels (raster) whose lookup fell outside the map (light.L.in_map 0).
size_t hitOutsideTheMap(const Frame& f, const std::string& light) {
  const auto& hit = f.get("hit");
  const auto& inMap = f.get("light." + light + ".in_map");
  size_t n = 0;
  for (size_t i = 0; i < hit.size(); ++i) n += hit[i] > 0.5f && inMap[i] < 0.5f;
  return n;
}

}  // namespace

TEST_F(SdsmVsReference, LowerFootprintThanCascadesAtEqualMemoryOnLongView) {
  REQUIRE_DEVICE();
  const Scene s = loadScene(resolveScenePath("long_view"));  // 960x540
  const std::string light = s.lights[0].name;
  auto t0 = std::chrono::steady_clock::now();
  const Frame ref = renderReference(s, ReferenceOptions{});
  Method cascades;  // hand-set: the default split (lambda 0.75)
  cascades.fit = Fit::Cascades;
  cascades.mapSize = 1024;
  cascades.cascadeCount = 4;
  Method cascadesLog = cascades;
  cascadesLog.cascadeLambda = 1.0f;
  Method sdsm = cascades;  // its default: logarithmic splits over the samples' range, as Lauritzen et al.
  sdsm.fit = Fit::Sdsm;
  ASSERT_EQ(sdsm.sdsmLambda, 1.0f);
  Method sdsmDefault = sdsm;  // cascades' default split, which sdsm once shared
  sdsmDefault.sdsmLambda = 0.75f;
  const Frame rasCascades = R->render(s, cascades), rasSdsm = R->render(s, sdsm);
  const Score c = score(ref, rasCascades, light), d = score(ref, rasSdsm, light);
  const Score cLog = score(ref, R->render(s, cascadesLog), light),
              dDefault = score(ref, R->render(s, sdsmDefault), light);
  std::printf(
      "  long_view %dx%d (%zu px both see), 4 x 1024: cascades (lambda 0.75) error_rate %.5f (%zu px), m_p95 %.3f;"
      " cascades (lambda 1) %.5f, %.3f; sdsm (lambda 1) error_rate %.5f (%zu px), m_p95 %.3f; sdsm (lambda 0.75) %.5f,"
      " %.3f  [%.1f s]\n",
      s.camera.width, s.camera.height, c.both, c.errorRate, c.wrong, c.mP95, cLog.errorRate, cLog.mP95, d.errorRate,
      d.wrong, d.mP95, dDefault.errorRate, dDefault.mP95,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  ASSERT_GT(c.both, 100000u);
  EXPECT_LT(d.mP95, 0.7 * c.mP95);
  EXPECT_LT(d.mP95, 0.5 * cLog.mP95);
  EXPECT_LT(d.errorRate, cLog.errorRate);
  // The samples are the visible pixels: each one's point lies inside its layer's map.
  EXPECT_EQ(hitOutsideTheMap(rasSdsm, light), 0u);
  // Every partition holds samples and the channel says which (0..3).
  const auto& cascade = rasSdsm.get("light." + light + ".cascade");
  std::vector<size_t> perCascade(4, 0);
  for (size_t i = 0; i < cascade.size(); ++i) {
    const float k = cascade[i];
    ASSERT_TRUE(k == 0.0f || k == 1.0f || k == 2.0f || k == 3.0f) << "got " << k;
    if (rasSdsm.get("hit")[i] > 0.5f) ++perCascade[size_t(k)];
  }
  for (int k = 0; k < 4; ++k) EXPECT_GT(perCascade[size_t(k)], 0u) << "partition " << k;

  // Snapped crops (texel sizes rounded up to powers of two) and a blend band (the next layer's
  // crop widened by its band's samples): every pixel still inside its map, every channel finite,
  // the footprint no finer than without them and still below cascades'.
  Method snapped = sdsm;
  snapped.sdsmSnap = true;
  Method blended = sdsm;
  blended.cascadeBlend = 0.2f;
  for (const Method& m : {snapped, blended}) {
    const Frame f = R->render(s, m);
    const Score sc = score(ref, f, light);
    std::printf("  long_view 4 x 1024 sdsm, snap %d blend %.2f: error_rate %.5f, m_p95 %.3f\n", int(m.sdsmSnap),
                m.cascadeBlend, sc.errorRate, sc.mP95);
    EXPECT_EQ(hitOutsideTheMap(f, light), 0u);
    EXPECT_LT(sc.mP95, c.mP95);
    EXPECT_GE(sc.mP95, 0.99 * d.mP95);
    for (size_t k = 0; k < f.names.size(); ++k)
      for (float v : f.data[k]) ASSERT_TRUE(std::isfinite(v)) << f.names[k];
  }
}

// The samples come from the fit camera's own camera pass: with the fit camera equal to the scene's
// the frame is the one without a fit camera, bit for bit; with a fit camera 4 units further
// forward, the near ground of the evaluation view is not among its samples, so the pixels there
// fall outside every map (in_map 0); back at the scene's camera, the first frame again.
TEST_F(SdsmVsReference, SamplesFollowTheFitCamera) {
  REQUIRE_DEVICE();
  const Scene s = loadScene(resolveScenePath("long_view"), {{"/camera/width", 480}, {"/camera/height", 270}});
  const std::string light = s.lights[0].name;
  Method sdsm;
  sdsm.fit = Fit::Sdsm;
  sdsm.mapSize = 1024;
  const Frame plain = R->render(s, sdsm);
  const Frame same = R->render(s, sdsm, "", nullptr, &s.camera);
  const std::string vis = "light." + light + ".vis";
  EXPECT_EQ(plain.get(vis), same.get(vis));
  EXPECT_EQ(plain.get("light." + light + ".m"), same.get("light." + light + ".m"));
  EXPECT_EQ(hitOutsideTheMap(plain, light), 0u);
  const std::vector<Camera> path = dollyPath(s.camera, 4.0f, 2);
  const Frame ahead = R->render(s, sdsm, "", nullptr, &path[1]);
  const size_t outside = hitOutsideTheMap(ahead, light);
  std::printf("  fit camera 4 units ahead: %zu hit pixels outside the maps\n", outside);
  EXPECT_GT(outside, 1000u) << "the near ground the fit camera does not see is in no partition";
  // And back to the scene's camera: the samples are the scene camera's again.
  const Frame again = R->render(s, sdsm);
  EXPECT_EQ(again.get(vis), plain.get(vis));
  // A rasterizer whose first frame is fit=sdsm (its sample pass runs before any other pass has
  // made the frame's images and descriptors) gives the same frame.
  RasterDeviceOptions options;
  options.validation = true;
  Rasterizer fresh(options);
  const Frame first = fresh.render(s, sdsm);
  EXPECT_EQ(first.get(vis), plain.get(vis));
  EXPECT_EQ(fresh.validationMessages(), 0);
}

}  // namespace raster_sdsm_reference_test
