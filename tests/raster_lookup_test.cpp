// The lookup pass (rasterizer.cpp, pass 4; lookup_gpu_ms in compare/TIMINGS.md) is resolve.frag
// specialized to the visibility alone. It must compute exactly what the resolve computes, or the
// report's time axis would time some other method: its byte per pixel must equal the resolve's
// vis converted to 8 bits (UNORM, round to nearest) with the extremes and the lit decision kept
// exact (255 only for vis 1, 0 only for vis 0, 128..255 exactly for vis >= 0.5: evidence on demand
// rebuilds vis from the bytes), for every filter, light type, cascades with a blend band, the
// receiver-plane bias and a scene with a projector (which the lookup leaves out).
// Quarter-size cameras keep the executable fast on lavapipe.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/loader.h"
#include "support/raster_device.h"

namespace raster_lookup_test {

using namespace shadowlab;

namespace {

using RasterLookup = shadowlab::testing::ValidatedRasterTest;

Scene quarterScene(const std::string& name) {
  Scene s = loadScene(resolveScenePath(name));
  s.camera.width /= 4;
  s.camera.height /= 4;
  return s;
}

// The byte the lookup writes for a visibility (resolve.frag's lookupByte): vis clamped to [0, 1]
// (NaN: 0) rounded to 8 bits, except that only 1 gives 255, only 0 gives 0, and the rounding never
// crosses the 0.5 threshold.
int expectedByte(float vis) {
  const float v = vis >= 1.0f ? 1.0f : (vis > 0.0f ? vis : 0.0f);
  if (v == 0.0f) return 0;
  if (v == 1.0f) return 255;
  const int k = int(std::lround(double(v) * 255.0));
  return v >= 0.5f ? std::clamp(k, 128, 254) : std::clamp(k, 1, 127);
}

struct Agreement {
  size_t mismatches = 0, fractional = 0, lit = 0, shadowed = 0;
  size_t outsideMap = 0;  // pixels with a hit whose lookup lies outside the map (in_map 0)
  std::string first;      // the first mismatch, for the failure message
};

// Renders and compares the lookup's bytes with the frame's vis channel, pixel by pixel.
Agreement renderAndCompare(Rasterizer& r, const Scene& s, const Method& m, RasterTimings* timings = nullptr,
                           const Camera* fitCamera = nullptr) {
  RasterTimings local;
  Frame f = r.render(s, m, "", timings ? timings : &local, fitCamera);
  const std::vector<float>& inMap = f.get("light." + s.lights.front().name + ".in_map");
  const std::vector<float>& vis = f.get("light." + s.lights.front().name + ".vis");
  const std::vector<uint8_t> bytes = r.lookupVisibility();
  Agreement a;
  EXPECT_EQ(bytes.size(), vis.size());
  for (size_t i = 0; i < vis.size() && i < bytes.size(); ++i) {
    const int expected = expectedByte(vis[i]);
    if (bytes[i] != expected) {
      if (a.mismatches++ == 0)
        a.first = "pixel " + std::to_string(i) + ": vis " + std::to_string(vis[i]) + " (byte " +
                  std::to_string(expected) + "), lookup " + std::to_string(int(bytes[i]));
    }
    a.lit += expected == 255;
    a.shadowed += f.get("hit")[i] > 0.5f && expected == 0;
    a.fractional += expected != 0 && expected != 255;
    a.outsideMap += f.get("hit")[i] > 0.5f && inMap[i] < 0.5f;
  }
  return a;
}

}  // namespace

// Every filter kind on a scene with a projector and on the sphere: the same bytes, and the frames
// hold both shadow and light (a lookup that wrote a constant could not pass).
TEST_F(RasterLookup, EqualsTheResolveVisibilityForEveryFilter) {
  REQUIRE_DEVICE();
  for (const char* sceneName : {"sphere_on_plane", "projector"}) {
    const Scene s = quarterScene(sceneName);
    for (const auto& kind : filterKinds()) {
      // The projector scene (its resolve has projectors, the lookup none) with a few filters only.
      const bool few = kind.kind == Filter::None || kind.kind == Filter::Pcf || kind.kind == Filter::Msm;
      if (std::string(sceneName) == "projector" && !few) continue;
      Method m;
      m.mapSize = 512;
      m.filter = kind.kind;
      RasterTimings t;
      const Agreement a = renderAndCompare(*R, s, m, &t);
      const std::string what = std::string(sceneName) + ", filter=" + toString(kind.kind);
      EXPECT_EQ(a.mismatches, 0u) << what << "; first: " << a.first;
      EXPECT_GT(a.lit, 100u) << what;
      EXPECT_GT(a.shadowed, 100u) << what;
      if (kind.kind != Filter::None) {
        EXPECT_GT(a.fractional, 0u) << what << ": the filter's soft edge is there";
      }
      EXPECT_GT(t.lookupGpuMs, 0.0) << what;
      // The moments pass is timed as its part of the shadow pass, for the filterable maps only.
      if (isMomentFilter(kind.kind)) {
        EXPECT_GT(t.momentsGpuMs, 0.0) << what;
        EXPECT_LT(t.momentsGpuMs, t.shadowGpuMs) << what;
      } else {
        EXPECT_EQ(t.momentsGpuMs, 0.0) << what;
      }
    }
  }
}

// The other code paths of the shared lookup: cascades with a blend band, the receiver plane and
// normal offset, points outside the map (a tight fit to a camera that sees less), spot and point
// lights (cube faces), a float depth map.
TEST_F(RasterLookup, EqualsTheResolveVisibilityOnEveryLookupPath) {
  REQUIRE_DEVICE();
  const Scene sphere = quarterScene("sphere_on_plane");
  {
    Method m;
    m.mapSize = 512;
    m.fit = Fit::Cascades;
    m.cascadeCount = 3;
    m.cascadeBlend = 0.3f;
    m.filter = Filter::Pcf;
    m.filterSize = 3;
    const Agreement a = renderAndCompare(*R, sphere, m);
    EXPECT_EQ(a.mismatches, 0u) << "cascades with a blend band; first: " << a.first;
    EXPECT_GT(a.fractional, 0u);
  }
  {
    Method m;
    m.mapSize = 512;
    m.biasReceiverPlane = true;
    m.biasNormal = 1.5f;
    m.filter = Filter::Bilinear4;
    m.mapFormat = DepthFormat::D32F;
    const Agreement a = renderAndCompare(*R, sphere, m);
    EXPECT_EQ(a.mismatches, 0u) << "receiver plane, normal offset, D32F; first: " << a.first;
  }
  {
    // A tight fit to a camera that sees less than the evaluation camera: the points it does not
    // see lie outside the map (lit by policy), the rest inside; the lookup must tell them apart
    // as the resolve does.
    Camera ahead = sphere.camera;
    ahead.position += 0.6f * (sphere.camera.lookAt - sphere.camera.position);
    for (Filter filter : {Filter::None, Filter::Pcf}) {
      Method m;
      m.mapSize = 512;
      m.fit = Fit::Tight;
      m.filter = filter;
      const Agreement a = renderAndCompare(*R, sphere, m, nullptr, &ahead);
      EXPECT_EQ(a.mismatches, 0u) << "fit=tight to a camera ahead, " << toString(filter) << "; first: " << a.first;
      EXPECT_GT(a.outsideMap, 100u) << toString(filter);
      EXPECT_GT(a.shadowed, 100u) << toString(filter);
    }
  }
  for (LightType type : {LightType::Spot, LightType::Point}) {
    Scene s = sphere;
    Light& l = s.lights.front();
    l.type = type;
    l.position = glm::vec3(0.5f, 4.0f, 0.5f);
    l.direction = glm::vec3(0, -1, 0);
    l.coneDeg = 100.0f;
    for (Filter filter : {Filter::None, Filter::Hw2x2, Filter::Vsm}) {
      Method m;
      m.mapSize = 512;
      m.filter = filter;
      const Agreement a = renderAndCompare(*R, s, m);
      EXPECT_EQ(a.mismatches, 0u) << (type == LightType::Spot ? "spot" : "point") << ", " << toString(filter)
                                  << "; first: " << a.first;
      EXPECT_GT(a.shadowed, 100u);
    }
  }
}

// The lookup of a method without a normal (no normal offset, receiver plane or adaptive bias)
// reads its visible point from the group's surface image (with one map layer, the point's map
// coordinates): the planes pass draws it at a group's first frame on demand (and again where it
// was not kept), a full frame's resolve writes it, and the rasterizer keeps the surfaces of 4
// groups (rasterizer.cpp, surfaceFor) beside the planes of 4 groups on demand. Six groups that
// differ in what the surface holds (the camera's rays; the light, which decides which sides it
// reaches; a spot's cone; its direction), in a sequence where full frames evict surfaces whose
// planes stay kept, so that a frame on demand finds its planes but not its surface; where a full
// frame with a normal offset rewrites a surface that a frame on demand then reads (it must hold
// the point's own coordinates, not the offset point's); and where frames that read no surface
// (normal offset) come between: every frame's bytes must equal those of a full frame on a
// rasterizer of its own. A surface read under the wrong group puts another camera's points, or
// another light's facing, into the lookup.
TEST_F(RasterLookup, TheSurfaceFollowsItsGroup) {
  REQUIRE_DEVICE();
  const Scene base = quarterScene("sphere_on_plane");
  std::vector<Scene> groups(6, base);
  groups[1].camera.position += glm::vec3(1.5f, 0.5f, 0.0f);
  groups[2].camera.position += glm::vec3(-1.0f, 1.0f, 1.0f);
  // The light from below the plane: the camera sees the plane's side facing away from it.
  groups[3].lights.front().direction = -groups[3].lights.front().direction;
  Light& spot = groups[4].lights.front();
  spot.type = LightType::Spot;
  spot.position = glm::vec3(0.5f, 4.0f, 0.5f);
  spot.direction = glm::vec3(0, -1, 0);
  spot.coneDeg = 40.0f;  // the plane's far parts outside the cone
  groups[5].lights.front().direction = glm::normalize(glm::vec3(0.6f, -1.0f, 0.3f));
  Rasterizer expectedR;
  const EvidenceSelector askNothing = [](const uint8_t*, int, int, EvidenceRequest&) {};
  struct Step {
    size_t group;
    bool onDemand;
    Filter filter;
    bool normalOffset;
  };
  const Filter none = Filter::None, hw = Filter::Hw2x2;
  // Groups 0, 3, 4 and 5 share the camera, so their planes on demand are kept together (4 groups).
  const std::vector<Step> steps = {
      {0, true, none, false}, {3, true, hw, false},    {4, true, none, false},
      {5, true, none, false}, {1, false, none, false},  // another camera, full: evicts group 0's surface
      {0, true, none, false},                           // its planes kept, its surface not: drawn again
      {4, true, none, false},                           // planes and surface kept
      {0, false, none, true},                           // full, normal offset: writes group 0's surface
      {0, true, none, false},                           // planes kept: reads what the full frame wrote
      {3, true, none, true},  {2, false, hw, false},   {5, true, hw, false},
      {2, true, none, false}, {0, false, none, true},  {1, true, hw, false},
      {4, true, none, false}, {3, false, none, false}, {0, true, none, false}};
  int surfaceFrames = 0;
  for (size_t k = 0; k < steps.size(); ++k) {
    const Step& st = steps[k];
    const Scene& s = groups[st.group];
    Method m;
    m.mapSize = 512;
    m.filter = st.filter;
    if (st.normalOffset) m.biasNormal = 1.0f;
    Frame got = R->render(s, m, "", nullptr, nullptr, st.onDemand ? &askNothing : nullptr);
    const std::vector<uint8_t> bytes = R->lookupVisibility();
    R->recycle(std::move(got));
    const Frame expected = expectedR.render(s, m);
    const std::vector<float>& vis = expected.get("light." + s.lights.front().name + ".vis");
    const std::string what = "step " + std::to_string(k) + ", group " + std::to_string(st.group) +
                             (st.onDemand ? ", on demand" : ", full") + (st.normalOffset ? ", normal offset" : "");
    ASSERT_EQ(bytes.size(), vis.size()) << what;
    size_t mismatches = 0, lit = 0, shadowed = 0;
    for (size_t i = 0; i < vis.size(); ++i) {
      mismatches += bytes[i] != expectedByte(vis[i]);
      lit += bytes[i] == 255;
      shadowed += expected.get("hit")[i] > 0.5f && bytes[i] == 0;
    }
    EXPECT_EQ(mismatches, 0u) << what;
    if (st.group != 3) {
      EXPECT_GT(lit, 100u) << what;
    }
    EXPECT_GT(shadowed, 100u) << what;
    surfaceFrames += !st.normalOffset;
  }
  EXPECT_GE(surfaceFrames, 15);
}

}  // namespace raster_lookup_test
