// Metrics without any renderer: synthetic frames built in code with planted errors, so every
// count is known exactly.
#include <cmath>
#include <numeric>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "shadowlab/compare/compare.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::compare_metrics_test {
namespace {

constexpr int kW = 64, kH = 48;
constexpr int kBoundaryX = 32;      // reference: columns < 32 lit, >= 32 shadowed
constexpr int kBackgroundRows = 4;  // the bottom rows: no hit in either frame
constexpr float kPlane = 1, kCaster = 2;

struct Pair {
  Frame reference, raster;
  size_t idx(int x, int y) const { return size_t(y) * kW + x; }
  float& ref(const std::string& c, int x, int y) { return reference.get(c)[idx(x, y)]; }
  float& ras(const std::string& c, int x, int y) { return raster.get(c)[idx(x, y)]; }
};

// A plane (object 1) seen everywhere above the background rows, lit on the left half and
// shadowed on the right half. The raster agrees everywhere; its evidence says "map texel is the
// receiver itself, well in front of nothing", m = 1 pixel per texel.
Pair makeAgreeingPair(int w = kW, int h = kH) {
  Pair p;
  for (Frame* f : {&p.reference, &p.raster}) {
    f->width = w;
    f->height = h;
    f->meta["scene"] = "synthetic";
    f->meta["scene_hash"] = "00000000000000aa";
    f->meta["camera_hash"] = "00000000000000bb";
    f->meta["lights"] = {"sun"};
    f->add("hit", 0.0f);
    f->add("object_id", 0.0f);
    f->add("light.sun.vis", 0.0f);
  }
  p.reference.meta["kind"] = "reference";
  p.raster.meta["kind"] = "raster";
  p.raster.meta["light"] = "sun";
  p.reference.add("light.sun.occluder_dist", -1.0f);
  for (const char* c : {"receiver_depth", "map_depth", "occluder_id", "in_map", "m", "bias_depth", "bias_world"}) {
    p.raster.add(std::string("light.sun.") + c, 0.0f);
  }
  for (int y = 0; y < h - kBackgroundRows; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const bool lit = x < kBoundaryX;
      for (Frame* f : {&p.reference, &p.raster}) {
        f->get("hit")[i] = 1;
        f->get("object_id")[i] = kPlane;
        f->get("light.sun.vis")[i] = lit ? 1.0f : 0.0f;
      }
      p.reference.get("light.sun.occluder_dist")[i] = lit ? -1.0f : 3.0f;
      p.raster.get("light.sun.receiver_depth")[i] = 0.5f;
      p.raster.get("light.sun.map_depth")[i] = lit ? 0.5f : 0.2f;  // shadowed: a caster far in front
      p.raster.get("light.sun.occluder_id")[i] = lit ? kPlane : kCaster;
      p.raster.get("light.sun.in_map")[i] = 1;
      p.raster.get("light.sun.m")[i] = 1;
      p.raster.get("light.sun.bias_depth")[i] = 0.001f;
      p.raster.get("light.sun.bias_world")[i] = 0.01f;
    }
  }
  return p;
}

// Every value a finite number; the one null allowed is a region's mae and rmse when the region
// has no pixel (compare/METRICS.md "Soft shadows": a binary truth has no penumbra).
void expectFiniteJson(const nlohmann::json& j) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool emptyRegion = false;
    for (const VisRegionInfo& r : kVisRegions)
      emptyRegion |= (it.key() == r.maeMetric || it.key() == r.rmseMetric) && j.at(r.pixelsMetric) == 0;
    if (emptyRegion && it->is_null()) continue;
    ASSERT_TRUE(it->is_number()) << it.key() << " = " << it->dump();
    ASSERT_TRUE(std::isfinite(it->get<double>())) << it.key() << " = " << it->dump();
  }
}

struct Planted {
  uint64_t acne = 0, leak = 0, aliasing = 0, coverage = 0, other = 0, mismatch = 0;
};

// Plants exactly 37 acne, 11 leak, 5 aliasing, 3 coverage, 4 other and 9 geometry mismatches.
// Every planted pixel changes only the raster's decision (and evidence), never the reference's,
// so the only reference shadow boundary stays between columns 31 and 32.
Planted plant(Pair& p) {
  Planted n;
  // Acne: lit in the reference, shadowed by the receiver's own texel, far (>= 6 px) from the
  // boundary: 37 pixels in columns 2..25 of rows 2..3 (24 + 13).
  for (int k = 0; k < 37; ++k) {
    const int x = 2 + k % 24, y = 2 + k / 24;
    p.ras("light.sun.vis", x, y) = 0.0f;
    p.ras("light.sun.occluder_id", x, y) = kPlane;
    p.ras("light.sun.receiver_depth", x, y) = 0.5004f;
    ++n.acne;
  }
  // Leak through the map: shadowed in the reference, the caster in the map only 0.0005 in front,
  // bias 0.001: 6 pixels on row 10, columns 40..45.
  for (int x = 40; x < 46; ++x) {
    p.ras("light.sun.vis", x, 10) = 1.0f;
    p.ras("light.sun.map_depth", x, 10) = 0.4995f;
    ++n.leak;
  }
  // Leak by distance: the reference occluder 0.012 away, bias 0.01 world units (within the 1.5
  // slack), the map itself saying nothing (receiver's own texel): 5 pixels on row 12.
  for (int x = 40; x < 45; ++x) {
    p.ras("light.sun.vis", x, 12) = 1.0f;
    p.ras("light.sun.occluder_id", x, 12) = kPlane;
    p.ras("light.sun.map_depth", x, 12) = 0.5f;
    p.ref("light.sun.occluder_dist", x, 12) = 0.012f;
    ++n.leak;
  }
  // Aliasing: disagreements near the boundary (boundary pixels: columns 31 and 32) with the caster
  // in the map (so not acne) and the reference occluder too far for a leak. Distances to the
  // nearest boundary pixel: (30, 20) 1 px, (31, 21) 0, (33, 22) 1, (34, 23) 2.
  p.ras("light.sun.vis", 30, 20) = 0.0f;
  p.ras("light.sun.occluder_id", 30, 20) = kCaster;
  p.ras("light.sun.vis", 31, 21) = 0.0f;
  p.ras("light.sun.occluder_id", 31, 21) = kCaster;
  p.ras("light.sun.vis", 33, 22) = 1.0f;
  p.ras("light.sun.vis", 34, 23) = 1.0f;  // 2 px from column 32: the limit is 2 texels x m = 1
  // 5 px from the boundary but m = 3 pixels per texel: within 2 texels = 6 px.
  p.ras("light.sun.vis", 37, 24) = 1.0f;
  p.ras("light.sun.m", 37, 24) = 3.0f;
  n.aliasing = 5;
  // Other: the same kind of disagreement beyond 2 texels: 5 px with m = 1, and far away.
  p.ras("light.sun.vis", 37, 26) = 1.0f;
  p.ras("light.sun.vis", 10, 30) = 0.0f;
  p.ras("light.sun.occluder_id", 10, 30) = kCaster;
  p.ras("light.sun.vis", 50, 30) = 1.0f;
  p.ras("light.sun.vis", 35, 31) = 1.0f;  // 3 px: just beyond 2 texels
  n.other = 4;
  // Coverage: outside the map wins over acne and leak evidence (precedence).
  p.ras("light.sun.vis", 5, 35) = 0.0f;  // would be acne (own texel)
  p.ras("light.sun.in_map", 5, 35) = 0.0f;
  p.ras("light.sun.vis", 45, 35) = 1.0f;  // would be a leak
  p.ras("light.sun.map_depth", 45, 35) = 0.4995f;
  p.ras("light.sun.in_map", 45, 35) = 0.0f;
  p.ras("light.sun.vis", 20, 36) = 0.0f;
  p.ras("light.sun.occluder_id", 20, 36) = kCaster;
  p.ras("light.sun.in_map", 20, 36) = 0.0f;
  n.coverage = 3;
  // Geometry mismatch: 7 pixels where the raster sees the caster, 2 where it sees nothing.
  for (int x = 0; x < 7; ++x) p.ras("object_id", 10 + x, 40) = kCaster;
  p.ras("hit", 50, 41) = 0;
  p.ras("object_id", 50, 41) = 0;
  p.ref("hit", 51, 41) = 0;  // the reference sees nothing there, the raster the plane
  p.ref("object_id", 51, 41) = 0;
  n.mismatch = 9;
  return n;
}

TEST(CompareMetrics, PlantedErrorsGiveExactCounts) {
  Pair p = makeAgreeingPair();
  const Planted n = plant(p);
  Classification c;
  const Metrics m = compareFrames(p.reference, p.raster, {}, &c);
  const uint64_t hitPixels = uint64_t(kW) * (kH - kBackgroundRows);
  EXPECT_EQ(m.pixelsCompared, hitPixels - n.mismatch);
  EXPECT_EQ(m.count(PixelClass::GeometryMismatch), n.mismatch);
  EXPECT_EQ(m.count(PixelClass::Acne), 37u);
  EXPECT_EQ(m.count(PixelClass::Leak), 11u);
  EXPECT_EQ(m.count(PixelClass::Aliasing), 5u);
  EXPECT_EQ(m.count(PixelClass::Coverage), 3u);
  EXPECT_EQ(m.count(PixelClass::Other), 4u);
  EXPECT_EQ(m.errors, 37u + 11 + 5 + 3 + 4);
  const double compared = double(m.pixelsCompared);
  EXPECT_DOUBLE_EQ(m.rate(PixelClass::Acne), 37 / compared);
  EXPECT_DOUBLE_EQ(m.rate(PixelClass::Leak), 11 / compared);
  EXPECT_DOUBLE_EQ(m.rate(PixelClass::Aliasing), 5 / compared);
  EXPECT_DOUBLE_EQ(m.rate(PixelClass::Coverage), 3 / compared);
  EXPECT_DOUBLE_EQ(m.rate(PixelClass::Other), 4 / compared);
  EXPECT_DOUBLE_EQ(m.errorRate, 60 / compared);
  // Binary visibilities: every error is off by exactly 1.
  EXPECT_NEAR(m.mae, 60 / compared, 1e-12);
  EXPECT_NEAR(m.rmse, std::sqrt(60 / compared), 1e-12);
  // Shadowed sets: reference = right half of the compared pixels; the raster moves 37 + 3 + 2 + 1
  // (acne, coverage, aliasing, other on the lit side) in and 11 + 3 + 1 + 3 + 1 (leak, aliasing,
  // other, coverage on the shadowed side) out.
  uint64_t refShadow = 0, both = 0, rasShadow = 0;
  for (size_t i = 0; i < c.classes.size(); ++i) {
    if (c.classes[i] == PixelClass::NotCompared || c.classes[i] == PixelClass::GeometryMismatch) continue;
    const bool r = p.reference.get("light.sun.vis")[i] < 0.5f, s = p.raster.get("light.sun.vis")[i] < 0.5f;
    refShadow += r;
    rasShadow += s;
    both += r && s;
  }
  EXPECT_DOUBLE_EQ(m.shadowIou, double(both) / double(refShadow + rasShadow - both));
  EXPECT_LT(m.shadowIou, 1.0);
  // Per-pixel classes where the reason matters.
  EXPECT_EQ(c.classes[p.idx(5, 35)], PixelClass::Coverage);
  EXPECT_EQ(c.classes[p.idx(2, 2)], PixelClass::Acne);
  EXPECT_EQ(c.classes[p.idx(40, 10)], PixelClass::Leak);
  EXPECT_EQ(c.classes[p.idx(40, 12)], PixelClass::Leak);
  EXPECT_EQ(c.classes[p.idx(37, 24)], PixelClass::Aliasing);
  EXPECT_EQ(c.classes[p.idx(37, 26)], PixelClass::Other);
  EXPECT_EQ(c.classes[p.idx(35, 31)], PixelClass::Other);
  EXPECT_EQ(c.classes[p.idx(10, 40)], PixelClass::GeometryMismatch);
  EXPECT_EQ(c.classes[p.idx(0, kH - 1)], PixelClass::NotCompared);
  EXPECT_EQ(c.classes[p.idx(0, 0)], PixelClass::Correct);
  EXPECT_EQ(c.referenceLit[p.idx(0, 0)], 1);
  EXPECT_EQ(c.referenceLit[p.idx(kW - 1, 0)], 0);
  // The JSON carries the same numbers under the stable names.
  const nlohmann::json j = m.toJson();
  EXPECT_EQ(j.at("acne").get<uint64_t>(), 37u);
  EXPECT_EQ(j.at("leak").get<uint64_t>(), 11u);
  EXPECT_EQ(j.at("aliasing").get<uint64_t>(), 5u);
  EXPECT_EQ(j.at("coverage").get<uint64_t>(), 3u);
  EXPECT_EQ(j.at("geometry_mismatch").get<uint64_t>(), 9u);
  EXPECT_DOUBLE_EQ(j.at("acne_rate").get<double>(), 37 / compared);
  EXPECT_FALSE(j.contains("projector_coverage_iou"));  // no projector in these frames
  expectFiniteJson(j);
}

TEST(CompareMetrics, BoundaryTexelsWidensAliasing) {
  Pair p = makeAgreeingPair();
  plant(p);
  CompareOptions wide;
  wide.boundaryTexels = 3.0f;  // now 3 px with m = 1 (35, 31) is aliasing too
  const Metrics m = compareFrames(p.reference, p.raster, wide);
  EXPECT_EQ(m.count(PixelClass::Aliasing), 6u);
  EXPECT_EQ(m.count(PixelClass::Other), 3u);
  CompareOptions none;
  none.boundaryTexels = 0.0f;  // only disagreements on boundary pixels themselves (31, 21)
  const Metrics m0 = compareFrames(p.reference, p.raster, none);
  EXPECT_EQ(m0.count(PixelClass::Aliasing), 1u);
  EXPECT_EQ(m0.count(PixelClass::Other), 8u);
}

TEST(CompareMetrics, LeakEvidenceNearTheBoundaryIsAliasing) {
  // Within boundaryTexels texels of the true edge the map's resolution limits every texel-scaled
  // bias, so leak evidence there counts as aliasing; farther out it is a leak. Acne keeps its
  // own signature even at the edge.
  Pair p = makeAgreeingPair();
  for (int x : {33, 34, 40}) {  // 1, 2 and 8 px from the boundary column 32, m = 1
    p.ras("light.sun.vis", x, 5) = 1.0f;
    p.ras("light.sun.map_depth", x, 5) = 0.4995f;  // caster in front, within the bias
  }
  p.ras("light.sun.vis", 30, 6) = 0.0f;  // 1 px from the boundary, own texel: acne
  p.ras("light.sun.occluder_id", 30, 6) = kPlane;
  Classification c;
  const Metrics m = compareFrames(p.reference, p.raster, {}, &c);
  EXPECT_EQ(c.classes[p.idx(33, 5)], PixelClass::Aliasing);
  EXPECT_EQ(c.classes[p.idx(34, 5)], PixelClass::Aliasing);
  EXPECT_EQ(c.classes[p.idx(40, 5)], PixelClass::Leak);
  EXPECT_EQ(c.classes[p.idx(30, 6)], PixelClass::Acne);
  EXPECT_EQ(m.count(PixelClass::Aliasing), 2u);
  EXPECT_EQ(m.count(PixelClass::Leak), 1u);
  EXPECT_EQ(m.count(PixelClass::Acne), 1u);
  EXPECT_EQ(m.count(PixelClass::Other), 0u);
}

TEST(CompareMetrics, FrameComparedWithItselfHasZeroError) {
  Pair p = makeAgreeingPair();
  plant(p);
  for (const Frame* f : {&p.reference, &p.raster}) {
    const Metrics m = compareFrames(*f, *f);
    EXPECT_EQ(m.errors, 0u);
    EXPECT_EQ(m.count(PixelClass::GeometryMismatch), 0u);
    EXPECT_EQ(m.errorRate, 0.0);
    EXPECT_EQ(m.mae, 0.0);
    EXPECT_EQ(m.rmse, 0.0);
    EXPECT_EQ(m.shadowIou, 1.0);
    EXPECT_GT(m.pixelsCompared, 0u);
  }
  // The agreeing pair itself: no errors either.
  const Metrics m = compareFrames(makeAgreeingPair().reference, makeAgreeingPair().raster);
  EXPECT_EQ(m.errors, 0u);
}

TEST(CompareMetrics, EmptyFramesAreNanFree) {
  // No pixel at all, and pixels that are all background: nothing NaN in memory, and in JSON every
  // ratio is null (undefined, not "perfect"), flagged by "nothing_compared".
  for (int size : {0, 8}) {
    Pair p = makeAgreeingPair(size, size);
    for (Frame* f : {&p.reference, &p.raster}) std::fill(f->get("hit").begin(), f->get("hit").end(), 0.0f);
    Classification c;
    const Metrics m = compareFrames(p.reference, p.raster, {}, &c);
    EXPECT_EQ(m.pixelsCompared, 0u);
    EXPECT_TRUE(m.nothingCompared());
    const nlohmann::json j = m.toJson();
    EXPECT_EQ(j.at("pixels_compared"), 0);
    EXPECT_EQ(j.at("nothing_compared"), true);
    EXPECT_EQ(j.at("errors"), 0);
    EXPECT_EQ(j.at("acne"), 0);
    for (const char* k : {"error_rate", "acne_rate", "leak_rate", "bleed_rate", "aliasing_rate", "coverage_rate",
                          "other_rate", "shadow_iou", "mae", "rmse", "m_median", "m_p95", "m_max"})
      EXPECT_TRUE(j.at(k).is_null()) << k << " = " << j.at(k).dump();
    EXPECT_EQ(nothingComparedMessage(m).rfind("nothing to compare: the camera sees no surface (all " +
                                                  std::to_string(size * size) + " pixels are background",
                                              0),
              0u)
        << nothingComparedMessage(m);
  }
  // NaN and infinity in the inputs do not leak into the metrics.
  Pair p = makeAgreeingPair();
  p.ras("light.sun.vis", 3, 3) = std::nanf("");
  p.ras("light.sun.m", 4, 4) = std::nanf("");
  p.ras("light.sun.m", 5, 5) = INFINITY;
  p.ref("light.sun.vis", 6, 6) = std::nanf("");
  const Metrics m = compareFrames(p.reference, p.raster);
  expectFiniteJson(m.toJson());
  EXPECT_FALSE(m.toJson().contains("nothing_compared"));
  EXPECT_EQ(nothingComparedMessage(m), "");
}

TEST(CompareMetrics, OnlyGeometryMismatchComparesNothing) {
  // Both frames hit, but different objects everywhere: 0 compared, every pixel a mismatch.
  Pair p = makeAgreeingPair(16, 12);
  std::fill(p.raster.get("object_id").begin(), p.raster.get("object_id").end(), kCaster);
  const Metrics m = compareFrames(p.reference, p.raster);
  EXPECT_TRUE(m.nothingCompared());
  EXPECT_EQ(m.count(PixelClass::GeometryMismatch), uint64_t(16 * (12 - kBackgroundRows)));
  EXPECT_TRUE(m.toJson().at("error_rate").is_null());
  EXPECT_NE(nothingComparedMessage(m).find("no pixel shows the same surface in both frames (" +
                                           std::to_string(16 * (12 - kBackgroundRows)) + " geometry mismatch"),
            std::string::npos)
      << nothingComparedMessage(m);
}

TEST(CompareMetrics, CappedFootprintsAreCountedAndLeftOutOfTheStatistics) {
  // 1000 compared pixels: 300 at the cap (1e6, or +inf), 700 holding m = 1..700 shuffled. The
  // statistics are over the 700: median rank ceil(0.5 * 700) = 350, p95 rank ceil(0.95 * 700) = 665.
  Pair p = makeAgreeingPair(40, 25 + kBackgroundRows);
  std::vector<float> values;
  for (int i = 1; i <= 700; ++i) values.push_back(float(i));
  for (int i = 0; i < 300; ++i) values.push_back(i % 3 ? kFootprintCapPx : INFINITY);
  std::mt19937 rng(11);
  std::shuffle(values.begin(), values.end(), rng);
  for (int i = 0; i < 1000; ++i) p.raster.get("light.sun.m")[size_t(i)] = values[size_t(i)];
  Classification classification;
  const Metrics m = compareFrames(p.reference, p.raster, {}, &classification);
  EXPECT_EQ(m.pixelsCompared, 1000u);
  EXPECT_EQ(m.mCapped, 300u);
  EXPECT_EQ(m.mMedian, 350.0);
  EXPECT_EQ(m.mP95, 665.0);
  EXPECT_EQ(m.mMax, 700.0);
  const nlohmann::json j = m.toJson();
  EXPECT_EQ(j.at("m_capped"), 300);
  EXPECT_EQ(j.at("m_max"), 700.0);
  EXPECT_NE(footprintCapNote(m).find("300 of 1000 compared pixels have the texel footprint m at its cap 1000000"),
            std::string::npos)
      << footprintCapNote(m);

  // Through a group's context: the same numbers.
  p.raster.meta["evidence_group"] = "g";
  const CompareContext context(p.reference, p.raster);
  ASSERT_TRUE(context.appliesTo(p.reference, p.raster));
  const Metrics viaContext = compareFrames(context, p.reference, p.raster);
  EXPECT_EQ(viaContext.mCapped, 300u);
  EXPECT_EQ(viaContext.mMedian, 350.0);
  EXPECT_EQ(viaContext.toJson(), j);

  // Every compared pixel capped: nothing left to describe, the statistics are null.
  std::fill(p.raster.get("light.sun.m").begin(), p.raster.get("light.sun.m").end(), kFootprintCapPx);
  const Metrics all = compareFrames(p.reference, p.raster);
  EXPECT_EQ(all.mCapped, 1000u);
  const nlohmann::json ja = all.toJson();
  for (const char* k : {"m_median", "m_p95", "m_max"}) EXPECT_TRUE(ja.at(k).is_null()) << k;
  EXPECT_EQ(ja.at("error_rate"), 0.0);  // the rest is defined

  // Without an m channel nothing is capped and the statistics are 0, as before.
  Pair none = makeAgreeingPair(16, 12);
  Frame withoutM;
  withoutM.width = none.raster.width;
  withoutM.height = none.raster.height;
  withoutM.meta = none.raster.meta;
  for (size_t k = 0; k < none.raster.names.size(); ++k)
    if (none.raster.names[k] != "light.sun.m") withoutM.add(none.raster.names[k]) = none.raster.data[k];
  const Metrics noM = compareFrames(none.reference, withoutM);
  EXPECT_EQ(noM.mCapped, 0u);
  EXPECT_EQ(noM.toJson().at("m_median"), 0.0);
}

TEST(CompareMetrics, MismatchedInputsThrow) {
  Pair p = makeAgreeingPair();
  Pair small = makeAgreeingPair(32, 24);
  CompareOptions named;
  named.referenceName = "a/reference.exr";
  named.rasterName = "b/raster.exr";
  try {
    compareFrames(p.reference, small.raster, named);
    FAIL() << "different sizes were accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("a/reference.exr"), std::string::npos) << what;
    EXPECT_NE(what.find("b/raster.exr"), std::string::npos) << what;
    EXPECT_NE(what.find("64x48 vs 32x24"), std::string::npos) << what;
  }
  Pair other = makeAgreeingPair();
  other.raster.meta["scene_hash"] = "00000000000000cc";
  try {
    compareFrames(other.reference, other.raster, named);
    FAIL() << "different scene hashes were accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("scene_hash"), std::string::npos) << what;
    EXPECT_NE(what.find("b/raster.exr"), std::string::npos) << what;
  }
  CompareOptions moon;
  moon.light = "moon";
  EXPECT_THROW(compareFrames(p.reference, p.raster, moon), InputError);
  Frame noVis = p.raster;
  noVis.names.clear();
  noVis.data.clear();
  noVis.add("hit", 1.0f);
  noVis.add("object_id", 1.0f);
  EXPECT_THROW(compareFrames(p.reference, noVis), InputError);
}

TEST(CompareMetrics, FootprintQuantilesAreExactNearestRank) {
  // 40 x 25 = 1000 compared pixels holding m = 1..1000 in a shuffled order:
  // median = value at rank ceil(0.5 * 1000) = 500, p95 = ceil(0.95 * 1000) = 950, max 1000.
  Pair p = makeAgreeingPair(40, 25 + kBackgroundRows);
  std::vector<int> values(1000);
  std::iota(values.begin(), values.end(), 1);
  std::mt19937 rng(7);
  std::shuffle(values.begin(), values.end(), rng);
  for (int i = 0; i < 1000; ++i) p.raster.get("light.sun.m")[size_t(i)] = float(values[size_t(i)]) * 0.37f;
  // background pixels hold an m that must be ignored
  p.raster.get("light.sun.m")[1000] = 1e6f;
  const Metrics m = compareFrames(p.reference, p.raster);
  EXPECT_EQ(m.pixelsCompared, 1000u);
  EXPECT_EQ(m.mMedian, double(500 * 0.37f));
  EXPECT_EQ(m.mP95, double(950 * 0.37f));
  EXPECT_EQ(m.mMax, double(1000 * 0.37f));
}

TEST(CompareMetrics, ProjectorMetrics) {
  Pair p = makeAgreeingPair(16, 8 + kBackgroundRows);
  for (Frame* f : {&p.reference, &p.raster}) {
    f->meta["projectors"] = {"slide"};
    f->add("proj.slide.coverage", 0.0f);
    for (const char* c : {"R", "G", "B"}) f->add(std::string("proj.slide.") + c, 0.0f);
  }
  p.raster.add("proj.slide.reverse", 0.0f);
  // Both cover columns 0..7 of the 8 hit rows (64 px) with the same color; the raster also
  // covers columns 8..9 (16 px) behind the projector (reverse projection) and gets 8 pixels'
  // red wrong by 0.6.
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 10; ++x) {
      const size_t i = p.idx(0, 0) + size_t(y) * 16 + x;
      if (x < 8) {
        p.reference.get("proj.slide.coverage")[i] = 1;
        p.reference.get("proj.slide.R")[i] = 0.5f;
      }
      p.raster.get("proj.slide.coverage")[i] = 1;
      p.raster.get("proj.slide.R")[i] = x < 8 ? 0.5f : 0.3f;
      if (x >= 8) p.raster.get("proj.slide.reverse")[i] = 1;
    }
  }
  for (int y = 0; y < 8; ++y) p.raster.get("proj.slide.R")[size_t(y) * 16 + 3] = 1.1f;
  const Metrics m = compareFrames(p.reference, p.raster);
  ASSERT_TRUE(m.hasProjector);
  EXPECT_EQ(m.pixelsCompared, 128u);
  EXPECT_DOUBLE_EQ(m.projectorCoverageIou, 64.0 / 80.0);
  EXPECT_EQ(m.reverseProjectionPixels, 16u);
  // |dR| summed: 16 reverse pixels x 0.3 + 8 pixels x 0.6, averaged over channels and pixels.
  EXPECT_NEAR(m.projectorColorMae, (16 * 0.3 + 8 * 0.6) / 3.0 / 128.0, 1e-6);
  const nlohmann::json j = m.toJson();
  EXPECT_EQ(j.at("reverse_projection_pixels").get<uint64_t>(), 16u);
  EXPECT_TRUE(j.contains("projector_coverage_iou"));
}

// A projector-only scene (no light): the projector metrics are computed, no pixel can be a
// shadow error, and the JSON says the light was not compared. Without a projector either, there
// is nothing to compare.
TEST(CompareMetrics, ProjectorOnlyFramesCompareTheProjector) {
  auto makeFrame = [](bool withProjector) {
    Frame f;
    f.width = 16;
    f.height = 8;
    f.add("hit", 1.0f);
    f.add("object_id", 1.0f);
    if (withProjector) {
      f.meta["projectors"] = {"slide"};
      f.add("proj.slide.coverage", 0.0f);
      for (const char* c : {"R", "G", "B"}) f.add(std::string("proj.slide.") + c, 0.0f);
    }
    return f;
  };
  Frame reference = makeFrame(true), raster = makeFrame(true);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 10; ++x) {
      const size_t i = size_t(y) * 16 + size_t(x);
      if (x < 8) reference.get("proj.slide.coverage")[i] = 1;
      raster.get("proj.slide.coverage")[i] = 1;  // 16 pixels more than the reference
    }
  const Metrics m = compareFrames(reference, raster);
  EXPECT_FALSE(m.lightCompared);
  ASSERT_TRUE(m.hasProjector);
  EXPECT_EQ(m.pixelsCompared, 128u);
  EXPECT_EQ(m.errors, 0u);
  EXPECT_DOUBLE_EQ(m.projectorCoverageIou, 64.0 / 80.0);
  EXPECT_EQ(m.toJson().at("light_compared"), false);
  EXPECT_EQ(projectorSummary(m).rfind("no light (projector-only scene); projector: coverage_iou 0.8000", 0), 0u)
      << projectorSummary(m);

  try {
    compareFrames(makeFrame(false), makeFrame(false));
    ADD_FAILURE() << "frames with neither a light nor a projector were compared";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nothing to compare"), std::string::npos) << e.what();
  }
}

TEST(CompareMetrics, DeterministicForAnyThreadCount) {
  // A large random pair (many blocks, fractional visibility): the metrics and every class must
  // be bit-identical with one thread and with all of them.
  const int w = 700, h = 500;
  Pair p = makeAgreeingPair(w, h);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < size_t(w) * (h - kBackgroundRows); ++i) {
    p.raster.get("light.sun.vis")[i] = u(rng);
    p.reference.get("light.sun.vis")[i] = (i / 37) % 3 == 0 ? u(rng) : p.reference.get("light.sun.vis")[i];
    p.raster.get("light.sun.m")[i] = 0.1f + 5.0f * u(rng);
    p.raster.get("light.sun.occluder_id")[i] = u(rng) < 0.3f ? kPlane : kCaster;
  }
  Classification many, one;
  const nlohmann::json a = compareFrames(p.reference, p.raster, {}, &many).toJson();
  nlohmann::json b;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    b = compareFrames(p.reference, p.raster, {}, &one).toJson();
  }
  EXPECT_EQ(a.dump(), b.dump());
  EXPECT_TRUE(many.classes == one.classes);
  EXPECT_GT(a.at("aliasing").get<uint64_t>(), 0u);
  EXPECT_GT(a.at("other").get<uint64_t>(), 0u);
}

TEST(CompareMetrics, AliasingMatchesBruteForceBoundaryDistance) {
  // Random blobs of reference shadow and random raster disagreements without acne/leak evidence:
  // each disagreement is aliasing exactly when a boundary pixel (a compared pixel with a
  // 4-neighbour of the other reference decision) lies within boundaryTexels * m pixels.
  const int w = 150, h = 90 + kBackgroundRows;
  Pair p = makeAgreeingPair(w, h);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const int ch = h - kBackgroundRows;
  std::vector<float> centers;
  for (int k = 0; k < 6; ++k) centers.insert(centers.end(), {u(rng) * w, u(rng) * ch, 5 + 12 * u(rng)});
  auto& refVis = p.reference.get("light.sun.vis");
  auto& rasVis = p.raster.get("light.sun.vis");
  for (int y = 0; y < ch; ++y) {
    for (int x = 0; x < w; ++x) {
      bool shadow = false;
      for (size_t k = 0; k < centers.size(); k += 3)
        shadow = shadow || std::hypot(x - centers[k], y - centers[k + 1]) < centers[k + 2];
      const size_t i = size_t(y) * w + x;
      refVis[i] = rasVis[i] = shadow ? 0.0f : 1.0f;
      p.raster.get("light.sun.occluder_id")[i] = kCaster;  // never acne
      p.raster.get("light.sun.map_depth")[i] = 0.2f;       // never a leak
      p.raster.get("light.sun.m")[i] = 0.5f + 4.0f * u(rng);
      if (u(rng) < 0.05f) rasVis[i] = 1.0f - rasVis[i];
    }
  }
  Classification c;
  const Metrics m = compareFrames(p.reference, p.raster, {}, &c);
  std::vector<std::pair<int, int>> boundary;
  for (int y = 0; y < ch; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool lit = refVis[size_t(y) * w + x] >= 0.5f;
      auto differs = [&](int xx, int yy) {
        return xx >= 0 && yy >= 0 && xx < w && yy < ch && (refVis[size_t(yy) * w + xx] >= 0.5f) != lit;
      };
      if (differs(x - 1, y) || differs(x + 1, y) || differs(x, y - 1) || differs(x, y + 1)) boundary.emplace_back(x, y);
    }
  }
  ASSERT_FALSE(boundary.empty());
  uint64_t aliasing = 0, other = 0;
  for (int y = 0; y < ch; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if ((refVis[i] >= 0.5f) == (rasVis[i] >= 0.5f)) continue;
      double best = 1e30;
      for (auto [bx, by] : boundary) best = std::min(best, double(bx - x) * (bx - x) + double(by - y) * (by - y));
      const double limit = 2.0 * p.raster.get("light.sun.m")[i];
      const bool expectAliasing = best <= limit * limit;
      aliasing += expectAliasing;
      other += !expectAliasing;
      ASSERT_EQ(c.classes[i], expectAliasing ? PixelClass::Aliasing : PixelClass::Other)
          << "pixel (" << x << ", " << y << "), squared distance " << best << ", limit " << limit;
    }
  }
  EXPECT_EQ(m.count(PixelClass::Aliasing), aliasing);
  EXPECT_EQ(m.count(PixelClass::Other), other);
  EXPECT_GT(aliasing, 50u);
  EXPECT_GT(other, 50u);
}

TEST(CompareMetrics, ConcurrentCallsAgreeWithSerialOnes) {
  // A sweep may compare several pairs at once from TBB tasks (and a thread waiting inside one
  // compare may pick up another): the results must not mix.
  std::vector<Pair> pairs;
  std::vector<std::string> serial;
  for (int k = 0; k < 6; ++k) {
    pairs.push_back(makeAgreeingPair(200 + 10 * k, 120));
    Pair& p = pairs.back();
    std::mt19937 rng(100 + k);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (auto& v : p.raster.get("light.sun.vis")) v = u(rng) < 0.1f ? 1.0f - v : v;
    serial.push_back(compareFrames(p.reference, p.raster).toJson().dump());
  }
  std::vector<std::string> parallel(pairs.size());
  tbb::parallel_for(size_t(0), pairs.size(), [&](size_t k) {
    parallel[k] = compareFrames(pairs[k].reference, pairs[k].raster).toJson().dump();
  });
  EXPECT_EQ(parallel, serial);
}

TEST(CompareMetrics, ErrorsPictureHasLegendAndClassColors) {
  Pair p = makeAgreeingPair();
  plant(p);
  Classification c;
  compareFrames(p.reference, p.raster, {}, &c);
  int w = 0, h = 0;
  const std::vector<uint8_t> rgb = errorsPicture(c, &w, &h);
  EXPECT_EQ(w, kW);
  EXPECT_GT(h, kH);  // the legend is drawn below the classes
  ASSERT_EQ(rgb.size(), size_t(w) * h * 3);
  auto pixel = [&](int x, int y) {
    return std::vector<uint8_t>(&rgb[(size_t(y) * w + x) * 3], &rgb[(size_t(y) * w + x) * 3] + 3);
  };
  uint8_t expect[3];
  classColor(PixelClass::Acne, false, expect);
  EXPECT_EQ(pixel(2, 2), std::vector<uint8_t>(expect, expect + 3));
  classColor(PixelClass::Leak, false, expect);
  EXPECT_EQ(pixel(40, 10), std::vector<uint8_t>(expect, expect + 3));
  // The legend shows each class's swatch: the acne color appears below the image.
  classColor(PixelClass::Acne, false, expect);
  bool swatch = false;
  for (int y = kH; y < h && !swatch; ++y)
    for (int x = 0; x < w && !swatch; ++x) swatch = pixel(x, y) == std::vector<uint8_t>(expect, expect + 3);
  EXPECT_TRUE(swatch);
  // Text pixels are drawn in the legend (light grey on near-black).
  int textPixels = 0;
  for (int y = kH; y < h; ++y)
    for (int x = 0; x < w; ++x) textPixels += pixel(x, y) == std::vector<uint8_t>{235, 235, 235};
  EXPECT_GT(textPixels, 100);
}

// Per-cascade metrics. Three cascades by rows: rows 0..13 cascade 0, 14..27 cascade 1, 28..43
// cascade 2 (rows 44..47 are background), 64 columns each, so 896, 896 and 1024 compared pixels.
// The method declares 5 cascades: 3 and 4 hold nothing and must still be listed, NaN-free.
// Acne planted: 5 pixels in cascade 0, 7 in cascade 2 (lit pixels whose raster vis is 0 while the
// map texel holds the receiver itself). m: cascade 0 has m = x + 1 (values 1..64, 14 times each:
// nearest rank ceil(0.95 * 896) - 1 = 851, the value at sorted index 851 is 851 / 14 + 1 = 61),
// cascade 1 m = 2, cascade 2 m = 0.5.
TEST(CompareMetrics, PerCascadeErrorRateAndFootprint) {
  Pair p = makeAgreeingPair();
  p.raster.meta["method"] = {{"fit", "cascades"}, {"cascades.count", 5}};
  p.raster.add("light.sun.cascade", 0.0f);
  for (int y = 0; y < kH - kBackgroundRows; ++y)
    for (int x = 0; x < kW; ++x) {
      int c = y < 14 ? 0 : y < 28 ? 1 : 2;
      p.ras("light.sun.cascade", x, y) = float(c);
      p.ras("light.sun.m", x, y) = c == 0 ? float(x + 1) : c == 1 ? 2.0f : 0.5f;
    }
  p.ras("light.sun.cascade", 40, 3) = std::nanf("");  // read as cascade 0, never NaN out
  for (int x = 1; x <= 5; ++x) p.ras("light.sun.vis", x, 0) = 0.0f;
  for (int x = 1; x <= 7; ++x) p.ras("light.sun.vis", x, 30) = 0.0f;
  Metrics m = compareFrames(p.reference, p.raster);
  EXPECT_EQ(m.count(PixelClass::Acne), 12u);
  ASSERT_EQ(m.cascades.size(), 5u);
  const uint64_t pixels[5] = {896, 896, 1024, 0, 0}, errors[5] = {5, 0, 7, 0, 0};
  const double p95[5] = {61.0, 2.0, 0.5, 0.0, 0.0};
  for (int k = 0; k < 5; ++k) {
    const CascadeMetrics& c = m.cascades[size_t(k)];
    EXPECT_EQ(c.index, k);
    EXPECT_EQ(c.pixels, pixels[k]) << "cascade " << k;
    EXPECT_EQ(c.errors, errors[k]) << "cascade " << k;
    EXPECT_EQ(c.errorRate, pixels[k] ? double(errors[k]) / double(pixels[k]) : 0.0) << "cascade " << k;
    EXPECT_EQ(c.mP95, p95[k]) << "cascade " << k;
  }
  nlohmann::json j = m.toJson();
  ASSERT_TRUE(j["cascades"].is_array());
  ASSERT_EQ(j["cascades"].size(), 5u);
  EXPECT_EQ(j["cascades"][2]["index"], 2);
  EXPECT_EQ(j["cascades"][2]["pixels"], 1024);
  EXPECT_EQ(j["cascades"][2]["error_rate"].get<double>(), 7.0 / 1024.0);
  EXPECT_EQ(j["cascades"][0]["m_p95"].get<double>(), 61.0);
  for (const auto& c : j["cascades"]) expectFiniteJson(c);

  // The same frame from a non-cascaded fit (channel all 0): no per-cascade list, keys unchanged.
  p.raster.meta["method"] = {{"fit", "sphere"}, {"cascades.count", 4}};
  Metrics sphere = compareFrames(p.reference, p.raster);
  EXPECT_TRUE(sphere.cascades.empty());
  EXPECT_FALSE(sphere.toJson().contains("cascades"));
  // fit=sdsm is cascaded too: the same list as fit=cascades.
  p.raster.meta["method"] = {{"fit", "sdsm"}, {"cascades.count", 5}};
  Metrics sdsm = compareFrames(p.reference, p.raster);
  ASSERT_EQ(sdsm.cascades.size(), 5u);
  EXPECT_EQ(sdsm.toJson()["cascades"], j["cascades"]);
}

}  // namespace
}  // namespace shadowlab::compare_metrics_test
