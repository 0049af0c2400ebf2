// Soft shadows in compare (compare/METRICS.md "Soft shadows"), without any renderer: a reference
// with `light.L.vis_sigma` (a sized light's truth) switches compare to soft mode. Planted penumbra
// errors give exact penumbra_hard / penumbra_wide counts, differences within k sigma are counted in
// within_uncertainty and are no errors, the per-region MAE / RMSE and the signed over- and
// under-shadowing are exact on hand-computed frames and null where a region is empty; the
// CompareContext path gives the same bits as the full one; and hard-light frames (no vis_sigma)
// keep every metric they had, to the bit (the values below were written by compareFrames before
// the soft metrics existed).
#ifndef SHADOWLAB_SOFT_TEST_FRAMES_ONLY
#include <gtest/gtest.h>
#endif

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>

#include "shadowlab/compare/classify.h"
#include "shadowlab/compare/compare.h"

namespace shadowlab::compare_metrics_soft_test {
namespace softtest {

constexpr float kPlane = 1, kCaster = 2;

Frame emptyFrame(int w, int h) {
  Frame f;
  f.width = w;
  f.height = h;
  f.meta["scene"] = "synthetic";
  f.meta["lights"] = {"sun"};
  return f;
}

struct Pair {
  Frame reference, raster;
};

// A hard light's pair with every kind of evidence: random shadow blobs in the reference (their rims
// fractional, as --spp makes them), the raster's blobs shifted by a few pixels (or, `filtered`,
// softened over 3 pixels as PCF does), a band outside the map, acne dots, occluder distances, bias
// and depth channels, m from 0.3 to 6 and, `cascaded`, three cascades.
Pair hardPair(int w, int h, unsigned seed, bool filtered, bool cascaded) {
  Pair p;
  p.reference = emptyFrame(w, h);
  p.raster = emptyFrame(w, h);
  p.raster.meta["light"] = "sun";
  if (cascaded) p.raster.meta["method"] = {{"fit", "cascades"}, {"cascades.count", 3}};
  for (Frame* f : {&p.reference, &p.raster})
    for (const char* c : {"hit", "object_id", "light.sun.vis"}) f->add(c, 0.0f);
  p.reference.add("light.sun.occluder_dist", -1.0f);
  for (const char* c : {"in_map", "occluder_id", "receiver_depth", "map_depth", "bias_depth", "bias_world", "m"})
    p.raster.add(std::string("light.sun.") + c, 0.0f);
  if (cascaded) p.raster.add("light.sun.cascade", 0.0f);
  std::mt19937 rng(seed);
  auto u = [&] { return float(rng() % 100000) / 100000.0f; };  // the same numbers on every library
  std::vector<float> blobs;
  for (int k = 0; k < 6; ++k) blobs.insert(blobs.end(), {u() * w, u() * h, 3 + 10 * u()});
  const float shift = 1.0f + 3.0f * u();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const bool background = y >= h - 2;
      const bool mismatch = !background && x == w / 2 && y % 7 == 0;
      float ref = 1, ras = 1;
      for (size_t k = 0; k < blobs.size(); k += 3) {
        const float r = std::hypot(x - blobs[k], y - blobs[k + 1]) - blobs[k + 2];
        ref = std::min(ref, std::clamp(r + 0.5f, 0.0f, 1.0f));
        const float rs = std::hypot(x - blobs[k] - shift, y - blobs[k + 1]) - blobs[k + 2];
        ras = std::min(ras, filtered ? std::clamp(rs / 3.0f + 0.5f, 0.0f, 1.0f) : (rs >= 0.0f ? 1.0f : 0.0f));
      }
      if ((x * 7 + y * 3) % 53 == 0) ras = 0.0f;  // acne dots
      p.reference.get("hit")[i] = background ? 0.0f : 1.0f;
      p.raster.get("hit")[i] = background ? 0.0f : 1.0f;
      p.reference.get("object_id")[i] = background ? 0.0f : kPlane;
      p.raster.get("object_id")[i] = background ? 0.0f : mismatch ? kCaster : kPlane;
      if (background) continue;
      p.reference.get("light.sun.vis")[i] = ref;
      p.raster.get("light.sun.vis")[i] = ras;
      p.reference.get("light.sun.occluder_dist")[i] = ref >= 0.5f ? -1.0f : 0.01f + 0.2f * u();
      p.raster.get("light.sun.in_map")[i] = x < 3 ? 0.0f : 1.0f;
      p.raster.get("light.sun.occluder_id")[i] = ras >= 0.5f || (x + y) % 3 == 0 ? kPlane : kCaster;
      p.raster.get("light.sun.receiver_depth")[i] = 0.5f;
      p.raster.get("light.sun.map_depth")[i] = 0.5f - 0.002f * u();
      p.raster.get("light.sun.bias_depth")[i] = 0.001f;
      p.raster.get("light.sun.bias_world")[i] = 0.05f;
      p.raster.get("light.sun.m")[i] = 0.3f + 5.7f * u();
      if (cascaded) p.raster.get("light.sun.cascade")[i] = float(3 * y / h);
    }
  }
  return p;
}

}  // namespace softtest
}  // namespace shadowlab::compare_metrics_soft_test

#ifndef SHADOWLAB_SOFT_TEST_FRAMES_ONLY
namespace shadowlab::compare_metrics_soft_test {
namespace {

using namespace softtest;

PixelEvidence softPixel(float r, float sigma, float s) {
  PixelEvidence e;
  e.referenceHit = e.rasterHit = true;
  e.referenceObject = e.rasterObject = kPlane;
  e.referenceVis = r;
  e.rasterVis = s;
  e.softTruth = true;
  e.referenceSigma = sigma;
  return e;
}

TEST(SoftClasses, TableRowsAndColoursAreDistinct) {
  EXPECT_EQ(int(PixelClass::PenumbraWide), 9);
  EXPECT_EQ(int(PixelClass::PenumbraHard), 10);
  EXPECT_STREQ(classInfo(PixelClass::PenumbraWide).label, "penumbra too wide");
  EXPECT_STREQ(classInfo(PixelClass::PenumbraHard).label, "penumbra too hard");
  EXPECT_STREQ(classInfo(PixelClass::PenumbraWide).rateMetric, "penumbra_wide_rate");
  EXPECT_STREQ(classInfo(PixelClass::PenumbraHard).countMetric, "penumbra_hard");
  EXPECT_TRUE(isErrorClass(PixelClass::PenumbraWide));
  EXPECT_TRUE(isErrorClass(PixelClass::PenumbraHard));
  // Every swatch of errors.png differs from every other by at least 60 in some channel.
  std::vector<uint32_t> colours;
  for (const PixelClassInfo& c : kPixelClasses) {
    colours.push_back(c.rgbLit);
    if (c.rgbShadowed != c.rgbLit) colours.push_back(c.rgbShadowed);
  }
  for (size_t a = 0; a < colours.size(); ++a)
    for (size_t b = a + 1; b < colours.size(); ++b) {
      int most = 0;
      for (int sh : {0, 8, 16})
        most = std::max(most, std::abs(int((colours[a] >> sh) & 255) - int((colours[b] >> sh) & 255)));
      EXPECT_GE(most, 60) << std::hex << colours[a] << " vs " << colours[b];
    }
}

TEST(SoftClasses, EachClassOnItsOwnEvidence) {
  // The truth partial (0.5), the raster hard: too hard, either way.
  EXPECT_EQ(classifyPixel(softPixel(0.5f, 0, 1.0f)), PixelClass::PenumbraHard);
  EXPECT_EQ(classifyPixel(softPixel(0.5f, 0, 0.0f)), PixelClass::PenumbraHard);
  EXPECT_EQ(classifyPixel(softPixel(0.3f, 0, 0.97f)), PixelClass::PenumbraHard);  // 0.97 >= 1 - epsilon
  // The truth fully lit or umbra, the raster partial: too wide.
  EXPECT_EQ(classifyPixel(softPixel(1.0f, 0, 0.6f)), PixelClass::PenumbraWide);
  EXPECT_EQ(classifyPixel(softPixel(0.0f, 0, 0.3f)), PixelClass::PenumbraWide);
  EXPECT_EQ(classifyPixel(softPixel(0.97f, 0, 0.8f)), PixelClass::PenumbraWide);  // 0.97 >= 1 - epsilon
  // The same evidence under a hard light: only the decisions count.
  PixelEvidence hard = softPixel(0.5f, 0, 1.0f);
  hard.softTruth = false;
  EXPECT_EQ(classifyPixel(hard), PixelClass::Correct);
  hard = softPixel(1.0f, 0, 0.6f);
  hard.softTruth = false;
  EXPECT_EQ(classifyPixel(hard), PixelClass::Correct);
  // Both partial, off by more than the tolerance, nothing else proven: other (aliasing within
  // the band); the decisions agree (0.3, 0.45: both shadowed).
  EXPECT_EQ(classifyPixel(softPixel(0.3f, 0, 0.45f)), PixelClass::Other);
  PixelEvidence band = softPixel(0.3f, 0, 0.45f);
  band.withinBoundaryBand = true;
  EXPECT_EQ(classifyPixel(band), PixelClass::Aliasing);
  // A hard raster against a hard truth of the other decision: the hard precedence.
  EXPECT_EQ(classifyPixel(softPixel(0.0f, 0, 1.0f)), PixelClass::Other);
}

TEST(SoftClasses, ToleranceAndUncertainty) {
  // |R - S| <= 0.1: correct, whatever the decisions (0.46 shadowed, 0.55 lit).
  EXPECT_EQ(softDecision(0.46f, 0.55f, 0), SoftDecision::Correct);
  EXPECT_EQ(classifyPixel(softPixel(0.46f, 0, 0.55f)), PixelClass::Correct);
  // 0.3 off, sigma 0.08: within 0.1 + 3 * 0.08 = 0.34: correct, decided by the uncertainty.
  EXPECT_EQ(softDecision(0.5f, 0.8f, 0.08f), SoftDecision::WithinUncertainty);
  EXPECT_EQ(classifyPixel(softPixel(0.5f, 0.08f, 0.8f)), PixelClass::Correct);
  // The same with sigma 0.05 (limit 0.25): an error.
  EXPECT_EQ(softDecision(0.5f, 0.8f, 0.05f), SoftDecision::Error);
  // NaN or negative sigma is read as 0.
  EXPECT_EQ(softDecision(0.5f, 0.8f, std::nanf("")), SoftDecision::Error);
  EXPECT_EQ(softDecision(0.5f, 0.8f, -1.0f), SoftDecision::Error);
  // The truth's side is confident by k sigma: 0.93 with sigma 0.01 is neither surely partial
  // (0.93 + 0.03 >= 0.95) nor surely lit (0.93 - 0.03 < 0.95): a hard raster 0 there is not
  // penumbra_hard but the hard precedence's (other); with sigma 0 it is.
  EXPECT_EQ(classifyPixel(softPixel(0.93f, 0.01f, 0.0f)), PixelClass::Other);
  EXPECT_EQ(classifyPixel(softPixel(0.93f, 0.0f, 0.0f)), PixelClass::PenumbraHard);
  // Fully lit by the estimate, not surely (1 - 3 * 0.02 < 0.95): a partial raster 0.5 is no
  // penumbra_wide but off by 0.5 > 0.16, the decisions agree: other.
  EXPECT_EQ(classifyPixel(softPixel(1.0f, 0.02f, 0.5f)), PixelClass::Other);
}

TEST(SoftClasses, CoverageAndAcneStillWin) {
  PixelEvidence e = softPixel(0.5f, 0, 1.0f);
  e.hasInMap = true;
  e.inMap = 0;
  EXPECT_EQ(classifyPixel(e), PixelClass::Coverage);
  // Acne: the truth lit (0.7: partial), the raster shadowed by its own texel.
  e = softPixel(0.7f, 0, 0.0f);
  e.hasOccluderId = true;
  e.occluderId = kPlane;
  EXPECT_EQ(classifyPixel(e), PixelClass::Acne);
  e.occluderId = kCaster;
  EXPECT_EQ(classifyPixel(e), PixelClass::PenumbraHard);
  // A too-dark raster never counts as a leak, whatever its depths say; a too-lit one does.
  PixelEvidence leak = softPixel(0.3f, 0, 0.1f);
  leak.hasOccluderDistance = true;
  leak.referenceOccluderDist = 0.01f;
  leak.biasWorld = 0.05f;
  EXPECT_EQ(classifyPixel(leak), PixelClass::Other);
  leak.rasterVis = 0.6f;
  EXPECT_EQ(classifyPixel(leak), PixelClass::Leak);
}

// A soft pair of 24 x 4 pixels, one planted row per case (R, sigma, S per pixel):
Pair plantedSoftPair() {
  const int w = 24, h = 4;
  Pair p;
  p.reference = emptyFrame(w, h);
  p.raster = emptyFrame(w, h);
  for (Frame* f : {&p.reference, &p.raster}) {
    f->add("hit", 1.0f);
    f->add("object_id", kPlane);
    f->add("light.sun.vis", 1.0f);
  }
  p.reference.add("light.sun.vis_sigma", 0.0f);
  auto set = [&](int x, int y, float r, float sigma, float s) {
    const size_t i = size_t(y) * w + x;
    p.reference.get("light.sun.vis")[i] = r;
    p.reference.get("light.sun.vis_sigma")[i] = sigma;
    p.raster.get("light.sun.vis")[i] = s;
  };
  for (int x = 0; x < w; ++x) {
    // Row 0: a soft truth ramp 0 .. 1 (sigma 0.01), the raster's hard edge at its middle.
    const float ramp = float(x) / float(w - 1);
    set(x, 0, ramp, 0.01f, x < w / 2 ? 0.0f : 1.0f);
    // Row 1: a hard truth edge (0 | 1), the raster blurred over 8 pixels around it.
    set(x, 1, x < w / 2 ? 0.0f : 1.0f, 0.0f, std::clamp((float(x) - (w / 2 - 4) + 0.5f) / 8.0f, 0.0f, 1.0f));
    // Row 2: a partial truth 0.5 with sigma 0.1, the raster 0.75 (0.25 off: within 0.1 + 0.3).
    set(x, 2, 0.5f, 0.1f, 0.75f);
    // Row 3: all lit in both.
  }
  return p;
}

// Row 0's expected penumbra_hard pixels, row 1's penumbra_wide, from the definitions.
void expectedPlanted(uint64_t* hardCount, uint64_t* wideCount, uint64_t* otherErrors) {
  const Pair p = plantedSoftPair();
  *hardCount = *wideCount = *otherErrors = 0;
  for (size_t i = 0; i < p.reference.pixelCount(); ++i) {
    const float r = p.reference.get("light.sun.vis")[i], s = p.raster.get("light.sun.vis")[i];
    const float sigma = p.reference.get("light.sun.vis_sigma")[i];
    if (std::fabs(r - s) <= kSoftTolerance + kSoftSigmaK * sigma) continue;
    if (truthPartial(r, sigma) && (s <= kSoftEpsilon || s >= 1 - kSoftEpsilon)) ++*hardCount;
    else if (truthFully(r, sigma) && s > kSoftEpsilon && s < 1 - kSoftEpsilon) ++*wideCount;
    else ++*otherErrors;
  }
}

TEST(SoftCompare, PlantedPenumbraErrorsGiveExactCounts) {
  const Pair p = plantedSoftPair();
  Classification cls;
  const Metrics m = compareFrames(p.reference, p.raster, {}, &cls);
  // Row 0 by hand: R = x / 23, S = 0 for x < 12, 1 from 12. An error where |R - S| > 0.13 (0.1 +
  // 3 * 0.01): x = 3..11 (R 0.13 .. 0.48 vs 0; x = 3: 0.1304 > 0.13) and x = 12..19 (R 0.52 ..
  // 0.83 vs 1; x = 20: 0.8696, 0.1304 off, is an error too). Partial truth (0.05 + 0.03 < R and
  // R + 0.03 < 0.95): R in (0.08, 0.92): x = 2..21. So penumbra_hard: x = 3..11 and 12..20 = 18.
  EXPECT_EQ(m.count(PixelClass::PenumbraHard), 18u);
  // Row 1 by hand: S = (x - 7.5) / 8 clamped: x = 8..15 partial (0.0625 .. 0.9375), R = 0 below
  // 12, 1 from 12: errors where |R - S| > 0.1: x = 9, 10, 11 (0.19, 0.31, 0.44 vs 0) and
  // x = 12..14 (0.56, 0.69, 0.81 vs 1): penumbra_wide 6 (x = 8: 0.0625; x = 15: 0.9375 are within 0.1).
  EXPECT_EQ(m.count(PixelClass::PenumbraWide), 6u);
  uint64_t hard = 0, wide = 0, other = 0;
  expectedPlanted(&hard, &wide, &other);
  EXPECT_EQ(hard, 18u);
  EXPECT_EQ(wide, 6u);
  EXPECT_EQ(other, 0u);
  EXPECT_EQ(m.errors, 24u);
  // Row 2: 24 pixels 0.25 off with sigma 0.1: within the uncertainty, correct.
  EXPECT_EQ(m.withinUncertainty, 24u);
  EXPECT_EQ(m.count(PixelClass::Correct), 96u - 24u);
  EXPECT_EQ(cls.classes[3], PixelClass::PenumbraHard);
  EXPECT_EQ(cls.classes[2], PixelClass::Correct);
  EXPECT_EQ(cls.classes[24 + 9], PixelClass::PenumbraWide);
  EXPECT_EQ(cls.classes[24 + 8], PixelClass::Correct);
  const nlohmann::json j = m.toJson();
  EXPECT_EQ(j.at("penumbra_hard"), 18);
  EXPECT_EQ(j.at("penumbra_wide"), 6);
  EXPECT_DOUBLE_EQ(j.at("penumbra_hard_rate").get<double>(), 18.0 / 96.0);
  EXPECT_EQ(j.at("within_uncertainty"), 24);
  // Without vis_sigma the same pair is a hard light's: the decisions alone, and they agree at
  // every pixel (row 0 and 1 flip at x = 12 in both frames, row 2 is lit in both): no error.
  Frame stripped = emptyFrame(24, 4);
  for (const char* c : {"hit", "object_id", "light.sun.vis"}) stripped.add(c) = p.reference.get(c);
  const Metrics h = compareFrames(stripped, p.raster);
  EXPECT_EQ(h.errors, 0u);
  EXPECT_EQ(h.withinUncertainty, 0u);
}

TEST(SoftCompare, RegionErrorsAndSignedShadowingAreExact) {
  // 4 x 1: R = 1, 1, 0.5, 0; S = 0.75, 1, 1, 0.25 (all exact in binary).
  Frame ref = emptyFrame(4, 1), ras = emptyFrame(4, 1);
  for (Frame* f : {&ref, &ras}) {
    f->add("hit", 1.0f);
    f->add("object_id", kPlane);
  }
  ref.add("light.sun.vis") = std::vector<float>{1.0f, 1.0f, 0.5f, 0.0f};
  ras.add("light.sun.vis") = std::vector<float>{0.75f, 1.0f, 1.0f, 0.25f};
  for (bool soft : {false, true}) {
    Frame r = ref;
    if (soft) r.add("light.sun.vis_sigma", 0.0f);
    const nlohmann::json j = compareFrames(r, ras).toJson();
    EXPECT_EQ(j.at("lit_pixels"), 2);
    EXPECT_EQ(j.at("penumbra_pixels"), 1);
    EXPECT_EQ(j.at("umbra_pixels"), 1);
    EXPECT_EQ(j.at("lit_mae").get<double>(), 0.125);                // (0.25 + 0) / 2
    EXPECT_EQ(j.at("lit_rmse").get<double>(), std::sqrt(0.03125));  // sqrt((0.0625 + 0) / 2)
    EXPECT_EQ(j.at("penumbra_mae").get<double>(), 0.5);
    EXPECT_EQ(j.at("penumbra_rmse").get<double>(), 0.5);
    EXPECT_EQ(j.at("umbra_mae").get<double>(), 0.25);
    EXPECT_EQ(j.at("umbra_rmse").get<double>(), 0.25);
    EXPECT_EQ(j.at("over_shadowing").get<double>(), 0.0625);   // (0.25) / 4: the raster darker
    EXPECT_EQ(j.at("under_shadowing").get<double>(), 0.1875);  // (0.5 + 0.25) / 4: lighter
    EXPECT_EQ(j.at("mae").get<double>(), 0.25);
    // Soft: pixel 0 (0.25 off, truth lit, raster partial) is penumbra_wide, pixel 2 (truth 0.5,
    // raster 1) penumbra_hard, pixel 3 (0 vs 0.25) penumbra_wide. Hard: only pixel 3 is no error
    // either (both shadowed); pixel 0 and 2 agree too (lit).
    EXPECT_EQ(j.at("penumbra_wide"), soft ? 2 : 0) << soft;
    EXPECT_EQ(j.at("penumbra_hard"), soft ? 1 : 0) << soft;
    EXPECT_EQ(j.at("errors"), soft ? 3 : 0) << soft;
  }
}

TEST(SoftCompare, EmptyRegionsAreNull) {
  // A binary truth: no penumbra; all lit: no penumbra and no umbra.
  Frame ref = emptyFrame(3, 1), ras = emptyFrame(3, 1);
  for (Frame* f : {&ref, &ras}) {
    f->add("hit", 1.0f);
    f->add("object_id", kPlane);
  }
  ref.add("light.sun.vis") = std::vector<float>{1.0f, 0.0f, 1.0f};
  ras.add("light.sun.vis") = std::vector<float>{1.0f, 0.5f, 0.9f};
  nlohmann::json j = compareFrames(ref, ras).toJson();
  EXPECT_EQ(j.at("penumbra_pixels"), 0);
  EXPECT_TRUE(j.at("penumbra_mae").is_null());
  EXPECT_TRUE(j.at("penumbra_rmse").is_null());
  EXPECT_EQ(j.at("umbra_mae").get<double>(), 0.5);
  EXPECT_NEAR(j.at("lit_mae").get<double>(), 0.05, 1e-7);
  ref.get("light.sun.vis")[1] = 1.0f;
  j = compareFrames(ref, ras).toJson();
  EXPECT_TRUE(j.at("umbra_mae").is_null());
  EXPECT_TRUE(j.at("umbra_rmse").is_null());
  EXPECT_EQ(j.at("umbra_pixels"), 0);
  EXPECT_EQ(j.at("lit_pixels"), 3);
  // Nothing compared: every region empty, over/under null as the other ratios.
  for (Frame* f : {&ref, &ras}) f->get("hit") = std::vector<float>(3, 0.0f);
  j = compareFrames(ref, ras).toJson();
  for (const char* k : {"lit_mae", "penumbra_rmse", "umbra_mae", "over_shadowing", "under_shadowing"})
    EXPECT_TRUE(j.at(k).is_null()) << k;
  EXPECT_EQ(j.at("within_uncertainty"), 0);
}

// compareFrames' JSON of two hard-light pairs before the soft metrics existed (hardPair(64, 48, 7,
// false, false) and hardPair(64, 48, 11, true, true): shifted and filtered blobs, acne, coverage,
// leaks, mismatches, cascades), written by the code of that time.
const char* const kHardBefore[2] = {
    R"({"acne":46,"acne_rate":0.015662240381341504,"aliasing":222,"aliasing_rate":0.0755873340143003,"bleed":0,"bleed_rate":0.0,"coverage":22,"coverage_rate":0.00749063670411985,"error_rate":0.10554988083077971,"errors":310,"geometry_mismatch":7,"leak":3,"leak_rate":0.0010214504596527069,"m_capped":0,"m_max":5.999088287353516,"m_median":3.0974457263946533,"m_p95":5.633318901062012,"mae":0.10984076940570918,"other":17,"other_rate":0.005788219271365339,"pixels_compared":2937,"rmse":0.3167880214371643,"shadow_iou":0.6168108776266996})",
    R"({"acne":50,"acne_rate":0.017024174327545116,"aliasing":194,"aliasing_rate":0.06605379639087504,"bleed":0,"bleed_rate":0.0,"cascades":[{"error_rate":0.08031341821743389,"index":0,"m_p95":5.682224750518799,"pixels":1021},{"error_rate":0.08414872798434442,"index":1,"m_p95":5.742929935455322,"pixels":1022},{"error_rate":0.09843400447427293,"index":2,"m_p95":5.706849098205566,"pixels":894}],"coverage":3,"coverage_rate":0.0010214504596527069,"error_rate":0.08716377255703098,"errors":256,"geometry_mismatch":7,"leak":1,"leak_rate":0.00034048348655090226,"m_capped":0,"m_max":5.999601364135742,"m_median":3.1018919944763184,"m_p95":5.70918607711792,"mae":0.09533298743148624,"other":8,"other_rate":0.002723867892407218,"pixels_compared":2937,"rmse":0.24218473468608015,"shadow_iou":0.7259100642398287})"};

TEST(SoftCompare, HardLightsKeepEveryMetricTheyHad) {
  const Pair pairs[2] = {hardPair(64, 48, 7, false, false), hardPair(64, 48, 11, true, true)};
  const std::set<std::string> added = {
      "penumbra_wide", "penumbra_wide_rate", "penumbra_hard",   "penumbra_hard_rate", "lit_pixels",   "lit_mae",
      "lit_rmse",      "penumbra_pixels",    "penumbra_mae",    "penumbra_rmse",      "umbra_pixels", "umbra_mae",
      "umbra_rmse",    "over_shadowing",     "under_shadowing", "within_uncertainty"};
  for (int k = 0; k < 2; ++k) {
    nlohmann::json now = compareFrames(pairs[k].reference, pairs[k].raster).toJson();
    const nlohmann::json before = nlohmann::json::parse(kHardBefore[k]);
    EXPECT_EQ(now.at("penumbra_wide"), 0);
    EXPECT_EQ(now.at("penumbra_hard"), 0);
    EXPECT_EQ(now.at("within_uncertainty"), 0);
    // The reference's rims are fractional (--spp-like): a penumbra region, measured.
    EXPECT_GT(now.at("penumbra_pixels").get<uint64_t>(), 0u);
    EXPECT_EQ(now.at("lit_pixels").get<uint64_t>() + now.at("penumbra_pixels").get<uint64_t>() +
                  now.at("umbra_pixels").get<uint64_t>(),
              now.at("pixels_compared").get<uint64_t>());
    EXPECT_NEAR(now.at("over_shadowing").get<double>() + now.at("under_shadowing").get<double>(),
                now.at("mae").get<double>(), 1e-12);
    for (const std::string& key : added) {
      EXPECT_TRUE(now.contains(key)) << key;
      now.erase(key);
    }
    EXPECT_EQ(now.dump(), before.dump()) << "pair " << k;
  }
}

// A group of soft frames (the same hit, object and m planes; the raster vis per configuration):
// CompareContext gives compareFrames' JSON and classes bit for bit, with penumbra classes, soft
// errors where the decisions agree and pixels within the uncertainty among them.
TEST(SoftCompare, ContextPathGivesTheFullPathsBits) {
  const int w = 96, h = 64;
  Pair base = hardPair(w, h, 5, true, false);
  base.raster.meta["evidence_group"] = "soft-group";
  // A soft truth: the blobs' fractional rims moved by up to 0.2, sigma up to 0.06 there.
  std::vector<float>& sigma = base.reference.add("light.sun.vis_sigma");
  std::vector<float>& vis = base.reference.get("light.sun.vis");
  std::mt19937 rng(3);
  for (size_t i = 0; i < vis.size(); ++i) {
    if (vis[i] > 0.0f && vis[i] < 1.0f) vis[i] = std::clamp(vis[i] + float(rng() % 5) * 0.1f - 0.2f, 0.0f, 1.0f);
    sigma[i] = vis[i] > 0.0f && vis[i] < 1.0f ? float(rng() % 7) * 0.01f : 0.0f;
  }
  CompareContext context(base.reference, base.raster);
  ASSERT_TRUE(context.appliesTo(base.reference, base.raster));
  uint64_t hard = 0, wide = 0, within = 0, agreeingErrors = 0;
  for (unsigned config = 0; config < 5; ++config) {
    Frame raster = base.raster;
    std::vector<float>& v = raster.get("light.sun.vis");
    std::mt19937 r(100 + config);
    for (size_t i = 0; i < v.size(); ++i) {
      const unsigned pick = r() % 10;
      if (pick == 0) v[i] = float(r() % 11) / 10.0f;            // anything
      else if (pick == 1) v[i] = std::round(v[i]);              // hardened
      else if (pick == 2) v[i] = v[i] * 0.8f + 0.1f;            // softened
      else if (pick == 3 && config == 4) v[i] = std::nanf("");  // NaN read as 0
    }
    Classification full, fast;
    const Metrics a = compareFrames(base.reference, raster, {}, &full);
    const Metrics b = compareFrames(context, base.reference, raster, &fast);
    EXPECT_EQ(a.toJson().dump(), b.toJson().dump()) << config;
    EXPECT_TRUE(full.classes == fast.classes) << config;
    hard += a.count(PixelClass::PenumbraHard);
    wide += a.count(PixelClass::PenumbraWide);
    within += a.withinUncertainty;
    const std::vector<float>& rv = base.reference.get("light.sun.vis");
    for (size_t i = 0; i < v.size(); ++i)
      agreeingErrors += isErrorClass(full.classes[i]) && litDecision(rv[i]) == litDecision(v[i]);
  }
  EXPECT_GT(hard, 100u);
  EXPECT_GT(wide, 100u);
  EXPECT_GT(within, 20u);
  EXPECT_GT(agreeingErrors, 100u);
}

}  // namespace
}  // namespace shadowlab::compare_metrics_soft_test
#endif
