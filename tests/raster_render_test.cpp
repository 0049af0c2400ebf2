// The rasterizer on scenes built in code, where the right answer is known in closed form.
// Every test runs with the Khronos validation layer (when installed) and requires zero messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "shadowlab/raster/raster.h"
#include "support/raster_device.h"
#include "shadowlab/scenes/error.h"

namespace raster_render_test {

using namespace shadowlab;

namespace {

// One Rasterizer for the whole executable: device creation and pipeline compilation are the
// slow part on lavapipe, and reusing it also exercises the scene/pipeline caches.
using RasterTest = shadowlab::testing::ValidatedRasterTest;

void addQuad(Scene& s, const std::string& name, uint32_t id, glm::vec3 corner, glm::vec3 edgeU, glm::vec3 edgeV,
             uint32_t material = 0) {
  Object o;
  o.name = name;
  o.id = id;
  o.positions = {corner, corner + edgeU, corner + edgeU + edgeV, corner + edgeV};
  o.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  o.triangles = {{0, 1, 2}, {0, 2, 3}};  // counter-clockwise seen from cross(edgeU, edgeV)
  o.triangleMaterial = {material, material};
  s.objects.push_back(o);
}

// A 10 x 10 floor at y = 0 (id 1) and a 2 x 2 roof at y = height (id 2), light straight down:
// the roof's shadow is exactly the square |x| <= 1, |z| <= 1 on the floor.
Scene roofScene(float height = 1.0f) {
  Scene s;
  s.name = "roof";
  s.materials.push_back(Material{});
  addQuad(s, "floor", 1, {-5, 0, 5}, {10, 0, 0}, {0, 0, -10});
  addQuad(s, "roof", 2, {-1, height, 1}, {2, 0, 0}, {0, 0, -2});
  s.camera.position = {0, 6, 6};
  s.camera.lookAt = {0, 0, 0};
  s.camera.width = 160;
  s.camera.height = 120;
  s.camera.vfovDeg = 50;
  Light l;
  l.name = "sun";
  l.direction = {0, -1, 0};
  s.lights.push_back(l);
  return s;
}

// Where the camera ray of pixel (i, j) meets the plane y = planeY (t < 0: misses).
glm::vec3 hitPlaneY(const Camera& c, int i, int j, float planeY, float* t) {
  glm::vec3 d = c.rayDirection(float(i) + 0.5f, float(j) + 0.5f);
  *t = (planeY - c.position.y) / d.y;
  return c.position + *t * d;
}

}  // namespace

TEST_F(RasterTest, CoverageAndIdsMatchAnalyticRayCast) {
  REQUIRE_DEVICE();
  Scene s = roofScene();
  Method m;
  Frame f = R->render(s, m);
  ASSERT_EQ(f.width, 160);
  const auto& hit = f.get("hit");
  const auto& id = f.get("object_id");
  size_t agree = 0, n = f.pixelCount();
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      float tRoof, tFloor;
      glm::vec3 pr = hitPlaneY(s.camera, i, j, 1.0f, &tRoof);
      glm::vec3 pf = hitPlaneY(s.camera, i, j, 0.0f, &tFloor);
      int expect = 0;
      if (tRoof > 0 && std::abs(pr.x) <= 1 && std::abs(pr.z) <= 1) expect = 2;
      else if (tFloor > 0 && std::abs(pf.x) <= 5 && std::abs(pf.z) <= 5) expect = 1;
      size_t k = size_t(j) * f.width + i;
      if (int(id[k]) == expect && (hit[k] > 0.5f) == (expect != 0)) ++agree;
    }
  EXPECT_GE(double(agree) / double(n), 0.999) << agree << " of " << n << " pixels agree";
  EXPECT_EQ(f.meta["kind"], "raster");
  EXPECT_EQ(f.meta["light"], "sun");
}

// Lloyd's m in closed form on the floor (y = 0) under a directional light fit to the scene's
// bounding sphere: one texel is T = 2 r / N world units across the light (r = 1.001 x half the
// box diagonal), and the map's axes are any orthonormal pair (a, b) normal to the light, so
// m = T / s_min(J) with J = d(a.p, b.p) / d(pixel), the camera ray's floor point p differentiated
// exactly (in double). s_min does not depend on which pair: the test needs no light matrix. The
// floor's foreshortening makes m vary ~3x across the image, so a wrong Jacobian cannot pass.
TEST_F(RasterTest, FootprintMIsLloydsClosedFormOnTheFloor) {
  REQUIRE_DEVICE();
  for (glm::dvec3 light : {glm::dvec3(0, -1, 0), glm::normalize(glm::dvec3(0.4, -1, 0.25))}) {
    Scene s = roofScene();
    s.lights[0].direction = glm::vec3(light);
    Method method;
    method.mapSize = 1024;
    Frame f = R->render(s, method);
    const auto& m = f.get("light.sun.m");
    const auto& id = f.get("object_id");
    const double texel = 2.0 * (0.5 * std::sqrt(201.0) * 1.001) / method.mapSize;  // box (-5,0,-5)..(5,1,5)
    const Camera& c = s.camera;
    // The unnormalized ray through image point (x, y): forward + x' right - y' up (Camera::rayDirection).
    glm::dvec3 o(c.position), forward = glm::normalize(glm::dvec3(c.lookAt) - o);
    glm::dvec3 right = glm::normalize(glm::cross(forward, glm::dvec3(c.up))), up = glm::cross(right, forward);
    double t = std::tan(glm::radians(double(c.vfovDeg)) * 0.5), aspect = double(float(c.width) / float(c.height));
    glm::dvec3 dx = (2.0 / c.width * aspect * t) * right, dy = (-2.0 / c.height * t) * up;
    glm::dvec3 a =
        glm::normalize(glm::cross(light, std::abs(light.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
    glm::dvec3 b = glm::cross(light, a);
    double lo = 1e30, hi = 0;
    int checked = 0, wrong = 0;
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        size_t k = size_t(j) * f.width + i;
        if (id[k] != 1.0f) continue;
        double x = i + 0.5, y = j + 0.5;
        glm::dvec3 d = forward + (2.0 * x / c.width - 1.0) * aspect * t * right - (2.0 * y / c.height - 1.0) * t * up;
        // p = o + s d with s = -o.y / d.y; dp/dx = s (dx - d dx.y / d.y), likewise for y.
        double sHit = -o.y / d.y;
        glm::dvec3 px = sHit * (dx - d * (dx.y / d.y)), py = sHit * (dy - d * (dy.y / d.y));
        double j00 = glm::dot(a, px), j01 = glm::dot(a, py), j10 = glm::dot(b, px), j11 = glm::dot(b, py);
        double sumSq = j00 * j00 + j01 * j01 + j10 * j10 + j11 * j11, det = std::abs(j00 * j11 - j01 * j10);
        double sMax = std::sqrt(0.5 * (sumSq + std::sqrt(std::max(sumSq * sumSq - 4.0 * det * det, 0.0))));
        double expect = texel * sMax / det;  // T / s_min, s_min = det / s_max
        ++checked;
        wrong += std::abs(double(m[k]) - expect) > 1e-3 * expect;
        lo = std::min(lo, expect), hi = std::max(hi, expect);
      }
    EXPECT_GT(checked, 5000);
    EXPECT_EQ(wrong, 0) << "light (" << light.x << ", " << light.y << ", " << light.z << ")";
    EXPECT_GT(hi / lo, 2.0) << "the floor should foreshorten: m from " << lo << " to " << hi;
  }
}

TEST_F(RasterTest, RoofShadowIsTheSquareUnderIt) {
  REQUIRE_DEVICE();
  Scene s = roofScene();
  Method m;  // defaults
  Frame f = R->render(s, m);
  const auto& vis = f.get("light.sun.vis");
  const auto& id = f.get("object_id");
  const auto& inMap = f.get("light.sun.in_map");
  int checked = 0, wrong = 0;
  // Exact away from the edge: further than 2 map texels (10*sqrt(2)*1.001 / 2048 world units).
  const float margin = 2.0f * 14.2f / 2048.0f;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      size_t k = size_t(j) * f.width + i;
      if (id[k] == 2.0f) {  // the roof is lit from straight above
        ++checked;
        wrong += vis[k] != 1.0f;
        continue;
      }
      if (id[k] != 1.0f) continue;
      float t;
      glm::vec3 p = hitPlaneY(s.camera, i, j, 0.0f, &t);
      float edge = std::max(std::abs(p.x), std::abs(p.z));
      if (std::abs(edge - 1.0f) < margin) continue;
      ++checked;
      float expect = edge < 1.0f ? 0.0f : 1.0f;
      wrong += vis[k] != expect;
      EXPECT_EQ(inMap[k], 1.0f);
    }
  EXPECT_GT(checked, 10000);
  EXPECT_EQ(wrong, 0) << "of " << checked;
}

TEST_F(RasterTest, OutputsAreBitIdenticalAcrossRuns) {
  REQUIRE_DEVICE();
  Scene s = roofScene(0.5f);
  Method m;
  m.filter = Filter::Poisson;
  m.biasNormal = 1.0f;
  m.biasReceiverPlane = true;
  Frame a = R->render(s, m);
  Frame b = R->render(s, m);
  ASSERT_EQ(a.names, b.names);
  for (size_t c = 0; c < a.names.size(); ++c)
    EXPECT_EQ(0, std::memcmp(a.data[c].data(), b.data[c].data(), a.data[c].size() * sizeof(float))) << a.names[c];
}

// The visibility buffer is kept while the scene and the camera stay the same (a sweep over
// methods) and drawn again when either changes: every frame must equal one from a fresh device,
// whatever was rendered before it.
TEST_F(RasterTest, KeptVisibilityBufferNeverOutlivesItsCamera) {
  REQUIRE_DEVICE();
  auto fresh = [](const Scene& scene, const Method& method) {  // a new device: nothing kept
    RasterDeviceOptions o;
    o.validation = true;
    Rasterizer r(o);
    Frame f = r.render(scene, method);
    EXPECT_EQ(r.validationMessages(), 0);
    return f;
  };
  auto expectSame = [](const Frame& a, const Frame& b, const std::string& what) {
    ASSERT_EQ(a.names, b.names) << what;
    for (size_t c = 0; c < a.names.size(); ++c)
      EXPECT_EQ(0, std::memcmp(a.data[c].data(), b.data[c].data(), a.data[c].size() * sizeof(float)))
          << what << ": " << a.names[c];
  };
  Scene s = roofScene(0.5f);
  Method m;
  RasterTimings first, kept;
  R->render(s, m, "", &first);
  m.biasSlope = 4.0f;  // another method: the same visibility buffer, its time carried over
  Frame sameCamera = R->render(s, m, "", &kept);
  EXPECT_EQ(first.visibilityGpuMs, kept.visibilityGpuMs);
  EXPECT_GE(kept.cameraGpuMs, kept.visibilityGpuMs);
  expectSame(sameCamera, fresh(s, m), "same camera, other method");

  Scene moved = s;  // the camera moves: the roof covers other pixels
  moved.camera.position = {1.5f, 5.0f, 6.5f};
  expectSame(R->render(moved, m), fresh(moved, m), "moved camera");
  Scene nearer = moved;  // only the near plane changes: the roof's corner is clipped away
  nearer.camera.nearPlane = 6.5f;
  Frame clipped = R->render(nearer, m);
  expectSame(clipped, fresh(nearer, m), "near plane");
  Scene other = nearer;  // other geometry under the same camera
  other.objects[1].positions[0].y += 0.25f;
  other.hash.clear();
  expectSame(R->render(other, m), fresh(other, m), "other scene");
}

// The shadow maps are kept while everything the shadow pass reads stays the same (a sweep's
// filter axis) and drawn again when anything it reads changes: every frame must equal one from a
// fresh device, and the maps must be kept exactly where nothing the pass reads changed.
TEST_F(RasterTest, KeptShadowMapsNeverOutliveWhatDrewThem) {
  REQUIRE_DEVICE();
  auto fresh = [](const Scene& scene, const Method& method) {
    RasterDeviceOptions o;
    o.validation = true;
    Rasterizer r(o);
    Frame f = r.render(scene, method);
    EXPECT_EQ(r.validationMessages(), 0);
    return std::make_pair(std::move(f), r.lookupVisibility());
  };
  auto expectSame = [](const Frame& a, const Frame& b, const std::string& what) {
    ASSERT_EQ(a.names, b.names) << what;
    for (size_t c = 0; c < a.names.size(); ++c)
      EXPECT_EQ(0, std::memcmp(a.data[c].data(), b.data[c].data(), a.data[c].size() * sizeof(float)))
          << what << ": " << a.names[c];
  };
  const Scene s = roofScene(0.5f);
  Method m;
  m.mapSize = 256;
  struct Step {
    const char* what;
    Scene scene;
    Method method;
    bool kept;
  };
  std::vector<Step> steps;
  auto step = [&](const char* what, bool kept, auto edit, Scene scene) {
    edit(m);
    steps.push_back({what, std::move(scene), m, kept});
  };
  auto same = [](Method&) {};
  step("first", false, same, s);
  step("the same method", true, same, s);
  step(
      "pcf", true, [](Method& x) { x.filter = Filter::Pcf; }, s);
  step(
      "vsm (its moments pass from the kept map)", true, [](Method& x) { x.filter = Filter::Vsm; }, s);
  step(
      "another compare bias", true, [](Method& x) { x.biasCompare = 0.01f; }, s);
  step(
      "another slope bias", false, [](Method& x) { x.biasSlope = 4.0f; }, s);
  step(
      "another constant bias", false, [](Method& x) { x.biasConstant = 64.0f; }, s);
  step(
      "cull front faces", false, [](Method& x) { x.cull = CullMode::Front; }, s);
  step(
      "map 512", false, [](Method& x) { x.mapSize = 512; }, s);
  step(
      "d32f", false, [](Method& x) { x.mapFormat = DepthFormat::D32F; }, s);
  step("a higher roof", false, same, roofScene(0.75f));
  Scene turned = roofScene(0.75f);
  turned.lights[0].direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.0f));
  step("the light turned", false, same, turned);
  step(
      "filter none again", true, [](Method& x) { x.filter = Filter::None; }, turned);
  // A pipeline's first use draws the maps in both of its runs: warm every step's pipelines first.
  for (const Step& st : steps) R->render(st.scene, st.method);
  for (const Step& st : steps) {
    RasterTimings t;
    const Frame f = R->render(st.scene, st.method, "", &t);
    EXPECT_EQ(t.shadowMapsKept, st.kept) << st.what;
    EXPECT_GE(t.shadowGpuMs, 0.0) << st.what;  // kept: the drawn maps' time carried over (a tiny map's may round to 0)
    const std::vector<uint8_t> bytes = R->lookupVisibility();
    const auto [expected, expectedBytes] = fresh(st.scene, st.method);
    expectSame(f, expected, st.what);
    EXPECT_EQ(bytes, expectedBytes) << st.what;
  }
  // Off: every render draws its maps.
  RasterDeviceOptions o;
  o.keepShadowMaps = false;
  Rasterizer r(o);
  RasterTimings t;
  for (int i = 0; i < 2; ++i) r.render(s, m, "", &t);
  EXPECT_FALSE(t.shadowMapsKept);
}

// Recycled planes are overwritten entirely: a frame rendered into another scene's planes (other
// values, other sizes) equals one rendered into fresh memory.
TEST_F(RasterTest, RecycledPlanesAreOverwrittenEverywhere) {
  REQUIRE_DEVICE();
  Scene s = roofScene(0.5f);
  Method m;
  Frame expected = R->render(s, m);
  for (int size : {0, 1, 2}) {  // smaller, equal, larger frames handed back
    Scene other = roofScene(0.25f);
    other.camera.position = {2, 3, 7};
    other.camera.width = 160 + (size - 1) * 8;
    other.camera.height = 120 + (size - 1) * 6;
    Frame old = R->render(other, m);
    for (auto& plane : old.data) std::fill(plane.begin(), plane.end(), 12345.0f);
    R->recycle(std::move(old));
    Frame again = R->render(s, m);
    ASSERT_EQ(again.names, expected.names);
    for (size_t c = 0; c < again.names.size(); ++c)
      EXPECT_EQ(0, std::memcmp(again.data[c].data(), expected.data[c].data(), expected.data[c].size() * sizeof(float)))
          << "size step " << size << ": " << again.names[c];
  }
}

TEST_F(RasterTest, MapSizeLimits) {
  REQUIRE_DEVICE();
  Scene s = roofScene();
  s.camera.width = 32;
  s.camera.height = 24;
  Method m;
  m.mapSize = 16;
  EXPECT_NO_THROW(R->render(s, m));
  m.mapSize = 0;
  EXPECT_THROW(R->render(s, m), InputError);
  m.mapSize = R->maxMapSize() + 1;
  try {
    R->render(s, m);
    ADD_FAILURE() << "map.size above the device limit was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("map.size"), std::string::npos) << e.what();
  }
  // The limit itself renders (d16 keeps the 16384^2 map's memory down).
  m.mapSize = R->maxMapSize();
  m.mapFormat = DepthFormat::D16;
  Frame f = R->render(s, m);
  EXPECT_EQ(f.meta["method"]["map.size"], R->maxMapSize());
}

TEST_F(RasterTest, UnknownLightIsAnInputError) {
  REQUIRE_DEVICE();
  try {
    R->render(roofScene(), Method{}, "moon");
    ADD_FAILURE() << "unknown light accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sun"), std::string::npos) << "should list the lights: " << e.what();
  }
}

// Every filter on the roof: exact inside and outside, fractional only in a band at the edge
// whose width the kernel sets (pcf 5: 2.5 texels, poisson radius 3: 3 texels).
TEST_F(RasterTest, FiltersBlendOnlyNearTheEdge) {
  REQUIRE_DEVICE();
  Scene s = roofScene();
  const float texel = 2.0f * 5.0f * std::sqrt(3.0f) * 1.001f / 512.0f;  // 10x1x10 box's sphere
  for (Filter filter : {Filter::None, Filter::Hw2x2, Filter::Bilinear4, Filter::Pcf, Filter::Poisson}) {
    Method m;
    m.mapSize = 512;
    m.filter = filter;
    m.filterSize = 5;
    m.filterRadius = 3.0f;
    Frame f = R->render(s, m);
    const auto& vis = f.get("light.sun.vis");
    const auto& id = f.get("object_id");
    int wrong = 0, fractional = 0;
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        size_t k = size_t(j) * f.width + i;
        if (id[k] != 1.0f) continue;
        float t;
        glm::vec3 p = hitPlaneY(s.camera, i, j, 0.0f, &t);
        float edge = std::max(std::abs(p.x), std::abs(p.z));
        fractional += vis[k] > 0.0f && vis[k] < 1.0f;
        if (std::abs(edge - 1.0f) < 5.0f * texel) continue;
        wrong += vis[k] != (edge < 1.0f ? 0.0f : 1.0f);
      }
    EXPECT_EQ(wrong, 0) << toString(filter);
    if (filter == Filter::None) EXPECT_EQ(fractional, 0);
    else EXPECT_GT(fractional, 20) << toString(filter) << " must blend at the edge";
  }
}

// Spot light straight down from (0, 4, 0) with a 60-degree cone over the floor: lit exactly
// inside the circle r = 4 tan(30 deg) (minus the roof's shadow), 0 outside.
TEST_F(RasterTest, SpotLightConeAndShadow) {
  REQUIRE_DEVICE();
  Scene s = roofScene(1.0f);
  s.lights[0].type = LightType::Spot;
  s.lights[0].position = {0, 4, 0};
  s.lights[0].direction = {0, -1, 0};
  s.lights[0].coneDeg = 60;
  s.lights[0].nearPlane = 0.1f;
  Frame f = R->render(s, Method{});
  const auto& vis = f.get("light.sun.vis");
  const auto& id = f.get("object_id");
  const float radius = 4.0f * std::tan(glm::radians(30.0f));
  int wrong = 0, checked = 0;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      size_t k = size_t(j) * f.width + i;
      if (id[k] != 1.0f) continue;
      float t;
      glm::vec3 p = hitPlaneY(s.camera, i, j, 0.0f, &t);
      float r = std::hypot(p.x, p.z);
      // The roof (|x|,|z| <= 1 at y = 1) seen from (0,4,0) shadows |x|,|z| <= 4/3 on the floor.
      float edge = std::max(std::abs(p.x), std::abs(p.z));
      if (std::abs(r - radius) < 0.03f || std::abs(edge - 4.0f / 3.0f) < 0.03f) continue;
      ++checked;
      float expect = (r < radius && edge > 4.0f / 3.0f) ? 1.0f : 0.0f;
      wrong += vis[k] != expect;
    }
  EXPECT_GT(checked, 5000);
  EXPECT_EQ(wrong, 0) << "of " << checked;
}

// A point light at (0, 0.5, 0) between the floor and the roof (height 1): the roof's underside
// is lit through the +Y face, the floor through -Y; a post beside the light in +X shadows the
// floor behind it through the +X face.
TEST_F(RasterTest, PointLightCubeFaces) {
  REQUIRE_DEVICE();
  Scene s = roofScene(1.0f);
  s.camera.position = {0, 0.6f, 4};
  s.camera.lookAt = {0, 0.3f, 0};
  s.lights[0].type = LightType::Point;
  s.lights[0].position = {0, 0.5f, 0};
  s.lights[0].nearPlane = 0.05f;
  // A vertical card at x = 1.5 facing -X: it shadows the floor at x > 1.5 * (0.5 / (0.5 - y))...
  addQuad(s, "card", 3, {1.5f, 0.0f, 0.5f}, {0, 0, -1.0f}, {0, 0.4f, 0});
  Frame f = R->render(s, Method{});
  const auto& vis = f.get("light.sun.vis");
  const auto& id = f.get("object_id");
  const auto& inMap = f.get("light.sun.in_map");
  int roofLit = 0, roofPixels = 0, floorNear = 0, floorNearLit = 0, behindCard = 0, behindCardLit = 0;
  for (int j = 0; j < f.height; ++j)
    for (int i = 0; i < f.width; ++i) {
      size_t k = size_t(j) * f.width + i;
      EXPECT_TRUE(id[k] == 0.0f || inMap[k] == 1.0f);
      float t;
      if (id[k] == 2.0f) ++roofPixels, roofLit += vis[k] == 1.0f;
      if (id[k] != 1.0f) continue;
      glm::vec3 p = hitPlaneY(s.camera, i, j, 0.0f, &t);
      // The card (x = 1.5, 0 <= y <= 0.4, -0.5 <= z <= 0.5) seen from (0, 0.5, 0) shadows the
      // floor for x >= 1.5 * 0.5 / (0.5 - 0.4) = 7.5 (beyond the floor) down to x >= 1.5 where
      // |z| <= 0.5 * x / 1.5 ... keep to the safe core: 1.7 <= x <= 4, |z| <= 0.3.
      if (p.x > 1.7f && p.x < 4.0f && std::abs(p.z) < 0.3f) ++behindCard, behindCardLit += vis[k] == 1.0f;
      if (std::hypot(p.x, p.z) < 1.2f && p.x < 1.3f) ++floorNear, floorNearLit += vis[k] == 1.0f;
    }
  EXPECT_GT(roofPixels, 100);
  EXPECT_EQ(roofLit, roofPixels) << "the roof's underside faces the light";
  EXPECT_GT(floorNear, 100);
  EXPECT_EQ(floorNearLit, floorNear);
  EXPECT_GT(behindCard, 20);
  EXPECT_EQ(behindCardLit, 0) << "the card must shadow the floor behind it (+X face)";
}

// Lloyd's m on the floor under an orthographic light straight down: one texel is
// (2 R / size) world units wide; the camera at distance d sees it at most ~ that size * focal / d
// pixels. Checked against the closed form at the image center.
TEST_F(RasterTest, TexelFootprintMatchesTheClosedForm) {
  REQUIRE_DEVICE();
  Scene s = roofScene();
  s.objects.pop_back();  // floor only
  s.camera.position = {0, 5, 0.001f};
  s.camera.lookAt = {0, 0, 0};
  s.camera.up = {0, 0, -1};
  s.camera.vfovDeg = 40;
  s.camera.width = s.camera.height = 200;
  Method m;
  m.mapSize = 256;
  Frame f = R->render(s, m);
  // Floor box 10 x 0 x 10: sphere radius 5 sqrt(2) * 1.001; texel = 2 R / 256.
  const double texel = 2.0 * 5.0 * std::sqrt(2.0) * 1.001 / 256.0;
  // Straight down from height 5: one pixel covers 2 * 5 * tan(20 deg) / 200 world units.
  const double pixel = 2.0 * 5.0 * std::tan(glm::radians(20.0)) / 200.0;
  float mCenter = f.get("light.sun.m")[size_t(100) * 200 + 100];
  EXPECT_NEAR(mCenter, texel / pixel, 0.02 * texel / pixel);
}

// The roof's square, exact for every depth format and both fits; and the cull convention:
// the roof quad faces the light (counter-clockwise seen from above), so cull=back keeps it and
// cull=front removes it (a single quad lit from its front casts nothing: the classic failure).
TEST_F(RasterTest, FormatsFitsAndCullOnTheRoof) {
  REQUIRE_DEVICE();
  Scene s = roofScene();
  s.camera.width = 120;
  s.camera.height = 90;
  auto countWrong = [&](const Method& m, bool expectShadow) {
    Frame f = R->render(s, m);
    const auto& vis = f.get("light.sun.vis");
    const auto& id = f.get("object_id");
    int wrong = 0;
    for (int j = 0; j < f.height; ++j)
      for (int i = 0; i < f.width; ++i) {
        size_t k = size_t(j) * f.width + i;
        if (id[k] != 1.0f) continue;
        float t;
        glm::vec3 p = hitPlaneY(s.camera, i, j, 0.0f, &t);
        float edge = std::max(std::abs(p.x), std::abs(p.z));
        if (std::abs(edge - 1.0f) < 0.03f) continue;
        wrong += vis[k] != ((expectShadow && edge < 1.0f) ? 0.0f : 1.0f);
      }
    return wrong;
  };
  for (DepthFormat format : {DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F})
    for (Fit fit : {Fit::Sphere, Fit::Tight}) {
      Method m;
      m.mapFormat = format;
      m.fit = fit;
      EXPECT_EQ(countWrong(m, true), 0) << toString(format) << " " << toString(fit);
    }
  Method back, front;
  back.cull = CullMode::Back;
  front.cull = CullMode::Front;
  EXPECT_EQ(countWrong(back, true), 0) << "cull=back keeps the light-facing roof";
  EXPECT_EQ(countWrong(front, false), 0) << "cull=front removes the roof from the map";
}

// Every filter and fit of kinds.h, under a directional, a spot and a point light: the validation
// layer reports nothing (the fixture checks after the test) and every output is finite. The lists
// come from the tables, so a new row is covered without a change here.
TEST_F(RasterTest, EveryFilterFitAndLightIsValidationClean) {
  REQUIRE_DEVICE();
  Scene directional = roofScene();
  directional.camera.width = 64;
  directional.camera.height = 48;
  Scene spot = directional, point = directional;
  spot.lights[0].type = LightType::Spot;
  spot.lights[0].position = {0, 4, 0};
  spot.lights[0].coneDeg = 90;
  point.lights[0].type = LightType::Point;
  point.lights[0].position = {0, 4, 0};
  // Every filter with every light type at the default fit, and every fit with the filters that
  // change which passes run or what they read (none: depth only; pcf: the kernel; vsm and msm: the
  // moments pass and blur in 2 and 4 channels; pcss and dpcf: the soft filters, refused on warped
  // maps). The other pairs compile the same passes with other constants (the product took 48 s).
  auto passesDiffer = [](Filter f) {
    return f == Filter::None || f == Filter::Pcf || f == Filter::Vsm || f == Filter::Msm || f == Filter::Pcss ||
           f == Filter::Dpcf;
  };
  for (const auto& filter : filterKinds()) {
    for (const auto& fit : fitKinds()) {
      for (const Scene* scene : {&directional, &spot, &point}) {
        if (scene != &directional && fit.kind != Fit::Sphere) continue;  // fits are directional-only
        if (fit.kind != Fit::Sphere && !passesDiffer(filter.kind)) continue;
        Method m;
        m.mapSize = 256;
        m.filter = filter.kind;
        m.fit = fit.kind;
        const std::string what =
            std::string(filter.key) + " / " + fit.key + " / " + kindKey(lightTypeKinds(), scene->lights[0].type);
        // The soft filters refuse a directional light's warped maps (raster/METHODS.md "Soft filters").
        const bool soft = filter.kind == Filter::Pcss || filter.kind == Filter::Dpcf;
        const bool warped = fit.kind == Fit::Lispsm || fit.kind == Fit::Psm || fit.kind == Fit::Tsm;
        if (soft && warped && scene == &directional) {
          EXPECT_THROW(R->render(*scene, m), InputError) << what;
          continue;
        }
        const Frame f = R->render(*scene, m);
        EXPECT_EQ(R->validationMessages(), 0) << what;
        for (size_t c = 0; c < f.names.size(); ++c)
          for (float v : f.data[c]) ASSERT_TRUE(std::isfinite(v)) << what << ": " << f.names[c];
      }
    }
  }
}

TEST_F(RasterTest, SceneWithoutLightsHasOnlyCameraChannels) {
  REQUIRE_DEVICE();
  Scene s = roofScene();
  s.lights.clear();
  Frame f = R->render(s, Method{});
  EXPECT_EQ(f.names, (std::vector<std::string>{"hit", "object_id", "prim_id"}));
  EXPECT_EQ(f.meta["light"], "");
  double hits = 0;
  for (float h : f.get("hit")) hits += h;
  EXPECT_GT(hits, 1000);
}

}  // namespace raster_render_test
