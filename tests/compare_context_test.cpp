// CompareContext (compare.h) on rendered frames: bundled scenes at 160x90 rendered with evidence on
// demand (as a sweep renders them; tests/compare_on_demand_test.cpp checks those against the full
// frames), groups of configurations sharing the light's layers (default fit, cascades with a
// blend band, a spot and a point light) under several filters (pcf, msm, poisson, hw2x2) and
// biases: the context made from the group's first frame gives the Metrics JSON of compareFrames
// exactly for every frame of the group, and a frame of another group (another map size) takes the
// full path.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/run_pipeline.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"
#include "support/tiny_scenes.h"

namespace compare_context_test {

using namespace shadowlab;

namespace {

using ContextOnFrames = shadowlab::testing::ValidatedRasterTest;

using shadowlab::testing::tinyScene;
using shadowlab::testing::withLight;

struct GroupCase {
  std::string what;
  int light = 0;                // 0 the scene's, 1 spot, 2 point
  std::vector<Method> methods;  // one map size and fit: one group
};

std::vector<GroupCase> groups() {
  auto method = [](Filter f, float slope, float compare, bool cascades) {
    Method m;
    m.mapSize = 512;
    m.filter = f;
    m.biasSlope = slope;
    m.biasCompare = compare;
    if (cascades) {
      m.fit = Fit::Cascades;
      m.cascadeCount = 3;
      m.cascadeBlend = 0.2f;
    }
    return m;
  };
  const float slope = Method().biasSlope, compare = Method().biasCompare;
  Method pcf5 = method(Filter::Pcf, slope, compare, false);
  pcf5.filterSize = 5;
  return {
      {"default fit",
       0,
       {method(Filter::None, slope, compare, false), method(Filter::None, 0.0f, 0.0f, false), pcf5,
        method(Filter::Msm, slope, compare, false), method(Filter::Poisson, 4.0f, compare, false),
        method(Filter::Hw2x2, 0.5f, compare, false)}},
      {"cascades 3, blend 0.2",
       0,
       {method(Filter::None, slope, compare, true), method(Filter::Pcf, 0.0f, 0.0f, true),
        method(Filter::Hw2x2, 2.0f, compare, true)}},
      {"spot", 1, {method(Filter::None, slope, compare, false), method(Filter::Pcf, 0.0f, 0.0f, false)}},
      {"point", 2, {method(Filter::Hw2x2, slope, compare, false), method(Filter::None, 0.0f, 0.0f, false)}},
  };
}

}  // namespace

TEST_F(ContextOnFrames, SameMetricsAsCompareFramesForEveryFrameOfAGroup) {
  REQUIRE_DEVICE();
  int checked = 0;
  uint64_t errors = 0;
  // Two scenes: a sphere's curved edge and the bunny's many triangles; the grazing scene's acne
  // is OnDemand's (compare_on_demand_test.cpp) and adds nothing the context treats differently.
  for (const std::string name : {"sphere_on_plane", "bunny"}) {
    const Scene base = tinyScene(name);
    ASSERT_FALSE(base.lights.empty()) << name;
    ASSERT_TRUE(base.projectors.empty()) << name;
    for (const GroupCase& g : groups()) {
      const Scene s = withLight(base, g.light);
      const std::string lightName = s.lights.front().name;
      const Frame reference = renderReference(s, ReferenceOptions{});
      const EvidenceSelector select = disagreementSelector(reference, lightName);
      CompareOptions options;
      options.light = lightName;
      CompareContext context;
      for (size_t k = 0; k < g.methods.size(); ++k) {
        RasterTimings t;
        Frame frame = R->render(s, g.methods[k], "", &t, nullptr, &select);
        const std::string what = name + ", " + g.what + ", method " + std::to_string(k);
        ASSERT_TRUE(frame.meta.contains("evidence_group")) << what;
        if (k == 0) context = CompareContext(reference, frame, options);  // the group's first frame
        EXPECT_EQ(context.group(), frame.meta["evidence_group"].get<std::string>()) << what;
        ASSERT_TRUE(context.appliesTo(reference, frame)) << what;
        EXPECT_TRUE(t.partialEvidence) << what;  // the first frame too (its planes pass)
        const Metrics want = compareFrames(reference, frame, options);
        EXPECT_EQ(compareFrames(context, reference, frame).toJson().dump(), want.toJson().dump()) << what;
        errors += want.errors;
        ++checked;
        R->recycle(std::move(frame));
      }
    }
  }
  EXPECT_EQ(checked, 2 * 13);
  EXPECT_GT(errors, 1000u);  // the frames had errors to classify
}

// A frame of another group (map size 1024 instead of 512: another m) is not the context's: the
// full path gives its metrics.
TEST_F(ContextOnFrames, AnotherGroupTakesTheFullPath) {
  REQUIRE_DEVICE();
  const Scene s = tinyScene("grazing");
  const std::string lightName = s.lights.front().name;
  const Frame reference = renderReference(s, ReferenceOptions{});
  const EvidenceSelector select = disagreementSelector(reference, lightName);
  Method m;
  m.mapSize = 512;
  Frame first = R->render(s, m, "", nullptr, nullptr, &select);
  const CompareContext context(reference, first);
  R->recycle(std::move(first));
  m.mapSize = 1024;
  Frame other = R->render(s, m, "", nullptr, nullptr, &select);
  ASSERT_NE(other.meta.value("evidence_group", ""), context.group());
  EXPECT_FALSE(context.appliesTo(reference, other));
  EXPECT_EQ(compareFrames(context, reference, other).toJson().dump(), compareFrames(reference, other).toJson().dump());
  R->recycle(std::move(other));
  // Rendered without a selector: no group, the full path.
  Frame full = R->render(s, m);
  EXPECT_FALSE(full.meta.contains("evidence_group"));
  EXPECT_FALSE(context.appliesTo(reference, full));
}

}  // namespace compare_context_test
