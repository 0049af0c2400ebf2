// A long sweep renders thousands of frames on one Rasterizer: its heap must not grow per frame.
// Caught here: lavapipe (Mesa 22.3) inlined the uniform-buffer values that bound a filter's loop
// (pcf's size, poisson's taps, the moments blur) and compiled a new shader variant at every
// draw, never freed: ~1 MB per evidence-on-demand frame with pcf or poisson, found as
// LeakSanitizer reports at exit and as sweeps' memory rising ~2.5 MB per row. The loop counts
// now come from a storage-buffer binding (resolve_abi.h, ParamsLoops). Every method family below
// renders repeated frames, full and on demand, the compare bias changing each frame (new
// uniform values, as in a bias sweep), and glibc's heap may not grow by more than a few frames'
// worth of planes.
#include <gtest/gtest.h>
#include <malloc.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"

namespace raster_memory_test {

using namespace shadowlab;

namespace {

using RasterMemory = shadowlab::testing::ValidatedRasterTest;

size_t heapBytes() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;  // in use: from the arenas and mmapped
}

}  // namespace

TEST_F(RasterMemory, RepeatedFramesDoNotGrowTheHeap) {
  REQUIRE_DEVICE();
  if (heapBytes() == 0) GTEST_SKIP() << "not glibc's allocator (a sanitizer build): LeakSanitizer covers this there";
  Scene s = loadScene(resolveScenePath("sphere_on_plane"));
  s.camera.width = 160;
  s.camera.height = 90;
  struct Case {
    const char* what;
    Method m;
  };
  std::vector<Case> cases;
  auto add = [&](const char* what, auto edit) {
    Method m;
    m.mapSize = 512;
    edit(m);
    cases.push_back({what, m});
  };
  add("none", [](Method&) {});
  add("hw2x2", [](Method& m) { m.filter = Filter::Hw2x2; });
  add("pcf 3", [](Method& m) { m.filter = Filter::Pcf; });
  add("pcf 5, receiver plane", [](Method& m) {
    m.filter = Filter::Pcf;
    m.filterSize = 5;
    m.biasReceiverPlane = true;
  });
  add("poisson", [](Method& m) { m.filter = Filter::Poisson; });
  add("pcf, adaptive bias", [](Method& m) {
    m.filter = Filter::Pcf;
    m.biasAdaptive = true;
  });
  add("vsm, blur 3", [](Method& m) {
    m.filter = Filter::Vsm;
    m.filterBlur = 3;
  });
  add("msm", [](Method& m) { m.filter = Filter::Msm; });
  add("cascades, blend, pcf", [](Method& m) {
    m.fit = Fit::Cascades;
    m.cascadeCount = 3;
    m.cascadeBlend = 0.3f;
    m.filter = Filter::Pcf;
  });
  // Lists every 11th pixel, and for the occluder alone the ones 5 after: each on-demand frame
  // resolves a few hundred pixels of each list in pass 5.
  const EvidenceSelector every11th = [](const uint8_t*, int width, int height, EvidenceRequest& request) {
    for (uint32_t i = 0; i < uint32_t(width * height); i += 11) request.full.push_back(i);
    for (uint32_t i = 5; i < uint32_t(width * height); i += 11) request.occluder.push_back(i);
  };
  const size_t planeBytes = 16 * sizeof(float) * size_t(s.camera.width) * size_t(s.camera.height);
  constexpr int kWarm = 3, kFrames = 12;
  for (bool onDemand : {true, false}) {
    for (Case& c : cases) {
      // The least the heap held over the first and over the last three frames: lavapipe holds a
      // 3.21 MB buffer now and then while it works (allocated and freed again, seen on a loaded
      // machine with main's binary too), which a single sample may catch.
      size_t before = SIZE_MAX, after = SIZE_MAX;
      for (int f = 0; f < kWarm + kFrames; ++f) {
        c.m.biasCompare = 1e-4f * float(f % 4);  // the uniform buffer changes every frame
        RasterTimings t;
        Frame frame = R->render(s, c.m, "", &t, nullptr, onDemand ? &every11th : nullptr);
        if (onDemand && f > 0) {
          EXPECT_TRUE(t.partialEvidence) << c.what;
        }
        R->recycle(std::move(frame));
        if (f >= kWarm && f < kWarm + 3) before = std::min(before, heapBytes());
        if (f >= kWarm + kFrames - 3) after = std::min(after, heapBytes());
      }
      const long long grown = (long long)after - (long long)before;
      // A leaked shader variant per frame grows it by ~1 MB a frame (9 MB between the two ends); a
      // frame's planes are 0.9 MB at most, the pools keep a bounded number of them, and the three
      // samples at each end may all catch lavapipe's buffer (3.21 MB).
      EXPECT_LT(grown, (long long)(2 * planeBytes + (4 << 20)))
          << c.what << (onDemand ? " on demand" : " full frames") << ": the heap grew by " << grown << " bytes over "
          << kFrames << " frames";
    }
  }
}

}  // namespace raster_memory_test
