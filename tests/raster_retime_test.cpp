// Rasterizer::retimeMethod (raster.h; compare/TIMINGS.md, "Timed repetitions"): the last frame's
// method passes (shadow pass with every layer, moments pass, lookup pass) run again, each timed on
// its own. They must redraw from the same inputs, so the lookup's bytes stay those of the frame,
// every run has a shadow and a lookup time, the moments only for filterable maps, and the
// validation layer reports nothing (the fixture fails on any message): the passes the runs leave
// out (visibility buffer, planes, resolve) must not leave an image in a wrong layout.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"

namespace raster_retime_test {

using namespace shadowlab;

namespace {

using RasterRetime = shadowlab::testing::ValidatedRasterTest;

Scene quarterScene(const std::string& name) {
  Scene s = loadScene(resolveScenePath(name));
  s.camera.width /= 4;
  s.camera.height /= 4;
  return s;
}

}  // namespace

TEST_F(RasterRetime, RunsTheMethodPassesAgainWithoutChangingTheFrame) {
  REQUIRE_DEVICE();
  EXPECT_TRUE(R->retimeMethod(3).empty()) << "before the first render there is nothing to time";
  const Scene s = quarterScene("sphere_on_plane");
  for (Filter filter : {Filter::None, Filter::Pcf, Filter::Vsm}) {
    Method m;
    m.mapSize = 512;
    m.filter = filter;
    const std::string what = std::string("filter=") + toString(filter);
    // Twice: the second frame keeps the first's maps, the runs draw them anyway.
    for (int frame = 0; frame < 2; ++frame) {
      RasterTimings t;
      R->render(s, m, "", &t);
      if (frame == 1) {
        EXPECT_TRUE(t.shadowMapsKept) << what;
      }
      const std::vector<uint8_t> before = R->lookupVisibility();
      const std::vector<Rasterizer::MethodTiming> runs = R->retimeMethod(3);
      ASSERT_EQ(runs.size(), 3u) << what;
      for (const auto& run : runs) {
        EXPECT_GT(run.shadowGpuMs, 0.0) << what;
        EXPECT_GT(run.lookupGpuMs, 0.0) << what;
        EXPECT_DOUBLE_EQ(run.methodGpuMs(), run.shadowGpuMs + run.lookupGpuMs) << what;
        if (isMomentFilter(filter)) {
          EXPECT_GT(run.momentsGpuMs, 0.0) << what;
          EXPECT_LT(run.momentsGpuMs, run.shadowGpuMs) << what;
        } else {
          EXPECT_EQ(run.momentsGpuMs, 0.0) << what;
        }
      }
      EXPECT_EQ(R->lookupVisibility(), before) << what << ": the runs redraw the same visibility";
    }
  }
}

// A frame after the runs is the frame it would have been: same visibility, same lookup bytes.
TEST_F(RasterRetime, TheNextFrameIsUnchanged) {
  REQUIRE_DEVICE();
  const Scene s = quarterScene("sphere_on_plane");
  Method a, b;
  a.mapSize = b.mapSize = 512;
  b.filter = Filter::Pcf;
  R->render(s, b, "");
  const std::vector<uint8_t> plain = R->lookupVisibility();
  const Frame reference = R->render(s, b, "");
  R->render(s, a, "");
  R->retimeMethod(3);
  const Frame after = R->render(s, b, "");
  EXPECT_EQ(R->lookupVisibility(), plain);
  const std::string vis = "light." + s.lights.front().name + ".vis";
  EXPECT_EQ(after.get(vis), reference.get(vis));
}

}  // namespace raster_retime_test
