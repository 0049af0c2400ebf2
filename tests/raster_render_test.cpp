// The rasterizer on scenes built in code, where the right answer is known in closed form.
// Every test runs with the Khronos validation layer (when installed) and requires zero messages.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"

using namespace shadowlab;

namespace {

// One Rasterizer for the whole executable: device creation and pipeline compilation are the
// slow part on lavapipe, and reusing it also exercises the scene/pipeline caches.
Rasterizer* rasterizer() {
  static std::unique_ptr<Rasterizer> r;
  static bool tried = false;
  if (!tried) {
    tried = true;
    try {
      RasterDeviceOptions o;
      o.validation = true;
      r = std::make_unique<Rasterizer>(o);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "\n*** NO VULKAN DEVICE: raster tests are SKIPPED: %s ***\n\n", e.what());
    }
  }
  return r.get();
}

#define REQUIRE_DEVICE()                                                      \
  Rasterizer* R = rasterizer();                                               \
  if (!R) GTEST_SKIP() << "no Vulkan device (lavapipe) found: test NOT run";

class RasterTest : public ::testing::Test {
 protected:
  void TearDown() override {
    if (Rasterizer* r = rasterizer()) EXPECT_EQ(r->validationMessages(), 0) << "validation messages (printed above)";
  }
};

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
