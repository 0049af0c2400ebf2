// fit=sdsm's pure steps (sdsm.h), no GPU: the depth reduction, the per-partition bounds of
// synthetic samples (blend band and split tolerance included), the crops with and without the
// texel snap, the visible point of a pixel, and the whole fit (fitFrameLayers) on long_view with
// samples traced analytically on its ground: every sample lands inside the layer it picks, and the
// near layer's texels are finer than fit=cascades'.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "shadowlab/raster/resolve_params.h"
#include "shadowlab/raster/sdsm.h"
#include "shadowlab/scenes/loader.h"

namespace raster_sdsm_test {

using namespace shadowlab;
using namespace shadowlab::raster;

namespace {

SdsmSample sample(float depth, float x, float y) { return SdsmSample{depth, glm::vec2(x, y)}; }

// The partition resolve.frag's pickCascade gives a view depth: the number of inner splits it lies beyond.
int pick(const std::vector<float>& splits, float depth) {
  int k = 0;
  for (size_t j = 1; j + 1 < splits.size(); ++j)
    if (depth > splits[j]) k = int(j);
  return k;
}

glm::vec3 uvDepth(const glm::mat4& texFromWorld, glm::vec3 p) {
  glm::vec4 t = texFromWorld * glm::vec4(p, 1.0f);
  return glm::vec3(t) / t.w;
}

}  // namespace

TEST(RasterSdsm, DepthRangeIsTheSamplesMinAndMax) {
  ViewDepthRange r{-1, -1};
  EXPECT_FALSE(sdsmDepthRange({}, r));
  EXPECT_EQ(r.nearView, -1.0f);  // untouched without samples
  ASSERT_TRUE(sdsmDepthRange({sample(5, 0, 0), sample(2.5f, 1, 1), sample(40, 2, 2), sample(7, 3, 3)}, r));
  EXPECT_EQ(r.nearView, 2.5f);
  EXPECT_EQ(r.farView, 40.0f);
  // NaN depths are skipped; one depth only (a wall seen square on) still gets a range:
  // f = 1.001 n + 1e-4 = 10.0101.
  ASSERT_TRUE(sdsmDepthRange({sample(10, 0, 0), sample(std::nanf(""), 0, 0), sample(10, 1, 0)}, r));
  EXPECT_EQ(r.nearView, 10.0f);
  EXPECT_FLOAT_EQ(r.farView, 10.0101f);
  // A sample at (or behind) the eye: the near end is guarded at 1e-4 for the logarithmic split.
  ASSERT_TRUE(sdsmDepthRange({sample(0, 0, 0), sample(3, 0, 0)}, r));
  EXPECT_FLOAT_EQ(r.nearView, 1e-4f);
  EXPECT_EQ(r.farView, 3.0f);
}

TEST(RasterSdsm, PartitionBoundsHoldTheSamplesEachPartitionReads) {
  // Logarithmic splits of [1, 8] in 3: 1, 2, 4, 8.
  const std::vector<double> splits = cascadeSplits(1.0, 8.0, 3, 1.0);
  ASSERT_EQ(splits.size(), 4u);
  EXPECT_NEAR(splits[1], 2.0, 1e-12);
  EXPECT_NEAR(splits[2], 4.0, 1e-12);
  const std::vector<SdsmSample> samples = {sample(1.0f, 0, 0), sample(1.9f, 1, -1), sample(3.0f, 5, 5),
                                           sample(7.0f, -2, 3), sample(8.0f, 10, 10)};
  std::vector<SdsmBounds> b = sdsmPartitionBounds(samples, splits, 0.0);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b[0].samples, 2u);
  EXPECT_EQ(b[0].minLight, glm::vec2(0, -1));
  EXPECT_EQ(b[0].maxLight, glm::vec2(1, 0));
  EXPECT_EQ(b[1].samples, 1u);
  EXPECT_EQ(b[1].minLight, glm::vec2(5, 5));
  EXPECT_EQ(b[1].maxLight, glm::vec2(5, 5));
  EXPECT_EQ(b[2].samples, 2u);
  EXPECT_EQ(b[2].minLight, glm::vec2(-2, 3));
  EXPECT_EQ(b[2].maxLight, glm::vec2(10, 10));

  // A sample on a split (the shader's float depth may land on either side) counts for both.
  b = sdsmPartitionBounds({sample(1.0f, 0, 0), sample(2.0f, 7, 7), sample(8.0f, 1, 1)}, splits, 0.0);
  EXPECT_EQ(b[0].samples, 2u);
  EXPECT_EQ(b[0].maxLight, glm::vec2(7, 7));
  EXPECT_EQ(b[1].samples, 1u);
  EXPECT_EQ(b[1].minLight, glm::vec2(7, 7));
  EXPECT_EQ(b[2].samples, 1u);

  // Blend 0.25: partition 1 spans [2, 4], its band [3.5, 4]: a sample at 3.6 reads partition 2
  // too; one at 3.4 does not. Partition 0's band is [1.75, 2]: 1.9 reads partition 1.
  b = sdsmPartitionBounds({sample(1.9f, 1, -1), sample(3.4f, -3, 0), sample(3.6f, 9, 9), sample(6.0f, 0, 0)}, splits,
                          0.25);
  EXPECT_EQ(b[0].samples, 1u);
  EXPECT_EQ(b[1].samples, 3u);
  EXPECT_EQ(b[1].minLight, glm::vec2(-3, -1));
  EXPECT_EQ(b[1].maxLight, glm::vec2(9, 9));
  EXPECT_EQ(b[2].samples, 2u);
  EXPECT_EQ(b[2].minLight, glm::vec2(0, 0));
  EXPECT_EQ(b[2].maxLight, glm::vec2(9, 9));

  // No sample in a partition: marked by samples == 0.
  b = sdsmPartitionBounds({sample(1.5f, 0, 0), sample(7.0f, 1, 1)}, splits, 0.0);
  EXPECT_EQ(b[1].samples, 0u);
}

TEST(RasterSdsm, CropKeepsOneTexelOfMarginAroundTheBox) {
  SdsmBounds b;
  b.minLight = {0, 0};
  b.maxLight = {10, 5};
  b.samples = 4;
  // 1002 texels: 1000 over the box, one on each side. x: t = 10 / 1000, y: t = 5 / 1000.
  CascadeCrop c = sdsmCrop(b, 1002, false);
  EXPECT_FLOAT_EQ(c.minLight.x, -0.01f);
  EXPECT_FLOAT_EQ(c.maxLight.x, 10.01f);
  EXPECT_FLOAT_EQ(c.minLight.y, -0.005f);
  EXPECT_FLOAT_EQ(c.maxLight.y, 5.005f);
  EXPECT_FLOAT_EQ(c.texelWorld, 0.01f);
  // One sample: a tiny box of 1e-5 world units, still invertible.
  SdsmBounds one;
  one.minLight = one.maxLight = {3, 4};
  one.samples = 1;
  c = sdsmCrop(one, 1024, false);
  EXPECT_GT(c.maxLight.x, c.minLight.x);
  EXPECT_GT(c.maxLight.y, c.minLight.y);
  EXPECT_LT(c.minLight.x, 3.0f);
  EXPECT_GT(c.maxLight.x, 3.0f);
}

TEST(RasterSdsm, SnappedCropsKeepTheirTexelGridWhileTheBoxMoves) {
  SdsmBounds b;
  b.minLight = {0, 0};
  b.maxLight = {10, 5};
  b.samples = 4;
  // 1028 texels, 1024 for the box: x: 10 / 1024 -> the next power of two 1/64; y: 5 / 1024 -> 1/128.
  CascadeCrop c = sdsmCrop(b, 1028, true);
  EXPECT_EQ(c.texelWorld, 1.0f / 64.0f);
  EXPECT_EQ(c.minLight.x, -1.0f / 64.0f);  // floor((0 - t) / t) t
  EXPECT_EQ(c.maxLight.x - c.minLight.x, 1028.0f / 64.0f);
  EXPECT_EQ(c.minLight.y, -1.0f / 128.0f);
  EXPECT_EQ(c.maxLight.y - c.minLight.y, 1028.0f / 128.0f);
  // The box moved by 0.3 and grown by 0.2: same texel size, the crop moved by whole texels (a
  // multiple of 1/64, and 1/128 along y), so every texel of the map lies where one lay before.
  SdsmBounds moved = b;
  moved.minLight += glm::vec2(0.3f, 0.3f);
  moved.maxLight += glm::vec2(0.5f, 0.5f);
  CascadeCrop d = sdsmCrop(moved, 1028, true);
  EXPECT_EQ(d.texelWorld, c.texelWorld);
  EXPECT_EQ(d.maxLight.x - d.minLight.x, c.maxLight.x - c.minLight.x);
  const float shiftTexelsX = (d.minLight.x - c.minLight.x) * 64.0f,
              shiftTexelsY = (d.minLight.y - c.minLight.y) * 128.0f;
  EXPECT_EQ(shiftTexelsX, std::round(shiftTexelsX));
  EXPECT_EQ(shiftTexelsY, std::round(shiftTexelsY));
  EXPECT_EQ(shiftTexelsX, 19.0f);  // floor((0.3 - 1/64) * 64) = floor(18.2) = 18 texels from -1 -> 19
  // Every box point, with a texel of margin, is inside the snapped crop.
  EXPECT_LE(d.minLight.x, moved.minLight.x - d.texelWorld);
  EXPECT_GE(d.maxLight.x, moved.maxLight.x + d.texelWorld);
  // Doubling the box doubles the texel: the size steps by powers of two only.
  SdsmBounds twice = b;
  twice.maxLight = {20, 10};
  EXPECT_EQ(sdsmCrop(twice, 1028, true).texelWorld, 2.0f * c.texelWorld);
  // Not snapped, the same move changes the texel size (the grid crawls).
  EXPECT_NE(sdsmCrop(moved, 1028, false).texelWorld, sdsmCrop(b, 1028, false).texelWorld);
}

TEST(RasterSdsm, VisiblePointIsWhereThePixelsRayMeetsItsTriangle) {
  Camera cam;
  cam.position = {0, 0, 0};
  cam.lookAt = {0, 0, -1};
  cam.width = 4;
  cam.height = 4;
  cam.vfovDeg = 90;
  const CameraRays rays(cam);
  glm::vec3 p;
  // A triangle in the plane z = -5 (any three points of it: the plane is what counts).
  ASSERT_TRUE(visiblePoint(rays, cam.position, 2, 1, {0, 0, -5}, {1, 0, -5}, {0, 1, -5}, p));
  const glm::vec3 d = rays.direction(2.5f, 1.5f);
  EXPECT_NEAR(p.z, -5.0f, 1e-6f);
  EXPECT_NEAR(p.x, d.x * 5.0f / -d.z, 1e-6f);
  EXPECT_NEAR(p.y, d.y * 5.0f / -d.z, 1e-6f);
  // The plane z = +5 lies behind the camera; a plane along the ray has no point.
  EXPECT_FALSE(visiblePoint(rays, cam.position, 2, 1, {0, 0, 5}, {1, 0, 5}, {0, 1, 5}, p));
  EXPECT_FALSE(visiblePoint(rays, cam.position, 2, 2, {0, 0, 0}, {0, 0, -1}, d * 7.0f, p));
  // Its sample: view depth 5 along the forward axis.
  ASSERT_TRUE(visiblePoint(rays, cam.position, 2, 1, {0, 0, -5}, {1, 0, -5}, {0, 1, -5}, p));
  std::vector<SdsmSample> s = sdsmSamples({p}, cam, glm::mat4(1.0f));
  ASSERT_EQ(s.size(), 1u);
  EXPECT_NEAR(s[0].viewDepth, 5.0f, 1e-5f);
  EXPECT_EQ(s[0].light, glm::vec2(p.x, p.y));
}

// The whole fit on long_view with the ground's visible points (the camera's rays through a grid
// of pixels meet the plane y = 0; the poles and crates left out): the splits cover the samples'
// depth range only, every sample projects into the map of the layer it picks (and of the next one
// in a blend band), and the texels of the nearest layer are finer than fit=cascades' at the same
// map size and count. Without samples, fit=sdsm is fit=cascades exactly.
TEST(RasterSdsm, FitOnLongViewHoldsEverySampleInItsLayer) {
  const Scene s = loadScene(resolveScenePath("long_view"));
  const Camera& cam = s.camera;
  const CameraRays rays(cam);
  std::vector<glm::vec3> ground;
  double nearest = 1e30, farthest = 0;
  const glm::vec3 forward = glm::normalize(cam.lookAt - cam.position);
  for (int y = 0; y < cam.height; y += 3)
    for (int x = 0; x < cam.width; x += 3) {
      glm::vec3 p;
      if (!visiblePoint(rays, cam.position, x, y, {0, 0, 0}, {1, 0, 0}, {0, 0, -1}, p)) continue;
      if (std::abs(p.x) > 20.0f || p.z < -205.0f || p.z > 15.0f) continue;  // off the 40 x 220 ground
      ground.push_back(p);
      const double depth = glm::dot(p - cam.position, forward);
      nearest = std::min(nearest, depth);
      farthest = std::max(farthest, depth);
    }
  ASSERT_GT(ground.size(), 10000u);
  Method sdsm;
  sdsm.fit = Fit::Sdsm;
  sdsm.mapSize = 1024;
  Method cascades = sdsm;
  cascades.fit = Fit::Cascades;
  const FrameLayers a = fitFrameLayers(s, &s.lights[0], sdsm, cam, &ground);
  const FrameLayers c = fitFrameLayers(s, &s.lights[0], cascades, cam);
  ASSERT_EQ(a.lightLayers, 4);
  ASSERT_EQ(a.cascadeSplitsView.size(), 5u);
  EXPECT_NEAR(a.cascadeSplitsView.front(), nearest, 1e-4 * nearest);
  EXPECT_NEAR(a.cascadeSplitsView.back(), farthest, 1e-5 * farthest);
  std::printf("  long_view ground samples %zu: depth %.3f..%.3f; cascades' range %.3f..%.3f\n", ground.size(), nearest,
              farthest, c.cascadeSplitsView.front(), c.cascadeSplitsView.back());
  // Per sample, the texel size of the layer it picks over the sample's view depth (proportional to
  // the pixel's footprint: m without the slant), at the 95th percentile (the nearest samples, as
  // m_p95 sees them): with logarithmic splits (lambda 1, Lauritzen's) sdsm's split of its tighter
  // range beats fit=cascades at either its default 0.75 or 1 (whose first slices start at the
  // camera's near plane 0.1, the camera standing inside the scene's box). With lambda 0.75 the
  // first split of sdsm's range lies further out than cascades' and its nearest texels are coarser.
  auto texelP95 = [&](const FrameLayers& f) {
    std::vector<float> t;
    for (const glm::vec3& p : ground) {
      const float depth = glm::dot(p - cam.position, forward);
      t.push_back(f.layers[size_t(pick(f.cascadeSplitsView, depth))].texelWorldPerW / depth);
    }
    std::nth_element(t.begin(), t.begin() + std::ptrdiff_t(t.size() * 95 / 100), t.end());
    return t[t.size() * 95 / 100];
  };
  double p95[2][2];  // [sdsm, cascades][lambda 0.75, 1]
  for (int l = 0; l < 2; ++l) {
    Method ms = sdsm, mc = cascades;
    ms.sdsmLambda = mc.cascadeLambda = l == 0 ? 0.75f : 1.0f;
    const FrameLayers fs = fitFrameLayers(s, &s.lights[0], ms, cam, &ground),
                      fc = fitFrameLayers(s, &s.lights[0], mc, cam);
    p95[0][l] = texelP95(fs);
    p95[1][l] = texelP95(fc);
    std::printf("  lambda %.2f: sdsm splits %.2f %.2f %.2f %.2f %.2f, cascades' %.2f %.2f %.2f %.2f %.2f\n",
                ms.sdsmLambda, fs.cascadeSplitsView[0], fs.cascadeSplitsView[1], fs.cascadeSplitsView[2],
                fs.cascadeSplitsView[3], fs.cascadeSplitsView[4], fc.cascadeSplitsView[0], fc.cascadeSplitsView[1],
                fc.cascadeSplitsView[2], fc.cascadeSplitsView[3], fc.cascadeSplitsView[4]);
    std::printf("    texel / depth at the 95th percentile: sdsm %.6f, cascades %.6f\n", p95[0][l], p95[1][l]);
  }
  EXPECT_LT(p95[0][1], 0.8 * p95[1][0]);
  EXPECT_LT(p95[0][1], 0.8 * p95[1][1]);
  EXPECT_GT(p95[0][0], p95[1][0]);
  // sdsm's splits follow sdsm.lambda (default 1) alone: cascades.lambda is fit=cascades' own.
  sdsm.sdsmLambda = 1.0f;
  {
    Method other = sdsm;
    other.cascadeLambda = 0.25f;
    EXPECT_EQ(fitFrameLayers(s, &s.lights[0], other, cam, &ground).cascadeSplitsView,
              fitFrameLayers(s, &s.lights[0], sdsm, cam, &ground).cascadeSplitsView);
    EXPECT_EQ(Method().sdsmLambda, 1.0f);
  }
  for (bool snap : {false, true})
    for (float blend : {0.0f, 0.2f}) {
      Method m = sdsm;
      m.sdsmSnap = snap;
      m.cascadeBlend = blend;
      const FrameLayers f = fitFrameLayers(s, &s.lights[0], m, cam, &ground);
      size_t outside = 0;
      for (const glm::vec3& p : ground) {
        const float depth = glm::dot(p - cam.position, forward);
        const int k = pick(f.cascadeSplitsView, depth);
        std::vector<int> reads = {k};
        const float farSplit = f.cascadeSplitsView[size_t(k) + 1], nearSplit = f.cascadeSplitsView[size_t(k)];
        if (blend > 0 && k + 1 < 4 && depth >= farSplit - blend * (farSplit - nearSplit)) reads.push_back(k + 1);
        for (int layer : reads) {
          const glm::vec3 t = uvDepth(f.layers[size_t(layer)].texFromWorld, p);
          outside += !(t.x >= 0 && t.x <= 1 && t.y >= 0 && t.y <= 1 && t.z >= 0 && t.z <= 1);
        }
      }
      EXPECT_EQ(outside, 0u) << "snap " << snap << " blend " << blend;
    }
  // Without samples (none given, or none seen): exactly fit=cascades with cascades.lambda.
  const std::vector<glm::vec3> none;
  cascades.cascadeLambda = sdsm.cascadeLambda;
  const FrameLayers c1 = fitFrameLayers(s, &s.lights[0], cascades, cam);
  for (const std::vector<glm::vec3>* points : {static_cast<const std::vector<glm::vec3>*>(nullptr), &none}) {
    const FrameLayers f = fitFrameLayers(s, &s.lights[0], sdsm, cam, points);
    const FrameLayers& c = c1;
    ASSERT_EQ(f.layers.size(), c.layers.size());
    EXPECT_EQ(f.cascadeSplitsView, c.cascadeSplitsView);
    for (size_t k = 0; k < f.layers.size(); ++k) EXPECT_EQ(f.layers[k].texFromWorld, c.layers[k].texFromWorld);
  }
  EXPECT_TRUE(fitReadsVisiblePoints(&s.lights[0], sdsm));
  EXPECT_FALSE(fitReadsVisiblePoints(&s.lights[0], cascades));
  EXPECT_FALSE(fitReadsVisiblePoints(nullptr, sdsm));
}

}  // namespace raster_sdsm_test
