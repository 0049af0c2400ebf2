// Filterable maps (filter=vsm, evsm2, evsm4, msm) end to end against the Embree truth: light
// bleeding on the bundled stacked_occluders scene is classified as bleed (never leak) and orders
// the methods VSM > EVSM > MSM; no method returns another's image; the shader's Chebyshev bound is
// the formula's at every pixel; MSM's Hamburger reconstruction (a CPU copy of Peters & Klein's
// algorithm) is exact on a planted two-depth distribution where Chebyshev's bound is not; the
// fractional visibility is carried by mae/rmse against binary and fractional (--spp) truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>

#include "shadowlab/compare/compare.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"

namespace compare_filterable_maps_test {

using namespace shadowlab;

namespace {

using FilterableMaps = shadowlab::testing::ValidatedRasterTest;

// stacked_occluders at a quarter of its pixels; the map and the blur of the measurements below.
Scene stacked() {
  Scene s = loadScene(resolveScenePath("stacked_occluders"));
  s.camera.width = 480;
  s.camera.height = 270;
  return s;
}

Method filtered(Filter filter) {
  Method m;
  m.mapSize = 1024;
  m.filter = filter;
  m.filterBlur = 4;
  return m;
}

const Frame& truth() {
  static const Frame f = renderReference(stacked(), ReferenceOptions{});
  return f;
}

// Pixels whose visibility differs by more than 0.01 between two frames of the same camera.
size_t differing(const Frame& a, const Frame& b, const std::string& light) {
  const std::vector<float>&va = a.get("light." + light + ".vis"), &vb = b.get("light." + light + ".vis");
  size_t n = 0;
  for (size_t i = 0; i < va.size(); ++i) n += std::fabs(va[i] - vb[i]) > 0.01f;
  return n;
}

// Peters & Klein 2015, Algorithm 2, as resolve.frag's hamburger4 (double here): the lit fraction's
// bound at depth t from the biased moments of (z, z^2, z^3, z^4).
double hamburger4(const double moments[4], double t, double momentBias) {
  double b[4];
  for (int k = 0; k < 4; ++k) b[k] = moments[k] * (1 - momentBias) + 0.5 * momentBias;
  const double L32D22 = -b[0] * b[1] + b[2], D22 = -b[0] * b[0] + b[1], sq = -b[1] * b[1] + b[3];
  const double D33D22 = sq * D22 - L32D22 * L32D22, invD22 = 1 / D22, L32 = L32D22 * invD22;
  double c[3] = {1, t, t * t};
  c[1] -= b[0];
  c[2] -= b[1] + L32 * c[1];
  c[1] *= invD22;
  c[2] *= D22 / D33D22;
  c[1] -= L32 * c[2];
  c[0] -= c[1] * b[0] + c[2] * b[1];
  const double p = c[1] / c[2], q = c[0] / c[2], r = std::sqrt(std::max(p * p / 4 - q, 0.0));
  const double z1 = -p / 2 - r, z2 = -p / 2 + r;
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  if (z2 < t) s0 = z1, s1 = t, s2 = 1, s3 = 1;
  else if (z1 < t) s0 = t, s1 = z1, s2 = 0, s3 = 1;
  const double quotient = (s0 * z2 - b[0] * (s0 + z2) + b[1]) / ((z2 - s1) * (t - z1));
  return 1 - std::clamp(s2 + s3 * quotient, 0.0, 1.0);
}

double chebyshev(double mean, double meanSq, double t) {
  const double variance = meanSq - mean * mean, d = t - mean;
  return t <= mean ? 1.0 : variance / (variance + d * d);
}

}  // namespace

// The scene's wall shadows the ground where the floating slab's silhouette lies in the map: a
// blurred footprint there holds both occluders' depths, and Chebyshev's bound lights the ground.
TEST_F(FilterableMaps, BleedingOnStackedOccludersOrdersVsmEvsmMsm) {
  REQUIRE_DEVICE();
  const Scene s = stacked();
  const std::string light = s.lights[0].name;
  struct Case {
    const char* what;
    Method method;
    Metrics metrics;
  };
  Method evsmLow = filtered(Filter::Evsm4);  // exponents a 16-bit format would hold
  evsmLow.evsmExponentPos = evsmLow.evsmExponentNeg = 10;
  Case cases[] = {{"vsm", filtered(Filter::Vsm), {}},     {"evsm4 (10, 10)", evsmLow, {}},
                  {"evsm2", filtered(Filter::Evsm2), {}}, {"evsm4", filtered(Filter::Evsm4), {}},
                  {"msm", filtered(Filter::Msm), {}},     {"pcf 9x9", filtered(Filter::Pcf), {}}};
  cases[5].method.filterSize = 9;
  Frame vsmFrame;
  for (Case& c : cases) {
    Frame f = R->render(s, c.method);
    c.metrics = compareFrames(truth(), f);
    std::printf("  stacked_occluders, %s: bleed %llu, leak %llu, other %llu, aliasing %llu, mae %.5f\n", c.what,
                (unsigned long long)c.metrics.count(PixelClass::Bleed),
                (unsigned long long)c.metrics.count(PixelClass::Leak),
                (unsigned long long)c.metrics.count(PixelClass::Other),
                (unsigned long long)c.metrics.count(PixelClass::Aliasing), c.metrics.mae);
    if (c.method.filter == Filter::Vsm) vsmFrame = std::move(f);
  }
  const uint64_t vsm = cases[0].metrics.count(PixelClass::Bleed), evsm = cases[1].metrics.count(PixelClass::Bleed),
                 msm = cases[4].metrics.count(PixelClass::Bleed);
  // Measured (lavapipe, 480x270, map 1024, blur 4): vsm 391, evsm4 (10, 10) 89, msm 9; evsm2 and
  // evsm4 with the default exponents (40, 5) 0; pcf 0.
  EXPECT_GT(vsm, 200u);
  EXPECT_GT(vsm, 2 * evsm);
  EXPECT_GT(evsm, 2 * msm);
  EXPECT_LT(msm, vsm / 10);
  EXPECT_LE(cases[2].metrics.count(PixelClass::Bleed), msm);
  EXPECT_LE(cases[3].metrics.count(PixelClass::Bleed), msm);
  EXPECT_EQ(cases[5].metrics.count(PixelClass::Bleed), 0u) << "a depth-comparison filter has no moments";
  // Bleeding is not leak or other: VSM's ring is bleed. Without the moments' evidence (the same
  // frame, its moment channels removed) those pixels fall to leak and other.
  EXPECT_EQ(cases[0].metrics.count(PixelClass::Leak), 0u);
  EXPECT_EQ(cases[0].metrics.count(PixelClass::Other), 0u);
  Frame stripped;
  stripped.width = vsmFrame.width;
  stripped.height = vsmFrame.height;
  stripped.meta = vsmFrame.meta;
  for (size_t c = 0; c < vsmFrame.names.size(); ++c)
    if (vsmFrame.names[c].find(".moment_") == std::string::npos) stripped.add(vsmFrame.names[c]) = vsmFrame.data[c];
  const Metrics without = compareFrames(truth(), stripped);
  EXPECT_EQ(without.count(PixelClass::Bleed), 0u);
  EXPECT_EQ(without.count(PixelClass::Leak) + without.count(PixelClass::Other), vsm);
  std::printf("  vsm without the moment channels: leak %llu, other %llu\n",
              (unsigned long long)without.count(PixelClass::Leak),
              (unsigned long long)without.count(PixelClass::Other));
}

// A method silently replaced by another would render the other's image: every pair differs on
// this scene, and the moment channels exist exactly for the filterable maps.
TEST_F(FilterableMaps, NoMethodReturnsAnothersImage) {
  REQUIRE_DEVICE();
  const Scene s = stacked();
  const std::string light = s.lights[0].name;
  Method pcf = filtered(Filter::Pcf);
  pcf.filterSize = 9;
  const Frame fPcf = R->render(s, pcf), fVsm = R->render(s, filtered(Filter::Vsm)),
              fEvsm2 = R->render(s, filtered(Filter::Evsm2)), fEvsm4 = R->render(s, filtered(Filter::Evsm4)),
              fMsm = R->render(s, filtered(Filter::Msm));
  Method noBlur = filtered(Filter::Vsm);
  noBlur.filterBlur = 0;
  const Frame fVsm0 = R->render(s, noBlur);
  const struct {
    const char* what;
    const Frame *a, *b;
  } pairs[] = {{"vsm / pcf", &fVsm, &fPcf},     {"evsm2 / vsm", &fEvsm2, &fVsm}, {"evsm4 / evsm2", &fEvsm4, &fEvsm2},
               {"msm / evsm4", &fMsm, &fEvsm4}, {"msm / vsm", &fMsm, &fVsm},     {"blur 4 / blur 0", &fVsm, &fVsm0}};
  for (const auto& p : pairs) {
    const size_t n = differing(*p.a, *p.b, light);
    std::printf("  %s: %zu pixels differ by > 0.01\n", p.what, n);
    EXPECT_GT(n, 100u) << p.what;
  }
  for (const char* ch : {"moment_mean", "moment_variance", "moment_bound"}) {
    const std::string name = "light." + light + "." + ch;
    EXPECT_FALSE(fPcf.has(name)) << name;
    for (const Frame* f : {&fVsm, &fEvsm2, &fEvsm4, &fMsm}) EXPECT_TRUE(f->has(name)) << name;
  }
}

// The rasterizer keeps the moment images of earlier frames (another size or format: vsm's RG32F,
// msm's and evsm4's RGBA32F) and reuses them when a sweep comes back: every frame of a sequence
// that leaves and revisits them, with a non-filterable frame between, has the bits of a fresh
// rasterizer's frame, in every channel.
TEST_F(FilterableMaps, KeptMomentImagesGiveAFreshRasterizersBits) {
  REQUIRE_DEVICE();
  Scene s = stacked();
  s.camera.width = 240;
  s.camera.height = 135;
  auto method = [](Filter filter, int size) {
    Method m = filtered(filter);
    m.mapSize = size;
    m.filterBlur = 2;
    return m;
  };
  const std::pair<Filter, int> steps[] = {{Filter::Vsm, 256},   {Filter::Msm, 256}, {Filter::Pcf, 256},
                                          {Filter::Vsm, 512},   {Filter::Msm, 512}, {Filter::Vsm, 256},
                                          {Filter::Evsm4, 256}, {Filter::Msm, 256}, {Filter::Vsm, 512}};
  std::map<std::pair<Filter, int>, Frame> fresh;
  for (const auto& [filter, size] : steps) {
    if (fresh.count({filter, size})) continue;
    RasterDeviceOptions o;
    o.validation = true;
    Rasterizer r(o);
    fresh[{filter, size}] = r.render(s, method(filter, size));
    EXPECT_EQ(r.validationMessages(), 0);
  }
  for (const auto& [filter, size] : steps) {
    const Frame f = R->render(s, method(filter, size));
    const Frame& want = fresh[{filter, size}];
    const std::string what = toString(filter) + " " + std::to_string(size);
    ASSERT_EQ(f.names, want.names) << what;
    for (size_t c = 0; c < f.names.size(); ++c)
      EXPECT_EQ(0, std::memcmp(f.data[c].data(), want.data[c].data(), f.data[c].size() * sizeof(float)))
          << what << ": " << f.names[c];
  }
}

// The shader's bound is the one-sided Chebyshev bound of its own mean and variance at the
// receiver's reference depth, and vis is that bound through the linstep cut, at every pixel.
TEST_F(FilterableMaps, ChebyshevBoundAndBleedCutAreTheFormulasAtEveryPixel) {
  REQUIRE_DEVICE();
  const Scene s = stacked();
  const std::string p = "light." + s.lights[0].name + ".";
  Method m = filtered(Filter::Vsm);
  m.vsmBleedReduction = 0.3f;
  const Frame f = R->render(s, m);
  const auto &vis = f.get(p + "vis"), &recv = f.get(p + "receiver_depth"), &mean = f.get(p + "moment_mean"),
             &variance = f.get(p + "moment_variance"), &bound = f.get(p + "moment_bound"), &inMap = f.get(p + "in_map"),
             &hit = f.get("hit");
  size_t checked = 0, partial = 0;
  for (size_t i = 0; i < vis.size(); ++i) {
    if (hit[i] < 0.5f || inMap[i] < 0.5f || vis[i] == 0.0f) continue;  // 0: facing away (policy)
    const double t = double(recv[i]) - double(m.biasCompare), var = variance[i], d = t - mean[i];
    ASSERT_GE(var, double(m.vsmMinVariance) * (1 - 1e-6)) << i;
    const double expected = t <= mean[i] ? 1.0 : var / (var + d * d);
    ASSERT_NEAR(bound[i], expected, 1e-4 + 1e-3 * expected) << "pixel " << i;
    const double cut = std::clamp((double(bound[i]) - 0.3) / 0.7, 0.0, 1.0);
    ASSERT_NEAR(vis[i], cut, 1e-5) << "pixel " << i;
    ++checked;
    partial += bound[i] > 0.05f && bound[i] < 0.95f;
  }
  std::printf("  %zu pixels checked, %zu with a fractional bound\n", checked, partial);
  EXPECT_GT(checked, 50000u);
  EXPECT_GT(partial, 200u);
}

// A planted two-depth distribution: 60% of the footprint at depth 0.2, 40% at 0.6. Between the two
// the true lit fraction is 0.4: the 4-moment reconstruction finds it, Chebyshev's bound does not
// (0.66 at t = 0.5: the bleeding of VSM). Behind both: 0 lit; in front of both: 1.
TEST(FilterableMapsFormulas, HamburgerIsSharpOnTwoDepthsWhereChebyshevBleeds) {
  const double w1 = 0.6, z1 = 0.2, w2 = 0.4, z2 = 0.6;
  double moments[4];
  for (int k = 0; k < 4; ++k) moments[k] = w1 * std::pow(z1, k + 1) + w2 * std::pow(z2, k + 1);
  const double bias = 3e-5;
  EXPECT_NEAR(hamburger4(moments, 0.5, bias), 0.4, 0.01);
  EXPECT_NEAR(hamburger4(moments, 0.3, bias), 0.4, 0.01);
  EXPECT_NEAR(hamburger4(moments, 0.7, bias), 0.0, 0.01);
  EXPECT_NEAR(hamburger4(moments, 0.1, bias), 1.0, 1e-9);
  EXPECT_NEAR(chebyshev(moments[0], moments[1], 0.5), 0.0384 / (0.0384 + 0.0196), 1e-9);  // 0.662
  EXPECT_GT(chebyshev(moments[0], moments[1], 0.5), 0.6);
  // A larger moment bias smooths the reconstruction (less exact, more robust to quantization).
  EXPECT_GT(std::fabs(hamburger4(moments, 0.5, 0.05) - 0.4), std::fabs(hamburger4(moments, 0.5, bias) - 0.4));
}

// EVSM's exponents are clamped to what 32-bit moments hold (42): asking for more renders the same
// bits, and every output stays finite.
TEST_F(FilterableMaps, EvsmExponentsAreClampedToTheFormat) {
  REQUIRE_DEVICE();
  const Scene s = stacked();
  Method at = filtered(Filter::Evsm4), above = at;
  at.evsmExponentPos = at.evsmExponentNeg = 42;
  above.evsmExponentPos = above.evsmExponentNeg = 100;
  const Frame a = R->render(s, at), b = R->render(s, above);
  ASSERT_EQ(a.names, b.names);
  for (size_t c = 0; c < a.names.size(); ++c) {
    EXPECT_EQ(a.data[c], b.data[c]) << a.names[c];
    for (float v : b.data[c]) ASSERT_TRUE(std::isfinite(v)) << b.names[c];
  }
}

// Fractional visibility: the classes read the 0.5 decision, mae/rmse the fractions. Against the
// binary truth (spp 1) and the fractional one (spp 4) VSM's mae is the mean absolute difference of
// the clamped fractions over the compared pixels, recomputed here; its error_rate is not its mae.
TEST_F(FilterableMaps, MaeCarriesFractionalVisibilityAgainstBinaryAndFractionalTruth) {
  REQUIRE_DEVICE();
  const Scene s = stacked();
  const std::string name = "light." + s.lights[0].name + ".vis";
  const Frame ras = R->render(s, filtered(Filter::Vsm));
  ReferenceOptions spp4;
  spp4.spp = 4;
  const Frame fractional = renderReference(s, spp4);
  for (const Frame* ref : {&truth(), &fractional}) {
    const Metrics m = compareFrames(*ref, ras);
    const auto &rv = ref->get(name), &sv = ras.get(name), &rh = ref->get("hit"), &sh = ras.get("hit"),
               &ro = ref->get("object_id"), &so = ras.get("object_id");
    double sum = 0;
    size_t n = 0, fractionalRef = 0;
    for (size_t i = 0; i < rv.size(); ++i) {
      if (rh[i] < 0.5f || sh[i] < 0.5f || ro[i] != so[i]) continue;
      sum += std::fabs(double(std::clamp(rv[i], 0.0f, 1.0f)) - double(std::clamp(sv[i], 0.0f, 1.0f)));
      ++n;
      fractionalRef += rv[i] > 0.0f && rv[i] < 1.0f;
    }
    EXPECT_EQ(n, m.pixelsCompared);
    EXPECT_NEAR(m.mae, sum / double(n), 1e-9);
    EXPECT_GT(std::fabs(m.mae - m.errorRate), 1e-3) << "a fractional raster's mae is not its error rate";
    std::printf("  vsm against spp %d truth: mae %.5f, rmse %.5f, error_rate %.5f, %zu fractional truth pixels\n",
                ref == &fractional ? 4 : 1, m.mae, m.rmse, m.errorRate, fractionalRef);
    if (ref == &fractional) {
      EXPECT_GT(fractionalRef, 100u);
    }
  }
}

// Each filterable map on every bundled scene (its first light: directional, spot or a projector
// scene's), at a small camera and map: validation-clean (the fixture checks) and every output finite.
TEST_F(FilterableMaps, EveryBundledSceneRendersValidationCleanAndFinite) {
  REQUIRE_DEVICE();
  for (const std::string& name : bundledSceneNames()) {
    Scene s = loadScene(resolveScenePath(name));
    s.camera.width = 96;
    s.camera.height = 54;
    for (Filter filter : {Filter::Vsm, Filter::Evsm2, Filter::Evsm4, Filter::Msm}) {
      Method m;
      m.mapSize = 256;
      m.filter = filter;
      const Frame f = R->render(s, m);
      const std::string what = name + " / " + toString(filter);
      EXPECT_EQ(R->validationMessages(), 0) << what;
      EXPECT_EQ(f.has("light." + (s.lights.empty() ? std::string("?") : s.lights[0].name) + ".moment_bound"),
                !s.lights.empty())
          << what;
      for (size_t c = 0; c < f.names.size(); ++c)
        for (float v : f.data[c]) ASSERT_TRUE(std::isfinite(v)) << what << ": " << f.names[c];
    }
  }
}

// The shader's Hamburger reconstruction against the CPU copy above, where the footprint holds one
// depth z (variance ~0, away from every edge): the stored moments are (z, z^2, z^3, z^4) with z the
// mean, and the bound at the receiver's t must be the CPU's, in the lit (t <= z) and in the
// shadowed (t > z) interiors alike (the moment bias keeps both away from exactly 1 and 0).
TEST_F(FilterableMaps, MsmBoundIsTheHamburgerReconstructionWhereTheFootprintIsUniform) {
  REQUIRE_DEVICE();
  // The sun straight down: the ground's and the slab's depths are constant; the slab moved over
  // the visible ground, so its shadow's interior is in view.
  Scene s =
      loadScene(resolveScenePath("stacked_occluders"), {{"/lights/0/direction", nlohmann::json::array({0, -1, 0})},
                                                        {"/objects/2/transform/translate/0", 2.5},
                                                        {"/objects/2/transform/translate/1", 1.5}});
  s.camera.width = 480;
  s.camera.height = 270;
  const std::string p = "light." + s.lights[0].name + ".";
  Method m = filtered(Filter::Msm);
  m.msmMomentBias = 0.02f;  // a bias large enough that the bounds lie well inside (0, 1)
  const Frame f = R->render(s, m);
  const auto &recv = f.get(p + "receiver_depth"), &mean = f.get(p + "moment_mean"),
             &variance = f.get(p + "moment_variance"), &bound = f.get(p + "moment_bound"), &inMap = f.get(p + "in_map"),
             &vis = f.get(p + "vis"), &hit = f.get("hit");
  size_t lit = 0, shadowed = 0;
  double worst = 0, sumLit = 0, sumShadowed = 0;
  for (size_t i = 0; i < recv.size(); ++i) {
    if (hit[i] < 0.5f || inMap[i] < 0.5f || vis[i] == 0.0f || std::fabs(variance[i]) > 1e-7f) continue;
    const double z = mean[i], t = double(recv[i]) - double(m.biasCompare);
    const double moments[4] = {z, z * z, z * z * z, z * z * z * z};
    const double expected = hamburger4(moments, t, double(m.msmMomentBias));
    worst = std::max(worst, std::fabs(bound[i] - expected));
    ASSERT_NEAR(bound[i], expected, 0.02) << "pixel " << i << ", z " << z << ", t " << t;
    (t > z + 1e-3 ? shadowed : lit) += 1;
    (t > z + 1e-3 ? sumShadowed : sumLit) += expected;
  }
  std::printf(
      "  uniform footprints: %zu lit (mean bound %.4f), %zu shadowed (mean bound %.4f), largest |GPU - CPU| %.5f\n",
      lit, sumLit / double(std::max<size_t>(lit, 1)), shadowed, sumShadowed / double(std::max<size_t>(shadowed, 1)),
      worst);
  EXPECT_GT(lit, 1000u);
  EXPECT_GT(shadowed, 100u);
  EXPECT_GT(sumShadowed / double(shadowed), 0.3) << "so large a moment bias lights the shadow's interior";
  // With the default bias (3e-5) the same interior is dark: the bias is the knob that trades
  // robustness for bleeding.
  const Frame d = R->render(s, filtered(Filter::Msm));
  const auto& boundDefault = d.get(p + "moment_bound");
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < recv.size(); ++i)
    if (hit[i] >= 0.5f && inMap[i] >= 0.5f && vis[i] != 0.0f && std::fabs(variance[i]) <= 1e-7f &&
        double(recv[i]) - double(m.biasCompare) > double(mean[i]) + 1e-3)
      sum += boundDefault[i], ++n;
  ASSERT_EQ(n, shadowed);
  std::printf("  the same interior with msm.moment_bias 3e-5: mean bound %.5f\n", sum / double(n));
  EXPECT_LT(sum / double(n), 0.01);
}

}  // namespace compare_filterable_maps_test
