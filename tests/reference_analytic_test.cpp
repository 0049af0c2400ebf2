// The reference against closed-form answers: a sphere's shadow under a directional light, a
// square occluder's central projection under a point light, a spot light's cone, an alpha
// checker's shadow, projector coverage (frustum, reverse projection, occlusion) and the spp mean.
//
// Method, every test: the expected (object, visibility) of an image point (x, y) comes from
// intersecting Camera::rayDirection(x, y) with the analytic shapes in double precision. A pixel
// is compared only when the expected value is the same at all 25 points of the 5 x 5 grid
// {-1, -0.5, 0, 0.5, 1}^2 pixels around its center, i.e. when no analytic boundary (silhouette,
// shadow edge, texel edge, cone edge) passes within one pixel of it. Compared pixels must match
// EXACTLY (object id, and visibility 0 or 1), and each test asserts enough compared pixels on both
// sides of the boundary that it cannot pass vacuously.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include <glm/glm.hpp>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"

namespace reference_analytic_test {

namespace {

using namespace shadowlab;

struct Expected {
  uint32_t object = 0;  // 0: the ray leaves the scene
  float vis = 0.0f;
  int texel = -1;     // projector tests: the image texel expected (or -1)
  bool skip = false;  // no exact answer here (e.g. the faceted sphere's terminator): never compared
  bool operator==(const Expected& o) const {
    return object == o.object && vis == o.vis && texel == o.texel && skip == o.skip;
  }
};

using Classify = std::function<Expected(const glm::dvec3& origin, const glm::dvec3& dir)>;

struct Comparison {
  size_t compared = 0;
  size_t litCompared = 0;
  size_t shadowCompared = 0;
  size_t mismatches = 0;
  std::string firstMismatches;
};

// Classifies the half-pixel grid once, then compares every pixel whose 5 x 5 neighbourhood
// agrees. `check` may add further per-pixel assertions (returns false on a mismatch).
Comparison compareWithAnalytic(const Scene& scene, const Frame& frame, const std::string& visChannel,
                               const Classify& classify,
                               const std::function<bool(size_t, const Expected&, std::string*)>& check = {}) {
  const Camera& camera = scene.camera;
  const int gridW = 2 * camera.width + 3, gridH = 2 * camera.height + 3;
  std::vector<Expected> grid(size_t(gridW) * gridH);
  for (int gy = 0; gy < gridH; ++gy)
    for (int gx = 0; gx < gridW; ++gx) {
      const float x = gx * 0.5f - 0.5f, y = gy * 0.5f - 0.5f;
      grid[size_t(gy) * gridW + gx] = classify(glm::dvec3(camera.position), glm::dvec3(camera.rayDirection(x, y)));
    }
  const auto& objectId = frame.get("object_id");
  const auto& vis = frame.get(visChannel);
  Comparison result;
  for (int j = 0; j < camera.height; ++j)
    for (int i = 0; i < camera.width; ++i) {
      const Expected& center = grid[size_t(2 * j + 2) * gridW + (2 * i + 2)];
      bool uniform = true;
      for (int dy = 0; dy <= 4 && uniform; ++dy)
        for (int dx = 0; dx <= 4 && uniform; ++dx) uniform = grid[size_t(2 * j + dy) * gridW + (2 * i + dx)] == center;
      if (!uniform || center.skip) continue;
      const size_t pixel = size_t(j) * camera.width + i;
      ++result.compared;
      if (center.object != 0) (center.vis > 0.5f ? result.litCompared : result.shadowCompared)++;
      std::string why;
      bool ok = uint32_t(objectId[pixel]) == center.object && (center.object == 0 || vis[pixel] == center.vis);
      if (!ok) {
        why = "object " + std::to_string(objectId[pixel]) + " vis " + std::to_string(vis[pixel]) +
              "; expected object " + std::to_string(center.object) + " vis " + std::to_string(center.vis);
      } else if (check) {
        ok = check(pixel, center, &why);
      }
      if (!ok) {
        if (++result.mismatches <= 10)
          result.firstMismatches += "  pixel (" + std::to_string(i) + ", " + std::to_string(j) + "): " + why + "\n";
      }
    }
  return result;
}

// Ray-plane y = height: t > 0 or nothing.
std::optional<double> hitHorizontal(const glm::dvec3& o, const glm::dvec3& d, double height) {
  if (d.y == 0.0) return std::nullopt;
  const double t = (height - o.y) / d.y;
  if (t <= 0.0) return std::nullopt;
  return t;
}

// A quad with corners center -/+ halfU -/+ halfV, normal cross(halfU, halfV) (its triangles are
// counter-clockwise seen from that side), uv (0,0) at center - halfU - halfV, u along halfU,
// v along halfV.
Object makeQuad(const std::string& name, uint32_t id, glm::vec3 center, glm::vec3 halfU, glm::vec3 halfV,
                uint32_t material = 0) {
  Object object;
  object.name = name;
  object.id = id;
  object.positions = {center - halfU - halfV, center + halfU - halfV, center + halfU + halfV, center - halfU + halfV};
  object.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  object.triangles = {{0, 1, 2}, {0, 2, 3}};
  object.triangleMaterial = {material, material};
  return object;
}

constexpr uint32_t kGroundId = 1;
constexpr uint32_t kCasterId = 2;

// Top-down camera over a 20 x 20 ground at y = 0 (facing up, id 1): image right = +x, image
// top = -z.
Scene topDownScene(int width, int height) {
  Scene scene;
  scene.name = "in_code";
  scene.hash = "0123456789abcdef";
  scene.camera.position = {0, 10, 0};
  scene.camera.lookAt = {0, 0, 0};
  scene.camera.up = {0, 0, -1};
  scene.camera.vfovDeg = 60;
  scene.camera.width = width;
  scene.camera.height = height;
  Material material;
  material.name = "default";
  scene.materials.push_back(material);
  scene.objects.push_back(makeQuad("ground", kGroundId, {0, 0, 0}, {10, 0, 0}, {0, 0, -10}));
  return scene;
}

// ---------------------------------------------------------------------------------------------
// sphere_on_plane (bundled): sphere center c, radius r (recovered from the tessellated "ball":
// the bounding box center and the farthest vertex; the tessellation lies within 1e-3 r of the
// true sphere, far below a pixel), ground y = 0, light travelling along l, toLight = -l.
//   camera ray o + t d: sphere first if |o + t d - c| = r has a root t > 0 before the ground's
//   t = -o.y / d.y. On the sphere: the visible side is lit iff n . toLight > 0 (n the outward
//   normal; a convex body never shadows its own lit side); points within 0.05 of the terminator
//   (n . toLight in [-0.05, 0.05], about 3 degrees, covering the facets' normal error of
//   180/128 degrees) are left out. On the ground: P is shadowed iff the ray P + s toLight (s > 0)
//   meets the sphere, i.e. the distance from c to that line is < r with the nearest point at s > 0:
//   the elliptical shadow.
TEST(ReferenceAnalytic, SphereOnPlaneMatchesClosedFormAwayFromTheBoundary) {
  const Scene scene = loadScene(resolveScenePath("sphere_on_plane"));
  const Object* ball = nullptr;
  const Object* ground = nullptr;
  for (const Object& object : scene.objects) {
    if (object.name == "ball") ball = &object;
    if (object.name == "ground") ground = &object;
  }
  ASSERT_NE(ball, nullptr);
  ASSERT_NE(ground, nullptr);
  glm::dvec3 lo(1e30), hi(-1e30);
  for (const glm::vec3& p : ball->positions) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  const glm::dvec3 c = (lo + hi) * 0.5;
  double r = 0.0;
  for (const glm::vec3& p : ball->positions) r = std::max(r, glm::length(glm::dvec3(p) - c));
  const double groundY = ground->positions[0].y;
  ASSERT_EQ(scene.lights.size(), 1u);
  ASSERT_EQ(scene.lights[0].type, LightType::Directional);
  const glm::dvec3 toLight = -glm::normalize(glm::dvec3(scene.lights[0].direction));
  const float groundHalf = std::fabs(ground->positions[0].x);

  auto sphereHit = [&](const glm::dvec3& o, const glm::dvec3& d) -> std::optional<double> {
    const glm::dvec3 oc = o - c;
    const double b = glm::dot(oc, d), cc = glm::dot(oc, oc) - r * r;
    const double disc = b * b - cc;
    if (disc < 0.0) return std::nullopt;
    const double t = -b - std::sqrt(disc);
    if (t <= 0.0) return std::nullopt;
    return t;
  };
  const Classify classify = [&](const glm::dvec3& o, const glm::dvec3& d) {
    Expected e;
    auto ts = sphereHit(o, d);
    auto tg = hitHorizontal(o, d, groundY);
    if (ts && (!tg || *ts < *tg)) {
      const glm::dvec3 n = glm::normalize(o + *ts * d - c);
      const double facing = glm::dot(n, toLight);
      e.object = ball->id;
      e.vis = facing > 0.0 ? 1.0f : 0.0f;
      e.skip = std::fabs(facing) <= 0.05;
      return e;
    }
    if (!tg) return e;
    const glm::dvec3 p = o + *tg * d;
    if (std::fabs(p.x) > groundHalf || std::fabs(p.z) > groundHalf) return e;
    e.object = ground->id;
    e.vis = sphereHit(p, toLight) ? 0.0f : 1.0f;
    return e;
  };
  const Frame frame = renderReference(scene, {});
  const Comparison result = compareWithAnalytic(scene, frame, "light.sun.vis", classify);
  EXPECT_EQ(result.mismatches, 0u) << result.firstMismatches;
  // Of 518,400 pixels: most compared, and a real shadow and a lit sphere among them.
  EXPECT_GT(result.compared, size_t(0.95 * scene.camera.width * scene.camera.height));
  EXPECT_GT(result.shadowCompared, 1500u);
  EXPECT_GT(result.litCompared, 100000u);
}

// ---------------------------------------------------------------------------------------------
// Point light L above a horizontal square occluder (side 2a at height h, facing up) over the
// ground y = 0. A ground point P is shadowed iff the segment P -> L crosses y = h inside the
// square: Q = P + (L - P) * h / L.y, |Q.x - cx| < a and |Q.z - cz| < a. The shadow is the square's
// central projection from L. The nearest occluder along the shadow ray is the square, at
// distance |L - P| * h / L.y from P. The square's top sees L (L.y > h): lit.
struct SquareCaster {
  glm::dvec3 center{0.3, 1.0, -0.2};
  double half = 0.5;
  bool contains(const glm::dvec3& q) const {
    return std::fabs(q.x - center.x) < half && std::fabs(q.z - center.z) < half;
  }
};

Scene squareScene(const SquareCaster& square) {
  Scene scene = topDownScene(400, 300);
  scene.objects.push_back(
      makeQuad("square", kCasterId, glm::vec3(square.center), {float(square.half), 0, 0}, {0, 0, -float(square.half)}));
  return scene;
}

TEST(ReferenceAnalytic, PointLightShadowIsTheSquaresCentralProjection) {
  const SquareCaster square;
  Scene scene = squareScene(square);
  Light light;
  light.name = "bulb";
  light.type = LightType::Point;
  light.position = {2.5f, 3.0f, 1.5f};
  scene.lights.push_back(light);
  const glm::dvec3 lightPos(light.position);

  const Classify classify = [&](const glm::dvec3& o, const glm::dvec3& d) {
    Expected e;
    if (auto tq = hitHorizontal(o, d, square.center.y); tq && square.contains(o + *tq * d)) {
      e.object = kCasterId;
      e.vis = 1.0f;
      return e;
    }
    auto tg = hitHorizontal(o, d, 0.0);
    if (!tg) return e;
    const glm::dvec3 p = o + *tg * d;
    if (std::fabs(p.x) > 10 || std::fabs(p.z) > 10) return e;
    e.object = kGroundId;
    e.vis = square.contains(p + (lightPos - p) * (square.center.y / lightPos.y)) ? 0.0f : 1.0f;
    return e;
  };
  const Frame frame = renderReference(scene, {});
  const auto& px = frame.get("P.x");
  const auto& py = frame.get("P.y");
  const auto& pz = frame.get("P.z");
  const auto& dist = frame.get("light.bulb.occluder_dist");
  // Occluder distance from P: exact up to float rounding of the hit point.
  auto checkDistance = [&](size_t pixel, const Expected& e, std::string* why) {
    if (e.object != kGroundId) return true;
    const glm::dvec3 p(px[pixel], py[pixel], pz[pixel]);
    const double expected = e.vis > 0.5f ? -1.0 : glm::length(lightPos - p) * square.center.y / lightPos.y;
    if (std::fabs(dist[pixel] - expected) <= 1e-4) return true;
    *why = "occluder_dist " + std::to_string(dist[pixel]) + "; expected " + std::to_string(expected) + " +- 1e-4";
    return false;
  };
  const Comparison result = compareWithAnalytic(scene, frame, "light.bulb.vis", classify, checkDistance);
  EXPECT_EQ(result.mismatches, 0u) << result.firstMismatches;
  EXPECT_GT(result.compared, 110000u);  // of 120,000
  EXPECT_GT(result.shadowCompared, 1000u);
  EXPECT_GT(result.litCompared, 50000u);
}

// Spot light at S with unit axis a and full cone angle 2 theta: a ground point is lit iff
// angle(P - S, a) <= theta (a conic section: here an ellipse, the axis being tilted) and the
// segment to S misses the square (same central projection as above).
TEST(ReferenceAnalytic, SpotLightLightsExactlyItsConeMinusTheShadow) {
  const SquareCaster square;
  Scene scene = squareScene(square);
  Light light;
  light.name = "spot";
  light.type = LightType::Spot;
  light.position = {0.8f, 4.0f, 0.4f};
  light.direction = glm::normalize(glm::vec3(-0.35f, -1.0f, -0.2f));
  light.coneDeg = 70.0f;
  scene.lights.push_back(light);
  const glm::dvec3 spotPos(light.position), axis(light.direction);
  const double cosHalf = std::cos(glm::radians(35.0));

  auto inCone = [&](const glm::dvec3& p) { return glm::dot(glm::normalize(p - spotPos), axis) >= cosHalf; };
  const Classify classify = [&](const glm::dvec3& o, const glm::dvec3& d) {
    Expected e;
    if (auto tq = hitHorizontal(o, d, square.center.y); tq && square.contains(o + *tq * d)) {
      e.object = kCasterId;
      e.vis = inCone(o + *tq * d) ? 1.0f : 0.0f;
      return e;
    }
    auto tg = hitHorizontal(o, d, 0.0);
    if (!tg) return e;
    const glm::dvec3 p = o + *tg * d;
    if (std::fabs(p.x) > 10 || std::fabs(p.z) > 10) return e;
    e.object = kGroundId;
    const bool shadowed = square.contains(p + (spotPos - p) * (square.center.y / spotPos.y));
    e.vis = inCone(p) && !shadowed ? 1.0f : 0.0f;
    return e;
  };
  const Frame frame = renderReference(scene, {});
  const Comparison result = compareWithAnalytic(scene, frame, "light.spot.vis", classify);
  EXPECT_EQ(result.mismatches, 0u) << result.firstMismatches;
  EXPECT_GT(result.litCompared, 20000u);     // inside the cone and unshadowed
  EXPECT_GT(result.shadowCompared, 20000u);  // outside the cone, plus the square's shadow
  // The cone boundary must really cross the image: some ground pixels are outside it.
  size_t outsideCone = 0;
  const auto& px = frame.get("P.x");
  const auto& pz = frame.get("P.z");
  const auto& id = frame.get("object_id");
  for (size_t i = 0; i < frame.pixelCount(); ++i)
    if (id[i] == kGroundId && !inCone({px[i], 0.0, pz[i]})) ++outsideCone;
  EXPECT_GT(outsideCone, 10000u);
}

// ---------------------------------------------------------------------------------------------
// Alpha: a 4 x 4 quad at y = 1 whose 8 x 8 alpha texture is a checker (texel (x, y) opaque iff
// x + y even), cutoff 0.5, under a directional light. uv = ((x + 2) / 4, (2 - z) / 4) on the quad.
// Camera rays pass through the holes; a ground point P is shadowed iff P + s toLight meets the
// quad (s = 1 / toLight.y) at an opaque texel: a (sheared) checker shadow.
TEST(ReferenceAnalytic, CheckerAlphaCastsACheckerShadow) {
  Scene scene = topDownScene(400, 300);
  Material fence;
  fence.name = "checker";
  fence.hasAlpha = true;
  fence.alphaCutoff = 0.5f;
  fence.alphaTexture.width = 8;
  fence.alphaTexture.height = 8;
  fence.alphaTexture.channels = 1;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) fence.alphaTexture.pixels.push_back((x + y) % 2 == 0 ? 1.0f : 0.0f);
  scene.materials.push_back(fence);
  scene.objects.push_back(makeQuad("checker", kCasterId, {0, 1, 0}, {2, 0, 0}, {0, 0, -2}, 1));
  Light sun;
  sun.name = "sun";
  sun.direction = glm::normalize(glm::vec3(0.45f, -1.0f, 0.3f));
  scene.lights.push_back(sun);
  const glm::dvec3 toLight = -glm::dvec3(sun.direction);

  auto opaqueAt = [](const glm::dvec3& q) {
    if (std::fabs(q.x) >= 2 || std::fabs(q.z) >= 2) return false;
    const int tx = int(std::floor((q.x + 2) / 4 * 8)), ty = int(std::floor((2 - q.z) / 4 * 8));
    return (tx + ty) % 2 == 0;
  };
  const Classify classify = [&](const glm::dvec3& o, const glm::dvec3& d) {
    Expected e;
    if (auto tq = hitHorizontal(o, d, 1.0); tq && opaqueAt(o + *tq * d)) {
      e.object = kCasterId;
      e.vis = 1.0f;
      return e;
    }
    auto tg = hitHorizontal(o, d, 0.0);
    if (!tg) return e;
    const glm::dvec3 p = o + *tg * d;
    e.object = kGroundId;
    e.vis = opaqueAt(p + toLight * (1.0 / toLight.y)) ? 0.0f : 1.0f;
    return e;
  };
  const Frame frame = renderReference(scene, {});
  const Comparison result = compareWithAnalytic(scene, frame, "light.sun.vis", classify);
  EXPECT_EQ(result.mismatches, 0u) << result.firstMismatches;
  EXPECT_GT(result.shadowCompared, 1000u);
  EXPECT_GT(result.litCompared, 50000u);
  // Ground seen through the holes: the camera rays really passed the alpha test.
  size_t groundUnderQuad = 0;
  const auto& px = frame.get("P.x");
  const auto& pz = frame.get("P.z");
  const auto& id = frame.get("object_id");
  for (size_t i = 0; i < frame.pixelCount(); ++i)
    if (id[i] == kGroundId && std::fabs(px[i]) < 1.5f && std::fabs(pz[i]) < 1.5f) ++groundUnderQuad;
  EXPECT_GT(groundUnderQuad, 2000u);
}

// One-sided materials: a quad facing down (its back seen from the camera above and from the
// light above) is invisible to both and casts nothing; flipped to face up it is seen and casts
// its full shadow. Expected ground visibility with light direction l: shadowed iff
// P + toLight / toLight.y lies in the square (the facing-up case only).
TEST(ReferenceAnalytic, OneSidedQuadIsCulledFromTheBackForCameraAndLight) {
  for (bool facingUp : {false, true}) {
    SCOPED_TRACE(facingUp ? "facing up" : "facing down");
    Scene scene = topDownScene(320, 240);
    Material oneSided;
    oneSided.name = "one_sided";
    oneSided.twoSided = false;
    scene.materials.push_back(oneSided);
    const SquareCaster square;
    scene.objects.push_back(
        makeQuad("square", kCasterId, glm::vec3(square.center), {0.5f, 0, 0}, {0, 0, facingUp ? -0.5f : 0.5f}, 1));
    Light sun;
    sun.name = "sun";
    sun.direction = glm::normalize(glm::vec3(1.0f, -1.0f, 0.6f));
    scene.lights.push_back(sun);
    const glm::dvec3 toLight = -glm::dvec3(sun.direction);
    const Classify classify = [&](const glm::dvec3& o, const glm::dvec3& d) {
      Expected e;
      if (auto tq = hitHorizontal(o, d, square.center.y); facingUp && tq && square.contains(o + *tq * d)) {
        e.object = kCasterId;
        e.vis = 1.0f;
        return e;
      }
      auto tg = hitHorizontal(o, d, 0.0);
      if (!tg) return e;
      const glm::dvec3 p = o + *tg * d;
      e.object = kGroundId;
      e.vis = facingUp && square.contains(p + toLight * (square.center.y / toLight.y)) ? 0.0f : 1.0f;
      return e;
    };
    const Frame frame = renderReference(scene, {});
    const Comparison result = compareWithAnalytic(scene, frame, "light.sun.vis", classify);
    EXPECT_EQ(result.mismatches, 0u) << result.firstMismatches;
    if (facingUp) {
      EXPECT_GT(result.shadowCompared, 200u);
    } else {
      EXPECT_EQ(result.shadowCompared, 0u);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Projector at X = (0, 2, 0) looking down -z, up +y, vertical fov 40 deg, aspect 1.25, near 0.1,
// far 50, a 5 x 4 image whose texel (x, y) is ((x + 1) / 5, (y + 1) / 4, 0.5).
// For a point P, with s = X.z - P.z (the distance in front, along the axis) and t = tan(20 deg):
//   u = 0.5 + (P.x - X.x) / (2 s t aspect),  v = 0.5 - (P.y - X.y) / (2 s t)     (v = 0 at the top)
// coverage = 1 iff s > 0 (in front), u, v in [0, 1], s in [near, far], the visible side faces X,
// and the segment P -> X misses the blocker; the color is then texel (floor(5u), floor(4v)).
// Scene: a front wall at z = -5 facing +z (wider than the frustum: its outer part is outside),
// a blocker square at z = -2 facing +z, and a back wall at z = +5 facing -z BEHIND the
// projector, where s < 0 yet u, v land in [0, 1] after the divide (the mirrored image reverse
// projection would paint): coverage must be 0 there. The camera looks from the side at both walls.
TEST(ReferenceAnalytic, ProjectorCoverageHandlesFrustumReverseProjectionAndOcclusion) {
  Scene scene;
  scene.name = "in_code_projector";
  scene.hash = "00000000000000aa";
  scene.camera.position = {9, 4, 0};
  scene.camera.lookAt = {0, 2, 0};
  scene.camera.vfovDeg = 75;
  scene.camera.width = 480;
  scene.camera.height = 320;
  Material material;
  material.name = "default";
  scene.materials.push_back(material);
  constexpr uint32_t kFrontId = 1, kBlockerId = 2, kBackId = 3;
  scene.objects.push_back(makeQuad("front_wall", kFrontId, {0, 2, -5}, {6, 0, 0}, {0, 4, 0}));
  scene.objects.push_back(makeQuad("blocker", kBlockerId, {0.5f, 2.3f, -2}, {0.4f, 0, 0}, {0, 0.4f, 0}));
  scene.objects.push_back(makeQuad("back_wall", kBackId, {0, 2, 5}, {-6, 0, 0}, {0, 4, 0}));
  Projector projector;
  projector.name = "slide";
  projector.position = {0, 2, 0};
  projector.direction = {0, 0, -1};
  projector.up = {0, 1, 0};
  projector.fovDeg = 40;
  projector.aspect = 1.25f;
  projector.nearPlane = 0.1f;
  projector.farPlane = 50;
  projector.image.width = 5;
  projector.image.height = 4;
  projector.image.channels = 3;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x)
      projector.image.pixels.insert(projector.image.pixels.end(), {(x + 1) / 5.0f, (y + 1) / 4.0f, 0.5f});
  scene.projectors.push_back(projector);
  const glm::dvec3 X(projector.position);
  const double t = std::tan(glm::radians(20.0)), aspect = 1.25;

  struct Projection {
    double s, u, v;
  };
  auto project = [&](const glm::dvec3& p) {
    const double s = X.z - p.z;
    return Projection{s, 0.5 + (p.x - X.x) / (2 * s * t * aspect), 0.5 - (p.y - X.y) / (2 * s * t)};
  };
  auto blocked = [&](const glm::dvec3& p) {
    // The segment p -> X crosses z = -2 at q; the blocker covers |x - 0.5| < 0.4, |y - 2.3| < 0.4.
    if (!(p.z < -2.0)) return false;
    const glm::dvec3 q = p + (X - p) * ((-2.0 - p.z) / (X.z - p.z));
    return std::fabs(q.x - 0.5) < 0.4 && std::fabs(q.y - 2.3) < 0.4;
  };
  auto hitWall = [](const glm::dvec3& o, const glm::dvec3& d, double z, double halfX, double cy,
                    double halfY) -> std::optional<double> {
    if (d.z == 0.0) return std::nullopt;
    const double tt = (z - o.z) / d.z;
    if (tt <= 0.0) return std::nullopt;
    const glm::dvec3 p = o + tt * d;
    if (std::fabs(p.x) >= halfX || std::fabs(p.y - cy) >= halfY) return std::nullopt;
    return tt;
  };
  // vis = coverage; texel = y * 5 + x where covered.
  const Classify classify = [&](const glm::dvec3& o, const glm::dvec3& d) {
    Expected e;
    std::optional<double> best;
    uint32_t object = 0;
    for (auto [id, tt] :
         {std::pair{kFrontId, hitWall(o, d, -5, 6, 2, 4)}, std::pair{kBackId, hitWall(o, d, 5, 6, 2, 4)}}) {
      if (tt && (!best || *tt < *best)) best = tt, object = id;
    }
    if (d.z != 0.0) {
      const double tb = (-2.0 - o.z) / d.z;
      const glm::dvec3 q = o + tb * d;
      if (tb > 0 && std::fabs(q.x - 0.5) < 0.4 && std::fabs(q.y - 2.3) < 0.4 && (!best || tb < *best))
        best = tb, object = kBlockerId;
    }
    if (!best) return e;
    e.object = object;
    const glm::dvec3 p = o + *best * d;
    const Projection pr = project(p);
    const bool covered =
        pr.s > 0 && pr.s >= 0.1 && pr.s <= 50 && pr.u >= 0 && pr.u <= 1 && pr.v >= 0 && pr.v <= 1 && !blocked(p);
    e.vis = covered ? 1.0f : 0.0f;
    if (covered) e.texel = int(std::floor(pr.v * 4)) * 5 + int(std::floor(pr.u * 5));
    return e;
  };

  const Frame frame = renderReference(scene, {});
  const auto& px = frame.get("P.x");
  const auto& py = frame.get("P.y");
  const auto& pz = frame.get("P.z");
  const auto& u = frame.get("proj.slide.u");
  const auto& v = frame.get("proj.slide.v");
  const auto& r = frame.get("proj.slide.R");
  const auto& g = frame.get("proj.slide.G");
  const auto& b = frame.get("proj.slide.B");
  size_t reverseInRange = 0, occludedInFrustum = 0, coloredTexels = 0;
  std::vector<bool> texelSeen(20, false);
  auto check = [&](size_t pixel, const Expected& e, std::string* why) {
    if (e.object == 0) return true;
    const glm::dvec3 p(px[pixel], py[pixel], pz[pixel]);
    const Projection pr = project(p);
    // u, v are written before the frustum test, also behind the projector.
    if (std::fabs(u[pixel] - pr.u) > 1e-4 || std::fabs(v[pixel] - pr.v) > 1e-4) {
      *why = "u, v " + std::to_string(u[pixel]) + ", " + std::to_string(v[pixel]) + "; expected " +
             std::to_string(pr.u) + ", " + std::to_string(pr.v);
      return false;
    }
    if (e.object == kBackId && pr.u > 0 && pr.u < 1 && pr.v > 0 && pr.v < 1) ++reverseInRange;
    if (e.object == kFrontId && pr.u > 0 && pr.u < 1 && pr.v > 0 && pr.v < 1 && blocked(p)) ++occludedInFrustum;
    glm::vec3 expectedColor(0.0f);
    if (e.texel >= 0) {
      expectedColor = {(e.texel % 5 + 1) / 5.0f, (e.texel / 5 + 1) / 4.0f, 0.5f};
      texelSeen[e.texel] = true;
      ++coloredTexels;
    }
    if (r[pixel] != expectedColor.r || g[pixel] != expectedColor.g || b[pixel] != expectedColor.b) {
      *why = "color " + std::to_string(r[pixel]) + " " + std::to_string(g[pixel]) + " " + std::to_string(b[pixel]) +
             "; expected texel " + std::to_string(e.texel);
      return false;
    }
    return true;
  };
  const Comparison result = compareWithAnalytic(scene, frame, "proj.slide.coverage", classify, check);
  EXPECT_EQ(result.mismatches, 0u) << result.firstMismatches;
  EXPECT_GT(reverseInRange, 1000u) << "the back wall must have points that reverse projection would paint";
  EXPECT_GT(occludedInFrustum, 300u) << "the blocker must shadow part of the projected image";
  EXPECT_GT(coloredTexels, 1500u);
  EXPECT_GE(std::count(texelSeen.begin(), texelSeen.end(), true), 15) << "distinct texels seen, of 20";
}

// ---------------------------------------------------------------------------------------------
// spp: with N = 4 (a 2 x 2 grid at offsets 0.25, 0.75) visibility is the mean over the samples
// that hit the center's object, each sample exactly binary. Expected per pixel: classify the four
// sample points; the pixel is compared when no sample point lies within 0.02 pixels of a boundary
// (the samples are classified at +-0.02 px too) and the center and samples are all ground or all
// caster... except that samples on another object are simply left out of the mean.
TEST(ReferenceAnalytic, SppAveragesStratifiedSamplesOnTheCentersObject) {
  const SquareCaster square;
  Scene scene = squareScene(square);
  scene.camera.width = 160;
  scene.camera.height = 120;
  Light sun;
  sun.name = "sun";
  sun.direction = glm::normalize(glm::vec3(1.0f, -1.0f, 0.6f));
  scene.lights.push_back(sun);
  const glm::dvec3 toLight = -glm::dvec3(sun.direction);
  auto classify = [&](const glm::dvec3& o, const glm::dvec3& d) {
    Expected e;
    if (auto tq = hitHorizontal(o, d, square.center.y); tq && square.contains(o + *tq * d)) {
      e.object = kCasterId;
      e.vis = 1.0f;
      return e;
    }
    auto tg = hitHorizontal(o, d, 0.0);
    if (!tg) return e;
    const glm::dvec3 p = o + *tg * d;
    e.object = kGroundId;
    e.vis = square.contains(p + toLight * (square.center.y / toLight.y)) ? 0.0f : 1.0f;
    return e;
  };
  ReferenceOptions options;
  options.spp = 4;
  ReferenceStats stats;
  const Frame frame = renderReference(scene, options, &stats);
  EXPECT_EQ(stats.primaryRays, uint64_t(160 * 120 * 5));  // the center plus 4 samples
  const auto& vis = frame.get("light.sun.vis");
  const auto& id = frame.get("object_id");
  const glm::dvec3 o(scene.camera.position);
  size_t compared = 0, fractional = 0, mismatches = 0, mixedObjects = 0;
  std::string first;
  for (int j = 0; j < 120; ++j)
    for (int i = 0; i < 160; ++i) {
      const Expected center = classify(o, glm::dvec3(scene.camera.rayDirection(i + 0.5f, j + 0.5f)));
      double sum = 0;
      int count = 0;
      bool stable = true, mixed = false;
      for (float sy : {0.25f, 0.75f})
        for (float sx : {0.25f, 0.75f}) {
          const Expected e = classify(o, glm::dvec3(scene.camera.rayDirection(i + sx, j + sy)));
          for (float jitter : {-0.02f, 0.02f}) {
            stable = stable && classify(o, glm::dvec3(scene.camera.rayDirection(i + sx + jitter, j + sy))) == e &&
                     classify(o, glm::dvec3(scene.camera.rayDirection(i + sx, j + sy + jitter))) == e;
          }
          if (e.object != center.object) {
            mixed = true;
            continue;
          }
          sum += e.vis;
          ++count;
        }
      if (!stable || count == 0) continue;
      ++compared;
      if (mixed) ++mixedObjects;
      const float expected = float(sum / count);
      if (expected > 0.0f && expected < 1.0f) ++fractional;
      const size_t pixel = size_t(j) * 160 + i;
      if (id[pixel] != center.object || vis[pixel] != expected) {
        if (++mismatches <= 10)
          first += "  pixel (" + std::to_string(i) + ", " + std::to_string(j) + "): vis " + std::to_string(vis[pixel]) +
                   "; expected " + std::to_string(expected) + "\n";
      }
    }
  EXPECT_EQ(mismatches, 0u) << first;
  EXPECT_GT(compared, 18000u);   // of 19,200
  EXPECT_GT(fractional, 20u);    // the shadow edge yields 1/4, 1/2, 3/4
  EXPECT_GT(mixedObjects, 10u);  // pixels straddling the square's silhouette
}

TEST(ReferenceAnalytic, NonSquareSppGivesMultiplesOfOneOverN) {
  const SquareCaster square;
  Scene scene = squareScene(square);
  scene.camera.width = 96;
  scene.camera.height = 72;
  Light sun;
  sun.name = "sun";
  sun.direction = glm::normalize(glm::vec3(1.0f, -1.0f, 0.6f));
  scene.lights.push_back(sun);
  ReferenceOptions options;
  options.spp = 3;
  const Frame frame = renderReference(scene, options);
  const auto& vis = frame.get("light.sun.vis");
  size_t fractional = 0;
  for (float value : vis) {
    // Every pixel here has all samples on one object, or 1 or 2 of 3 on the center's object.
    bool ok = false;
    for (float allowed : {0.0f, 1.0f / 3, 0.5f, 2.0f / 3, 1.0f}) ok = ok || std::fabs(value - allowed) < 1e-6f;
    EXPECT_TRUE(ok) << value;
    if (value > 0.0f && value < 1.0f) ++fractional;
  }
  EXPECT_GT(fractional, 5u);
}

}  // namespace

}  // namespace reference_analytic_test
