// The blind rule of frames from other renderers (classify.h classifyBlindDisagreement,
// compare/METRICS.md "Frames from other renderers"): the decision for one pixel on hand-built
// evidence, and compareFrames on a synthetic outside frame with planted errors at known distances
// from the true shadow boundary (the acne band of half a texel against aliasing's two).
#include <string>

#include <gtest/gtest.h>

#include "shadowlab/compare/classify.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/outside_frame.h"

namespace shadowlab::compare_metrics_blind_test {
namespace {

constexpr float kReceiver = 1;

// A compared pixel of an outside frame with a declared map (in_map 1, contact 0.05 world units).
PixelEvidence blind(bool referenceLit) {
  PixelEvidence e;
  e.blind = true;
  e.referenceHit = e.rasterHit = true;
  e.referenceObject = e.rasterObject = kReceiver;
  e.referenceVis = referenceLit ? 1.0f : 0.0f;
  e.rasterVis = referenceLit ? 0.0f : 1.0f;
  e.hasInMap = true;
  e.inMap = 1.0f;
  e.hasContact = true;
  e.contactWorld = 0.05f;
  e.hasTruthOccluderDistance = true;
  e.truthOccluderDist = referenceLit ? -1.0f : 3.0f;
  return e;
}

PixelClass decide(const PixelEvidence& e, bool withinBand) {
  const DisagreementClass d = classifyBlindDisagreement(e);
  return d.candidate ? resolveCandidate(d.leakEvidence, withinBand, d.bleedEvidence, d.acneEvidence) : d.cls;
}

TEST(BlindRule, TooDarkIsAcneBeyondTheBandAndAliasingWithinIt) {
  EXPECT_EQ(decide(blind(true), false), PixelClass::Acne);
  EXPECT_EQ(decide(blind(true), true), PixelClass::Aliasing);
  // The same evidence through classifyPixel, which picks the blind rule by e.blind.
  PixelEvidence e = blind(true);
  e.withinBoundaryBand = false;
  EXPECT_EQ(classifyPixel(e), PixelClass::Acne);
  // The full rule on the same evidence proves nothing (no occluder_id): other.
  e.blind = false;
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
}

TEST(BlindRule, WithoutADeclaredMapNothingIsAcneOrCoverage) {
  PixelEvidence e = blind(true);
  e.hasInMap = false;
  EXPECT_EQ(decide(e, false), PixelClass::Other);
  e = blind(false);
  e.hasInMap = false;
  e.hasContact = false;
  e.truthOccluderDist = 0.01f;
  EXPECT_EQ(decide(e, false), PixelClass::Other);
}

TEST(BlindRule, OutsideTheDeclaredMapIsCoverageWhateverTheValues) {
  for (bool lit : {true, false}) {
    PixelEvidence e = blind(lit);
    e.inMap = 0.0f;
    EXPECT_EQ(decide(e, true), PixelClass::Coverage);
    EXPECT_EQ(decide(e, false), PixelClass::Coverage);
  }
}

TEST(BlindRule, TooLitIsLeakInContactBleedWithAFilterableMapElseOther) {
  PixelEvidence e = blind(false);
  e.truthOccluderDist = 0.04f;  // within the 0.05 contact distance
  EXPECT_EQ(decide(e, false), PixelClass::Leak);
  EXPECT_EQ(decide(e, true), PixelClass::Aliasing);  // aliasing first within the band
  e.truthOccluderDist = 0.06f;
  EXPECT_EQ(decide(e, false), PixelClass::Other);
  e.declaredFilterable = true;
  EXPECT_EQ(decide(e, false), PixelClass::Bleed);
  e.truthOccluderDist = 0.04f;  // contact wins over a filterable map
  EXPECT_EQ(decide(e, false), PixelClass::Leak);
}

TEST(BlindRule, SizedLightsKeepThePenumbraClassesAndAcneOnlyOnAFullyLitTruth) {
  PixelEvidence e = blind(true);
  e.softTruth = true;
  e.referenceVis = 0.6f;  // a true penumbra drawn hard
  e.rasterVis = 0.0f;
  EXPECT_EQ(decide(e, false), PixelClass::PenumbraHard);
  e.referenceVis = 1.0f;  // fully lit, drawn in penumbra
  e.rasterVis = 0.3f;
  EXPECT_EQ(decide(e, false), PixelClass::PenumbraWide);
  e.rasterVis = 0.0f;  // fully lit, drawn in umbra: the receiver shadowing itself
  EXPECT_EQ(decide(e, false), PixelClass::Acne);
}

// A synthetic outside frame: a plane lit for x < 32 and shadowed beyond, m = 4 pixels per texel
// (acne band 2 px, aliasing band 8 px; distances to the nearest boundary pixel, x = 31 or 32). Dark
// pixels planted on the lit side 0, 4 and 11 pixels from it: aliasing, acne, acne. Lit pixels
// planted on the shadowed side 2 and 12 pixels from it: aliasing and, with the true occluder in
// contact, leak.
TEST(BlindRule, CompareFramesUsesTheNarrowAcneBandAndTheContactPlane) {
  constexpr int kW = 64, kH = 16, kBoundaryX = 32;
  Frame truth, outside;
  for (Frame* f : {&truth, &outside}) {
    f->width = kW;
    f->height = kH;
    f->meta["scene_hash"] = "00000000000000aa";
    f->meta["camera_hash"] = "00000000000000bb";
    f->meta["lights"] = {"sun"};
    f->add("hit", 1.0f);
    f->add("object_id", kReceiver);
    f->add("light.sun.vis", 0.0f);
  }
  truth.meta["kind"] = "reference";
  outside.meta["kind"] = "outside";
  outside.meta["light"] = "sun";
  truth.add("light.sun.occluder_dist", 0.02f);
  outside.add("light.sun.in_map", 1.0f);
  outside.add("light.sun.m", 4.0f);
  outside.add("light.sun.contact_world", 0.05f);
  for (Frame* f : {&truth, &outside})
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kBoundaryX; ++x) f->get("light.sun.vis")[size_t(y) * kW + x] = 1.0f;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kBoundaryX; ++x) truth.get("light.sun.occluder_dist")[size_t(y) * kW + x] = -1.0f;
  auto at = [&](int x, int y) { return size_t(y) * kW + size_t(x); };
  std::vector<float>& v = outside.get("light.sun.vis");
  v[at(kBoundaryX - 1, 4)] = 0.0f;    // a boundary pixel itself: aliasing
  v[at(kBoundaryX - 5, 6)] = 0.0f;    // 4 px: beyond the 2 px acne band
  v[at(kBoundaryX - 12, 8)] = 0.0f;   // 11 px
  v[at(kBoundaryX + 2, 10)] = 1.0f;   // 2 px into the shadow: within aliasing's 8 px
  v[at(kBoundaryX + 12, 12)] = 1.0f;  // 12 px, the true occluder 0.02 away: contact
  CompareOptions options;
  options.light = "sun";
  Classification c;
  const Metrics m = compareFrames(truth, outside, options, &c);
  EXPECT_EQ(c.classes[at(kBoundaryX - 1, 4)], PixelClass::Aliasing);
  EXPECT_EQ(c.classes[at(kBoundaryX - 5, 6)], PixelClass::Acne);
  EXPECT_EQ(c.classes[at(kBoundaryX - 12, 8)], PixelClass::Acne);
  EXPECT_EQ(c.classes[at(kBoundaryX + 2, 10)], PixelClass::Aliasing);
  EXPECT_EQ(c.classes[at(kBoundaryX + 12, 12)], PixelClass::Leak);
  EXPECT_EQ(m.errors, 5u);
  // Beyond contact: other; and with a declared filterable map, bleed.
  outside.get("light.sun.contact_world")[at(kBoundaryX + 12, 12)] = 0.01f;
  compareFrames(truth, outside, options, &c);
  EXPECT_EQ(c.classes[at(kBoundaryX + 12, 12)], PixelClass::Other);
  options.declaredFilterable = true;
  compareFrames(truth, outside, options, &c);
  EXPECT_EQ(c.classes[at(kBoundaryX + 12, 12)], PixelClass::Bleed);
}

}  // namespace
}  // namespace shadowlab::compare_metrics_blind_test
