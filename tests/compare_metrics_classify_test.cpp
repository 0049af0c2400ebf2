// The steps of compareFrames on their own (classify.h): the class table, the decision for one pixel
// on hand-built evidence (each class and each precedence tie), and the tallies on planted classes.
#include <cmath>
#include <limits>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "shadowlab/compare/classify.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::compare_metrics_classify_test {
namespace {

constexpr float kReceiver = 1, kCaster = 2;

// A compared pixel (both frames hit the receiver) where the reference is lit and the raster
// shadowed, or the other way round; no evidence channel at all.
PixelEvidence disagreement(bool referenceLit) {
  PixelEvidence e;
  e.referenceHit = e.rasterHit = true;
  e.referenceObject = e.rasterObject = kReceiver;
  e.referenceVis = referenceLit ? 1.0f : 0.0f;
  e.rasterVis = referenceLit ? 0.0f : 1.0f;
  return e;
}

// Evidence of acne: the map texel holds the receiver itself.
PixelEvidence acneEvidence() {
  PixelEvidence e = disagreement(true);
  e.hasOccluderId = true;
  e.occluderId = kReceiver;
  return e;
}

// Leak (a): the caster is in the map 0.0005 in front of the receiver, the bias is 0.001.
PixelEvidence leakThroughMap() {
  PixelEvidence e = disagreement(false);
  e.hasOccluderId = true;
  e.occluderId = kCaster;
  e.hasDepths = true;
  e.receiverDepth = 0.5f;
  e.mapDepth = 0.4995f;
  e.biasDepth = 0.001f;
  return e;
}

// Leak (b): the true occluder 0.012 world units away, the bias 0.01 (within the 1.5 slack).
PixelEvidence leakWithinBias() {
  PixelEvidence e = disagreement(false);
  e.hasOccluderDistance = true;
  e.referenceOccluderDist = 0.012f;
  e.biasWorld = 0.01f;
  return e;
}

// Bleed: a filterable map's bound (0.6) lit a receiver at depth 0.5 whose footprint's mean depth
// (0.42) lies 0.08 in front of it, far beyond the 0.001 bias: the variance came from a second
// occluder layer (the map's center texel holds the caster, another layer is in the footprint).
PixelEvidence bleedEvidencePixel() {
  PixelEvidence e = disagreement(false);
  e.rasterVis = 0.6f;
  e.hasOccluderId = true;
  e.occluderId = kCaster;
  e.hasDepths = true;
  e.receiverDepth = 0.5f;
  e.mapDepth = 0.45f;
  e.biasDepth = 0.001f;
  e.hasMoments = true;
  e.momentMean = 0.42f;
  e.momentBound = 0.6f;
  return e;
}

TEST(CompareClassTable, CodesKeysAndMetricNamesAreTheStableOnes) {
  // Written to files and read by the gate: these must not move.
  const struct {
    PixelClass cls;
    int code;
    const char* key;
  } expected[] = {{PixelClass::NotCompared, 0, "not_compared"},
                  {PixelClass::GeometryMismatch, 1, "geometry_mismatch"},
                  {PixelClass::Correct, 2, "correct"},
                  {PixelClass::Acne, 3, "acne"},
                  {PixelClass::Leak, 4, "leak"},
                  {PixelClass::Aliasing, 5, "aliasing"},
                  {PixelClass::Coverage, 6, "coverage"},
                  {PixelClass::Other, 7, "other"},
                  {PixelClass::Bleed, 8, "bleed"},
                  {PixelClass::PenumbraWide, 9, "penumbra_wide"},
                  {PixelClass::PenumbraHard, 10, "penumbra_hard"}};
  for (const auto& x : expected) {
    EXPECT_EQ(int(x.cls), x.code) << x.key;
    EXPECT_STREQ(toString(x.cls), x.key);
    EXPECT_STREQ(classInfo(x.cls).key, x.key);
  }
  EXPECT_STREQ(toString(PixelClass(200)), "unknown");
  // Every class metric Metrics::toJson writes, and nothing else from the table.
  std::set<std::string> metrics;
  for (const PixelClassInfo& c : kPixelClasses) {
    if (c.countMetric) metrics.insert(c.countMetric);
    if (c.rateMetric) metrics.insert(c.rateMetric);
  }
  EXPECT_EQ(metrics, (std::set<std::string>{"geometry_mismatch", "acne", "leak", "bleed", "aliasing", "coverage",
                                            "other", "acne_rate", "leak_rate", "bleed_rate", "aliasing_rate",
                                            "coverage_rate", "other_rate", "penumbra_wide", "penumbra_wide_rate",
                                            "penumbra_hard", "penumbra_hard_rate"}));
  Metrics one;  // a comparison of one pixel: an empty one also says "nothing_compared"
  one.pixelsCompared = 1;
  const nlohmann::json j = one.toJson();
  EXPECT_EQ(Metrics{}.toJson().size(), j.size() + 1);
  EXPECT_EQ(Metrics{}.toJson().at("nothing_compared"), true);
  std::set<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.insert(it.key());
  EXPECT_EQ(keys, (std::set<std::string>{"pixels_compared",
                                         "geometry_mismatch",
                                         "errors",
                                         "acne",
                                         "leak",
                                         "bleed",
                                         "aliasing",
                                         "coverage",
                                         "other",
                                         "error_rate",
                                         "acne_rate",
                                         "leak_rate",
                                         "bleed_rate",
                                         "aliasing_rate",
                                         "coverage_rate",
                                         "other_rate",
                                         "shadow_iou",
                                         "mae",
                                         "rmse",
                                         "m_median",
                                         "m_p95",
                                         "m_max",
                                         "m_capped",
                                         "penumbra_wide",
                                         "penumbra_hard",
                                         "penumbra_wide_rate",
                                         "penumbra_hard_rate",
                                         "lit_pixels",
                                         "lit_mae",
                                         "lit_rmse",
                                         "penumbra_pixels",
                                         "penumbra_mae",
                                         "penumbra_rmse",
                                         "umbra_pixels",
                                         "umbra_mae",
                                         "umbra_rmse",
                                         "over_shadowing",
                                         "under_shadowing",
                                         "within_uncertainty"}));
}

TEST(CompareClassTable, ColoursAreTheOnesErrorsPngHasAlwaysUsed) {
  auto rgb = [](PixelClass c, bool lit) {
    uint8_t v[3];
    classColor(c, lit, v);
    return std::vector<int>{v[0], v[1], v[2]};
  };
  EXPECT_EQ(rgb(PixelClass::NotCompared, false), (std::vector<int>{18, 20, 40}));
  EXPECT_EQ(rgb(PixelClass::GeometryMismatch, false), (std::vector<int>{150, 95, 45}));
  EXPECT_EQ(rgb(PixelClass::Correct, true), (std::vector<int>{190, 190, 190}));
  EXPECT_EQ(rgb(PixelClass::Correct, false), (std::vector<int>{85, 85, 85}));
  EXPECT_EQ(rgb(PixelClass::Acne, false), (std::vector<int>{235, 35, 35}));
  EXPECT_EQ(rgb(PixelClass::Leak, true), (std::vector<int>{30, 120, 255}));
  EXPECT_EQ(rgb(PixelClass::Aliasing, false), (std::vector<int>{255, 215, 0}));
  EXPECT_EQ(rgb(PixelClass::Coverage, false), (std::vector<int>{40, 200, 70}));
  EXPECT_EQ(rgb(PixelClass::Other, false), (std::vector<int>{255, 0, 255}));
  EXPECT_EQ(rgb(PixelClass::Bleed, true), (std::vector<int>{0, 200, 200}));
}

TEST(CompareClassTable, JsonListsEveryRowInTableOrder) {
  const nlohmann::json j = pixelClassesJson();
  ASSERT_EQ(j.size(), kPixelClassCount);
  for (size_t r = 0; r < kPixelClassCount; ++r) {
    EXPECT_EQ(j[r]["code"], int(kPixelClasses[r].cls));
    EXPECT_EQ(j[r]["key"], kPixelClasses[r].key);
    EXPECT_EQ(j[r]["error"], kPixelClasses[r].error);
  }
  EXPECT_EQ(j[1]["key"], "acne");
  EXPECT_EQ(j[1]["rate_metric"], "acne_rate");
  EXPECT_EQ(j[1]["color"], "#eb2323");
  EXPECT_TRUE(j[0]["rate_metric"].is_null());  // correct has no metric
}

TEST(ClassifyPixel, EachClassOnItsOwnEvidence) {
  PixelEvidence background;
  EXPECT_EQ(classifyPixel(background), PixelClass::NotCompared);

  PixelEvidence onlyOne = disagreement(true);
  onlyOne.rasterHit = false;
  EXPECT_EQ(classifyPixel(onlyOne), PixelClass::GeometryMismatch);
  PixelEvidence otherObject = disagreement(true);
  otherObject.rasterObject = kCaster;
  EXPECT_EQ(classifyPixel(otherObject), PixelClass::GeometryMismatch);

  PixelEvidence agree = acneEvidence();  // evidence does not matter where the decisions agree
  agree.rasterVis = 0.7f;
  EXPECT_EQ(classifyPixel(agree), PixelClass::Correct);

  PixelEvidence outside = disagreement(true);
  outside.hasInMap = true;
  outside.inMap = 0.0f;
  EXPECT_EQ(classifyPixel(outside), PixelClass::Coverage);

  EXPECT_EQ(classifyPixel(acneEvidence()), PixelClass::Acne);

  PixelEvidence nearEdge = disagreement(false);
  nearEdge.withinBoundaryBand = true;
  EXPECT_EQ(classifyPixel(nearEdge), PixelClass::Aliasing);

  EXPECT_EQ(classifyPixel(leakThroughMap()), PixelClass::Leak);
  EXPECT_EQ(classifyPixel(leakWithinBias()), PixelClass::Leak);

  EXPECT_EQ(classifyPixel(bleedEvidencePixel()), PixelClass::Bleed);

  EXPECT_EQ(classifyPixel(disagreement(true)), PixelClass::Other);
  EXPECT_EQ(classifyPixel(disagreement(false)), PixelClass::Other);
}

// Light bleeding is not leak: the leak evidence holding as well (the true occluder within the
// bias's slack, which a bleeding pixel near its lower occluder easily has) does not make it leak,
// since the moments put the occluders 0.08 in front, far beyond the bias. Without the moments the
// same pixel is leak, and each part of the bleed evidence is needed.
TEST(ClassifyPixel, BleedingIsNotLeakAndNeedsEachPartOfItsEvidence) {
  PixelEvidence e = bleedEvidencePixel();
  e.hasOccluderDistance = true;
  e.referenceOccluderDist = 0.012f;
  e.biasWorld = 0.01f;
  EXPECT_EQ(classifyPixel(e), PixelClass::Bleed);
  e.hasMoments = false;  // a depth-comparison filter's frame: the leak evidence decides
  EXPECT_EQ(classifyPixel(e), PixelClass::Leak);

  e = bleedEvidencePixel();
  e.momentMean = 0.4995f;  // the mean within the bias of the receiver: the bias, not a second layer
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = bleedEvidencePixel();
  e.momentBound = std::nextafter(0.5f, 0.0f);  // the bound alone would not have lit it (a blend band did)
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = bleedEvidencePixel();
  e.hasDepths = false;
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  // Bleed needs a shadowed truth: a lit truth the map shadows is not bleeding.
  e = bleedEvidencePixel();
  e.referenceVis = 1.0f;
  e.rasterVis = 0.0f;
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  // Within the boundary band the map's resolution (the blurred edge) explains it first.
  e = bleedEvidencePixel();
  e.withinBoundaryBand = true;
  EXPECT_EQ(classifyPixel(e), PixelClass::Aliasing);
  // Coverage first, as for every class.
  e = bleedEvidencePixel();
  e.hasInMap = true;
  e.inMap = 0.0f;
  EXPECT_EQ(classifyPixel(e), PixelClass::Coverage);
}

TEST(ClassifyPixel, PrecedenceTies) {
  // Coverage over acne and over leak: outside the map no other evidence is meaningful.
  PixelEvidence e = acneEvidence();
  e.hasInMap = true;
  e.inMap = 0.2f;
  EXPECT_EQ(classifyPixel(e), PixelClass::Coverage);
  e = leakThroughMap();
  e.hasInMap = true;
  e.inMap = 0.0f;
  EXPECT_EQ(classifyPixel(e), PixelClass::Coverage);
  // Coverage over aliasing.
  e.withinBoundaryBand = true;
  EXPECT_EQ(classifyPixel(e), PixelClass::Coverage);
  // Acne over aliasing: the own texel is decided before the boundary distance.
  e = acneEvidence();
  e.withinBoundaryBand = true;
  EXPECT_EQ(classifyPixel(e), PixelClass::Acne);
  // Aliasing over leak, for both kinds of leak evidence.
  e = leakThroughMap();
  e.withinBoundaryBand = true;
  EXPECT_EQ(classifyPixel(e), PixelClass::Aliasing);
  e = leakWithinBias();
  e.withinBoundaryBand = true;
  EXPECT_EQ(classifyPixel(e), PixelClass::Aliasing);
  // Geometry mismatch over everything a disagreement could be.
  e = acneEvidence();
  e.referenceObject = kCaster;
  EXPECT_EQ(classifyPixel(e), PixelClass::GeometryMismatch);
}

TEST(ClassifyPixel, EvidenceOnlyCountsForItsOwnDirection) {
  // Acne needs a lit reference: the receiver's own texel under a shadowed reference is no acne.
  PixelEvidence e = acneEvidence();
  e.referenceVis = 0.0f;
  e.rasterVis = 1.0f;
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  // Leak needs a shadowed reference: the same evidence under a lit reference is other.
  for (PixelEvidence leak : {leakThroughMap(), leakWithinBias()}) {
    leak.referenceVis = 1.0f;
    leak.rasterVis = 0.0f;
    EXPECT_EQ(classifyPixel(leak), PixelClass::Other);
  }
}

TEST(ClassifyPixel, MissingOrEmptyEvidenceProvesNothing) {
  PixelEvidence e = acneEvidence();
  e.hasOccluderId = false;  // the value is there, the channel is not
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = disagreement(true);
  e.inMap = 0.0f;  // hasInMap false
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = leakThroughMap();
  e.hasDepths = false;
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = leakThroughMap();
  e.occluderId = 0.0f;  // nothing in the map
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = leakThroughMap();
  e.occluderId = kReceiver;  // a texel the receiver wrote itself proves no occluder
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = leakThroughMap();
  e.mapDepth = 0.4985f;  // the caster 0.0015 in front: beyond the 0.001 bias
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
  e = leakWithinBias();
  e.referenceOccluderDist = -1.0f;  // no occluder in truth
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
}

TEST(ClassifyPixel, LeakBiasFactorBoundsTheDistance) {
  PixelEvidence e = leakWithinBias();
  e.biasWorld = 0.01f;
  e.referenceOccluderDist = 1.5f * 0.01f;  // exactly at the slack: included
  EXPECT_EQ(classifyPixel(e, 1.5f), PixelClass::Leak);
  e.referenceOccluderDist = std::nextafter(1.5f * 0.01f, 1.0f);
  EXPECT_EQ(classifyPixel(e, 1.5f), PixelClass::Other);
  EXPECT_EQ(classifyPixel(e, 2.0f), PixelClass::Leak);
}

TEST(ClassifyPixel, DecisionIsLitFromOneHalfAndNanIsShadowed) {
  EXPECT_TRUE(litDecision(0.5f));
  EXPECT_FALSE(litDecision(std::nextafter(0.5f, 0.0f)));
  EXPECT_TRUE(litDecision(7.0f));
  EXPECT_FALSE(litDecision(-1.0f));
  EXPECT_FALSE(litDecision(std::numeric_limits<float>::quiet_NaN()));
  PixelEvidence e = disagreement(true);
  e.rasterVis = std::numeric_limits<float>::quiet_NaN();  // read as 0: shadowed, a disagreement
  EXPECT_EQ(classifyPixel(e), PixelClass::Other);
}

TEST(ClassTallies, PlantedClassesGiveExactCountsAndRates) {
  // 1000 pixels: 100 background, 13 geometry mismatches, 37 acne, 5 leak, the rest correct.
  std::vector<PixelClass> classes(1000, PixelClass::Correct);
  for (int k = 0; k < 100; ++k) classes[size_t(k)] = PixelClass::NotCompared;
  for (int k = 0; k < 13; ++k) classes[size_t(100 + k)] = PixelClass::GeometryMismatch;
  for (int k = 0; k < 37; ++k) classes[size_t(200 + 7 * k)] = PixelClass::Acne;  // scattered among correct ones
  for (int k = 0; k < 5; ++k) classes[size_t(600 + k)] = PixelClass::Leak;
  const PerPixelClass<uint64_t> counts = countClasses(classes);
  EXPECT_EQ(counts[classIndex(PixelClass::Acne)], 37u);
  EXPECT_EQ(counts[classIndex(PixelClass::Leak)], 5u);
  EXPECT_EQ(counts[classIndex(PixelClass::NotCompared)], 100u);
  EXPECT_EQ(counts[classIndex(PixelClass::GeometryMismatch)], 13u);
  EXPECT_EQ(counts[classIndex(PixelClass::Correct)], 1000u - 100 - 13 - 37 - 5);
  Metrics m;
  setClassMetrics(m, counts);
  const uint64_t compared = 1000 - 100 - 13;  // correct and the error classes
  EXPECT_EQ(m.pixelsCompared, compared);
  EXPECT_EQ(m.count(PixelClass::Acne), 37u);
  EXPECT_EQ(m.rate(PixelClass::Acne), 37.0 / double(compared));
  EXPECT_EQ(m.rate(PixelClass::Leak), 5.0 / double(compared));
  EXPECT_EQ(m.rate(PixelClass::Aliasing), 0.0);
  EXPECT_EQ(m.errors, 42u);
  EXPECT_EQ(m.errorRate, 42.0 / double(compared));
  const nlohmann::json j = m.toJson();
  EXPECT_EQ(j["acne"], 37u);
  EXPECT_EQ(j["acne_rate"], 37.0 / double(compared));
  EXPECT_EQ(j["geometry_mismatch"], 13u);
  EXPECT_EQ(errorClassSummary(m, false),
            "acne 37, leak 5, bleed 0, aliasing 0, coverage 0, penumbra_wide 0, penumbra_hard 0, other 0");
}

TEST(ClassTallies, NothingComparedGivesZeroRates) {
  Metrics m;
  setClassMetrics(m, countClasses(std::vector<PixelClass>(50, PixelClass::GeometryMismatch)));
  EXPECT_EQ(m.pixelsCompared, 0u);
  EXPECT_EQ(m.count(PixelClass::GeometryMismatch), 50u);
  for (size_t k = 0; k < kPixelClassCount; ++k) EXPECT_EQ(m.classRates[k], 0.0) << kPixelClasses[k].key;
  EXPECT_EQ(m.errorRate, 0.0);
}

TEST(ClassTallies, ACodeOutsideTheTableIsRefused) {
  std::vector<PixelClass> classes(4, PixelClass::Correct);
  classes[2] = PixelClass(kPixelClassCount);
  EXPECT_THROW(countClasses(classes), InputError);
}

}  // namespace
}  // namespace shadowlab::compare_metrics_classify_test
