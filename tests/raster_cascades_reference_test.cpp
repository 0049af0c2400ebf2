// Cascaded shadow maps against the Embree ground truth (renderReference): on long_view, four
// cascades beat one map of the same texel count; casters outside the view frustum still cast.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

#include "shadowlab/raster/raster.h"
#include "support/raster_device.h"
#include "support/reference_score.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"

namespace raster_cascades_reference_test {

using namespace shadowlab;

namespace {

using CascadesVsReference = shadowlab::testing::ValidatedRasterTest;
using shadowlab::testing::Score;
using shadowlab::testing::score;

}  // namespace

// Same texel count (4 x 1024^2 = 2048^2): the cascades spend their texels where the camera is
// close, so the footprint m (pixels per texel) at the 95th percentile drops, and so do the errors.
TEST_F(CascadesVsReference, FourCascadesBeatOneMapOfTheSameTexelCountOnLongView) {
  REQUIRE_DEVICE();
  Scene s = loadScene(resolveScenePath("long_view"));  // full 960x540: both renderers take well under a second
  const std::string light = s.lights[0].name;
  auto t0 = std::chrono::steady_clock::now();
  Frame ref = renderReference(s, ReferenceOptions{});
  Method one;
  one.mapSize = 2048;
  one.fit = Fit::Sphere;
  Method four;
  four.mapSize = 1024;
  four.fit = Fit::Cascades;
  four.cascadeCount = 4;
  Frame rasOne = R->render(s, one), rasFour = R->render(s, four);
  Score a = score(ref, rasOne, light), b = score(ref, rasFour, light);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "  long_view %dx%d (%zu px both see): 1 x 2048 sphere: error_rate %.5f (%zu px), m_p95 %.3f;"
      " 4 x 1024 cascades: error_rate %.5f (%zu px), m_p95 %.3f  [%.1f s]\n",
      s.camera.width, s.camera.height, a.both, a.errorRate, a.wrong, a.mP95, b.errorRate, b.wrong, b.mP95, seconds);
  ASSERT_GT(a.both, 10000u);
  EXPECT_LT(b.errorRate, a.errorRate);
  EXPECT_LT(b.mP95, a.mP95);
  // Every cascade is used and the channel says which (0..3), the sphere fit reports 0.
  const auto& cascade = rasFour.get("light." + light + ".cascade");
  std::vector<size_t> perCascade(4, 0);
  for (size_t i = 0; i < cascade.size(); ++i) {
    float c = cascade[i];
    ASSERT_TRUE(c == 0.0f || c == 1.0f || c == 2.0f || c == 3.0f) << "got " << c;
    if (rasFour.get("hit")[i] > 0.5f) ++perCascade[size_t(c)];
  }
  for (int k = 0; k < 4; ++k) EXPECT_GT(perCascade[size_t(k)], 0u) << "cascade " << k;
  for (float c : rasOne.get("light." + light + ".cascade")) ASSERT_EQ(c, 0.0f);

  // A blend band and a stabilized fit keep the advantage, and every channel stays finite.
  Method blended = four;
  blended.cascadeBlend = 0.2f;
  Method stable = four;
  stable.cascadeStabilize = true;
  for (const Method& m : {blended, stable}) {
    Frame f = R->render(s, m);
    Score sc = score(ref, f, light);
    std::printf("  long_view 4 x 1024 cascades, blend %.2f stabilize %d: error_rate %.5f, m_p95 %.3f\n", m.cascadeBlend,
                int(m.cascadeStabilize), sc.errorRate, sc.mP95);
    EXPECT_LT(sc.errorRate, a.errorRate);
    EXPECT_LT(sc.mP95, a.mP95);
    for (size_t c = 0; c < f.names.size(); ++c)
      for (float v : f.data[c]) ASSERT_TRUE(std::isfinite(v)) << f.names[c];
  }
  // Blending: vis takes values strictly between 0 and 1 only in the bands (filter none is 0/1).
  // The frame is a named local: a range-for over get() of the temporary render() returns would read
  // a plane the temporary's destruction had already freed.
  size_t fractional = 0;
  const Frame blendedFrame = R->render(s, blended);
  for (float v : blendedFrame.get("light." + light + ".vis")) fractional += v > 0.0f && v < 1.0f;
  std::printf("  blend 0.2: %zu pixels with fractional visibility\n", fractional);
  EXPECT_GT(fractional, 0u) << "where two cascades disagree inside a band, the blend must mix them";
}

// A pole behind the camera (outside the view frustum and so outside every slice's box) whose
// shadow falls forward into view: the slice's crop must take casters between the light and the
// slice (the near plane pulled back to the scene bounds), or the shadow vanishes. fit=sdsm too:
// its crops hold the visible samples only, the casters are the depth range's.
TEST_F(CascadesVsReference, CasterOutsideTheViewFrustumStillCastsIntoView) {
  REQUIRE_DEVICE();
  namespace fs = std::filesystem;
  fs::path dir = fs::temp_directory_path() / ("shadowlab_cascades_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::path file = dir / "pole_behind.json";
  {
    // Camera at the origin, 3 up, looking down the -z axis: the ground is in view from z = -3.4
    // on. The pole stands at z = +6 (behind the camera), 6 tall; the light travels (0, -0.3, -1),
    // so its shadow runs from z = 6 to z = 6 - 6 / 0.3 = -14 along x = 0: in view from -3.4 to -14.
    std::ofstream out(file);
    out << R"({
  "camera": {"position": [0, 3, 0], "look_at": [0, 0, -10], "vfov_deg": 50, "width": 320, "height": 240, "near": 0.1, "far": 100},
  "objects": [
    {"type": "plane", "name": "ground", "size": [40, 60], "transform": {"translate": [0, 0, -15]}},
    {"type": "cylinder", "name": "pole", "radius": 0.3, "height": 6, "segments": 32, "transform": {"translate": [0, 3, 6]}}
  ],
  "lights": [{"type": "directional", "name": "sun", "direction": [0, -0.3, -1]}]
})";
  }
  Scene s = loadScene(file.string());
  fs::remove_all(dir);
  Frame ref = renderReference(s, ReferenceOptions{});
  Method eight;  // more slices than the scene needs: cascades with few or no pixels still work
  eight.fit = Fit::Cascades;
  eight.cascadeCount = 8;
  eight.cascadeLambda = 1.0f;
  Frame f8 = R->render(s, eight);
  for (size_t c = 0; c < f8.names.size(); ++c)
    for (float v : f8.data[c]) ASSERT_TRUE(std::isfinite(v)) << f8.names[c];
  for (Fit fit : {Fit::Cascades, Fit::Tight, Fit::Sdsm}) {
    for (bool stabilize : {false, true}) {
      if (fit != Fit::Cascades && stabilize) continue;
      Method m;
      m.fit = fit;
      m.cascadeStabilize = stabilize;
      Score sc = score(ref, R->render(s, m), "sun");
      std::printf(
          "  pole behind the camera, fit=%s stabilize=%d: reference shadow %zu px, shadowed by raster %zu,"
          " error_rate %.5f\n",
          toString(fit).c_str(), int(stabilize), sc.refShadow, sc.refShadowRasShadow, sc.errorRate);
      ASSERT_GT(sc.refShadow, 500u) << "the pole's shadow must be in view";
      EXPECT_GE(double(sc.refShadowRasShadow), 0.97 * double(sc.refShadow)) << toString(fit);
      EXPECT_LT(sc.errorRate, 0.01) << toString(fit);
    }
  }
}

}  // namespace raster_cascades_reference_test
