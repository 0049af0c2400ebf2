// Loader, geometry and the camera/projector conventions both renderers rely on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <experimental/simd>
#include <filesystem>
#include <map>
#include <random>
#include <set>

#include <glm/gtc/matrix_transform.hpp>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace scenes_loader_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

constexpr double kPi = 3.14159265358979323846;

fs::path tempDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("shadowlab_scenes_loader_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string errorOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError thrown)";
}

const char* kMiniScene = R"({
  "camera": {"position": [0, 2, 5], "look_at": [0, 0, 0], "vfov_deg": 45, "width": 64, "height": 48},
  "objects": [%OBJECTS%],
  "lights": [%LIGHTS%] %EXTRA%
})";

std::string mini(const std::string& objects,
                 const std::string& lights = R"({"type": "directional", "elevation_deg": 45})",
                 const std::string& extra = "") {
  std::string s = kMiniScene;
  s.replace(s.find("%OBJECTS%"), 9, objects);
  s.replace(s.find("%LIGHTS%"), 8, lights);
  s.replace(s.find("%EXTRA%"), 7, extra);
  return s;
}

Scene loadText(const std::string& text, const std::string& name = "mini.json", const std::string& dirName = "mini") {
  fs::path dir = tempDir(dirName);
  writeFileAtomic((dir / name).string(), text);
  return loadScene((dir / name).string());
}

const Object& objectNamed(const Scene& s, const std::string& name) {
  for (const auto& o : s.objects)
    if (o.name == name) return o;
  throw std::runtime_error("no object " + name);
}

glm::vec3 toLight(double elevationDeg, double azimuthDeg) {
  double e = elevationDeg * kPi / 180, a = azimuthDeg * kPi / 180;
  return glm::vec3(std::cos(e) * std::sin(a), std::sin(e), std::cos(e) * std::cos(a));
}

}  // namespace

TEST(ScenesLoader, EveryBundledSceneLoads) {
  auto names = bundledSceneNames();
  EXPECT_EQ(names,
            (std::vector<std::string>{"sphere_on_plane", "grazing", "contact", "thin_wall", "alpha_fence", "projector",
                                      "bunny", "long_view", "stacked_occluders", "gltf_cards", "soft_post"}));
  for (const auto& n : names) {
    SCOPED_TRACE(n);
    Scene s = loadScene(resolveScenePath(n));
    EXPECT_EQ(s.name, n);
    EXPECT_EQ(s.path, bundledScenesDir() + "/" + n + ".json");
    ASSERT_EQ(s.hash.size(), 16u);
    EXPECT_EQ(s.hash.find_first_not_of("0123456789abcdef"), std::string::npos);
    EXPECT_GT(s.triangleCount(), 0u);
    EXPECT_FALSE(s.lights.empty());
    // gltf_cards is lit by its glTF file's KHR_lights_punctual spot only, soft_post by a sphere light.
    if (n == "gltf_cards") EXPECT_TRUE(s.findLight("spot") != nullptr && s.lights.size() == 1);
    else if (n == "soft_post") EXPECT_TRUE(s.findLight("bulb") != nullptr && s.lights.front().sized());
    else EXPECT_TRUE(s.findLight("sun") != nullptr) << "every other bundled scene has a light named sun";
    EXPECT_FALSE(s.failurePointer.empty());
    EXPECT_GE(s.failureValues.size(), 3u);
    EXPECT_LE(s.camera.width * s.camera.height, 1280 * 720) << "keep default resolutions moderate";
    std::set<uint32_t> ids;
    for (const auto& o : s.objects) {
      EXPECT_GE(o.id, 1u);
      EXPECT_TRUE(ids.insert(o.id).second) << "duplicate id " << o.id;
      EXPECT_EQ(o.triangleMaterial.size(), o.triangles.size());
      EXPECT_TRUE(o.uvs.empty() || o.uvs.size() == o.positions.size());
      for (const auto& t : o.triangles)
        EXPECT_TRUE(t.x < o.positions.size() && t.y < o.positions.size() && t.z < o.positions.size());
      for (uint32_t m : o.triangleMaterial) EXPECT_LT(m, s.materials.size());
      for (const auto& p : o.positions) ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    }
    // Loading is deterministic: same content, same hash.
    EXPECT_EQ(loadScene(resolveScenePath(n)).hash, s.hash);
  }
}

TEST(ScenesLoader, ResolveScenePath) {
  EXPECT_EQ(resolveScenePath("grazing"), bundledScenesDir() + "/grazing.json");
  EXPECT_EQ(resolveScenePath("my/scene.json"), "my/scene.json");
  EXPECT_EQ(resolveScenePath("scene.json"), "scene.json");
  EXPECT_EQ(resolveScenePath("./grazing"), "./grazing");
}

TEST(ScenesLoader, ObjectIdsAreStable) {
  Scene s = loadScene(resolveScenePath("sphere_on_plane"));
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[0].name, "ground");
  EXPECT_EQ(s.objects[0].id, 1u);
  EXPECT_EQ(s.objects[1].name, "ball");
  EXPECT_EQ(s.objects[1].id, 2u);
  Scene lv = loadScene(resolveScenePath("long_view"));
  for (size_t i = 0; i < lv.objects.size(); ++i) EXPECT_EQ(lv.objects[i].id, i + 1);
  // Explicit ids stay; the others keep their 1-based index.
  Scene m = loadText(mini(R"({"type": "plane", "size": [4, 4]}, {"type": "box", "id": 40, "size": [1, 1, 1]},
                          {"type": "sphere", "radius": 0.5, "segments": 8, "rings": 4})"));
  EXPECT_EQ(m.objects[0].id, 1u);
  EXPECT_EQ(m.objects[1].id, 40u);
  EXPECT_EQ(m.objects[2].id, 3u);
  EXPECT_EQ(m.objects[0].name, "plane1");
  EXPECT_EQ(m.objects[1].name, "box2");
}

// The sphere is compared against the exact sphere by the analytic test: every point of every
// triangle must lie within 1e-4 r of it, the mesh must be closed (each edge in exactly two
// triangles, so no ray slips through) and face outward.
TEST(ScenesLoader, SphereTessellationIsWithinToleranceClosedAndOutward) {
  Scene s = loadScene(resolveScenePath("sphere_on_plane"));
  const Object& ball = objectNamed(s, "ball");
  const glm::dvec3 center(0, 1, 0);
  const double radius = 1.0;
  EXPECT_EQ(ball.triangles.size(), 2u * 256u * 127u);
  double maxErr = 0;
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (const auto& t : ball.triangles) {
    glm::dvec3 a = ball.positions[t.x], b = ball.positions[t.y], c = ball.positions[t.z];
    for (int i = 0; i <= 6; ++i)
      for (int j = 0; i + j <= 6; ++j) {
        glm::dvec3 p = a + (i / 6.0) * (b - a) + (j / 6.0) * (c - a);
        maxErr = std::max(maxErr, std::fabs(glm::length(p - center) - radius));
      }
    glm::dvec3 n = glm::cross(b - a, c - a);
    EXPECT_GT(glm::dot(n, (a + b + c) / 3.0 - center), 0.0) << "inward-facing triangle";
    uint32_t v[3] = {t.x, t.y, t.z};
    for (int k = 0; k < 3; ++k) edges[{std::min(v[k], v[(k + 1) % 3]), std::max(v[k], v[(k + 1) % 3])}]++;
  }
  EXPECT_LE(maxErr, 1e-4 * radius);
  EXPECT_GT(maxErr, 1e-6) << "a tessellated sphere cannot be exact: the check is not sampling";
  for (const auto& [e, count] : edges) ASSERT_EQ(count, 2) << "open edge " << e.first << "-" << e.second;
}

TEST(ScenesLoader, CylinderAndBoxAreClosedAndOutward) {
  Scene m = loadText(mini(R"({"type": "cylinder", "radius": 0.5, "height": 2, "segments": 16},
                          {"type": "box", "size": [1, 2, 3], "transform": {"translate": [5, 0, 0]}})"));
  for (const auto& o : m.objects) {
    glm::dvec3 c = o.name == "box2" ? glm::dvec3(5, 0, 0) : glm::dvec3(0);
    for (const auto& t : o.triangles) {
      glm::dvec3 a = o.positions[t.x], b = o.positions[t.y], d = o.positions[t.z];
      EXPECT_GT(glm::dot(glm::cross(b - a, d - a), (a + b + d) / 3.0 - c), 0.0) << o.name;
    }
  }
  EXPECT_EQ(m.objects[0].triangles.size(), 16u * 4u);
  EXPECT_EQ(m.objects[1].triangles.size(), 12u);
  glm::vec3 lo = m.boundsMin(), hi = m.boundsMax();
  EXPECT_FLOAT_EQ(lo.y, -1.0f);
  EXPECT_FLOAT_EQ(hi.x, 5.5f);
  EXPECT_FLOAT_EQ(hi.z, 1.5f);
}

TEST(ScenesLoader, TransformAppliesXThenYThenZ) {
  // The north pole (0, r, 0) of a sphere: X by 90 takes it to +z, then Y by 90 to +x.
  // (Y first would leave it on the y axis and X would then take it to +z.)
  Scene m = loadText(mini(R"({"type": "sphere", "radius": 2, "segments": 4, "rings": 2,
                          "transform": {"rotate_deg": [90, 90, 0], "translate": [1, 2, 3], "scale": [1, 1, 1]}})"));
  glm::vec3 pole = m.objects[0].positions[0] - glm::vec3(1, 2, 3);
  EXPECT_GT(pole.x, 1.99f);
  EXPECT_NEAR(pole.y, 0.0f, 1e-5f);
  EXPECT_NEAR(pole.z, 0.0f, 1e-5f);
}

TEST(ScenesCamera, RaysThroughPixelCenters) {
  Scene s = loadScene(resolveScenePath("sphere_on_plane"));
  const Camera& cam = s.camera;
  const float w = float(cam.width), h = float(cam.height);
  glm::vec3 forward = glm::normalize(cam.lookAt - cam.position);
  glm::vec3 right = glm::normalize(glm::cross(forward, cam.up));
  glm::vec3 up = glm::cross(right, forward);
  glm::vec3 center = cam.rayDirection(w / 2, h / 2);
  EXPECT_NEAR(glm::length(center - forward), 0.0f, 1e-6f);
  // Top edge middle: half the vertical fov above the axis; row 0 is the top.
  glm::vec3 top = cam.rayDirection(w / 2, 0);
  EXPECT_NEAR(std::acos(glm::dot(top, forward)), cam.vfovDeg * kPi / 360, 1e-5);
  EXPECT_GT(glm::dot(top, up), 0.0f);
  // Left edge middle: atan(aspect * tan(vfov/2)) to the left.
  glm::vec3 left = cam.rayDirection(0, h / 2);
  EXPECT_NEAR(std::acos(glm::dot(left, forward)), std::atan(w / h * std::tan(cam.vfovDeg * kPi / 360)), 1e-5);
  EXPECT_LT(glm::dot(left, right), 0.0f);
  // Pixel (0, 0)'s center is half a pixel inside the corner, symmetric with the last pixel.
  glm::vec3 first = cam.rayDirection(0.5f, 0.5f), last = cam.rayDirection(w - 0.5f, h - 0.5f);
  EXPECT_NEAR(glm::dot(first, forward), glm::dot(last, forward), 1e-6f);
  EXPECT_NEAR(glm::length(first), 1.0f, 1e-6f);
}

// CameraRays::perspectiveDirection over a packet of 8 lanes (as the reference traces a 4 x 2 block)
// gives each lane direction(x, y)'s bits, and direction keeps the formula it always had (glm's
// normalize of f + (ndc.x aspect t) s - (ndc.y t) u): on every pixel of three bundled cameras and of
// an odd-sized wide one, at the pixel centers and at off-center sample positions.
TEST(ScenesCamera, PacketDirectionsHaveDirectionsBits) {
  namespace stdx = std::experimental;
  using DoubleN = stdx::fixed_size_simd<double, 8>;
  std::vector<Camera> cameras;
  for (const char* name : {"sphere_on_plane", "long_view", "projector"}) {
    Camera c = loadScene(resolveScenePath(name)).camera;
    c.width = 160;
    c.height = 90;
    cameras.push_back(c);
  }
  Camera wide;
  wide.position = {0.3f, 2.1f, -4.7f};
  wide.lookAt = {-1.0f, 0.2f, 0.5f};
  wide.vfovDeg = 83.0f;
  wide.width = 37;
  wide.height = 23;
  cameras.push_back(wide);
  for (const Camera& cam : cameras) {
    const CameraRays rays(cam);
    const glm::dvec3 f = glm::normalize(glm::dvec3(cam.lookAt) - glm::dvec3(cam.position));
    const glm::dvec3 r = glm::normalize(glm::cross(f, glm::dvec3(cam.up)));
    const glm::dvec3 u = glm::cross(r, f);
    const double t = std::tan(double(glm::radians(cam.vfovDeg)) * 0.5), aspect = double(float(cam.width) / float(cam.height));
    size_t packetDiffers = 0, formulaDiffers = 0, checked = 0;
    for (const glm::vec2 shift : {glm::vec2(0.5f), glm::vec2(0.125f, 0.875f), glm::vec2(0.9375f, 0.0625f)}) {
      for (int y0 = 0; y0 < cam.height; y0 += 2)
        for (int x0 = 0; x0 < cam.width; x0 += 4) {
          float x[8], y[8];
          for (int lane = 0; lane < 8; ++lane) {
            x[lane] = float(x0 + lane % 4) + shift.x;
            y[lane] = float(y0 + lane / 4) + shift.y;
          }
          const DoubleN xs([&](auto lane) { return double(x[lane]); });
          const DoubleN ys([&](auto lane) { return double(y[lane]); });
          DoubleN out[3];
          rays.perspectiveDirection(xs, ys, out);
          for (int lane = 0; lane < 8; ++lane) {
            // In double, before the rounding to float (which would hide a changed last bit).
            double scalar[3];
            rays.perspectiveDirection(double(x[lane]), double(y[lane]), scalar);
            const double packet[3] = {out[0][lane], out[1][lane], out[2][lane]};
            const double ndcX = 2.0 * x[lane] / cam.width - 1.0, ndcY = 2.0 * y[lane] / cam.height - 1.0;
            const glm::dvec3 formula = glm::normalize(f + (ndcX * aspect * t) * r - (ndcY * t) * u);
            packetDiffers += std::memcmp(scalar, packet, sizeof scalar) != 0;
            formulaDiffers += std::memcmp(scalar, &formula[0], sizeof scalar) != 0;
            // And direction is that result as float.
            const glm::vec3 one = rays.direction(x[lane], y[lane]), rounded = glm::vec3(formula);
            formulaDiffers += std::memcmp(&one, &rounded, sizeof one) != 0;
            ++checked;
          }
        }
    }
    EXPECT_EQ(packetDiffers, 0u) << cam.width << "x" << cam.height;
    EXPECT_EQ(formulaDiffers, 0u) << cam.width << "x" << cam.height;
    EXPECT_GE(checked, size_t(3 * cam.width * cam.height));
  }
}

// The rasterizer's matrices must put a point seen through image position (x, y) at exactly
// that position after the Vulkan viewport transform px = (ndc.x + 1) / 2 * W, py = (ndc.y + 1) / 2 * H.
TEST(ScenesCamera, ClipFromViewMatchesRayDirection) {
  for (const char* name : {"sphere_on_plane", "long_view", "projector"}) {
    Scene s = loadScene(resolveScenePath(name));
    const Camera& cam = s.camera;
    // The check runs in double on the float matrices and the float ray: what is measured is
    // the agreement of the formulas, not float rounding in the test itself. What remains is
    // the float view matrix's translation (|eye| * 6e-8 world units), which shifts points
    // close to the eye most (measured: 4e-4 px at 0.7 units, 1.3e-4 px at 2.5 units from the
    // long_view eye); 4 units is closer than any visible surface in these scenes.
    glm::dmat4 clipFromWorld = glm::dmat4(cam.clipFromView()) * glm::dmat4(cam.viewFromWorld());
    double worst = 0;
    for (int j = 0; j < cam.height; j += 37)
      for (int i = 0; i < cam.width; i += 53)
        for (double t : {4.0, 10.0, 60.0}) {
          float x = i + 0.5f, y = j + 0.5f;
          glm::dvec3 p = glm::dvec3(cam.position) + t * glm::dvec3(cam.rayDirection(x, y));
          glm::dvec4 clip = clipFromWorld * glm::dvec4(p, 1.0);
          double px = (clip.x / clip.w + 1.0) * 0.5 * cam.width, py = (clip.y / clip.w + 1.0) * 0.5 * cam.height;
          worst = std::max({worst, std::fabs(px - x), std::fabs(py - y)});
          double depth = clip.z / clip.w;
          EXPECT_TRUE(depth > 0.0 && depth < 1.0) << depth;
        }
    EXPECT_LE(worst, 1e-4) << name;
  }
  // Depth 0 at the near plane, 1 at the far plane, along the axis.
  Camera cam;
  cam.nearPlane = 0.5f;
  cam.farPlane = 80.0f;
  glm::vec3 f = glm::normalize(cam.lookAt - cam.position);
  glm::mat4 m = cam.clipFromView() * cam.viewFromWorld();
  glm::vec4 n = m * glm::vec4(cam.position + 0.5f * f, 1), fa = m * glm::vec4(cam.position + 80.0f * f, 1);
  EXPECT_NEAR(n.z / n.w, 0.0f, 1e-6f);
  EXPECT_NEAR(fa.z / fa.w, 1.0f, 1e-5f);
}

// An orthographic camera in JSON ("projection": "orthographic", "ortho_height"): parallel rays
// along the view direction, each from its point of the view plane, which the rasterizer's matrix
// puts at that very image position (any depth), with depth 0 at near and 1 at far; the errors
// of its keys name the JSON pointer; a perspective camera's hash is unchanged by the new fields.
TEST(ScenesCamera, OrthographicCameraFromJson) {
  const std::string ortho = R"({
    "camera": {"projection": "orthographic", "ortho_height": 4, "position": [1, 2, 5], "look_at": [0, 0, 0],
               "width": 64, "height": 48, "near": 0.5, "far": 40},
    "objects": [{"type": "plane", "size": [10, 10]}], "lights": [{"type": "directional", "elevation_deg": 45}]})";
  const Scene s = loadText(ortho, "ortho.json", "ortho");
  const Camera& cam = s.camera;
  ASSERT_EQ(cam.projection, Projection::Orthographic);
  EXPECT_EQ(cam.orthoHeight, 4.0f);
  const glm::vec3 forward = glm::normalize(cam.lookAt - cam.position);
  const glm::vec3 right = glm::normalize(glm::cross(forward, cam.up));
  const glm::vec3 up = glm::cross(right, forward);
  EXPECT_NEAR(glm::length(cam.rayDirection(3.5f, 40.5f) - forward), 0.0f, 1e-6f);
  // The view's top edge lies 2 above the axis, its left edge 2 * 64 / 48 to the left.
  EXPECT_NEAR(glm::length(cam.rayOrigin(32, 0) - (cam.position + 2.0f * up)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::length(cam.rayOrigin(0, 24) - (cam.position - (2.0f * 64 / 48) * right)), 0.0f, 1e-5f);
  glm::dmat4 clipFromWorld = glm::dmat4(cam.clipFromView()) * glm::dmat4(cam.viewFromWorld());
  double worst = 0;
  for (int j = 0; j < cam.height; j += 7)
    for (int i = 0; i < cam.width; i += 9)
      for (double t : {0.5, 3.0, 39.0}) {
        const float x = i + 0.5f, y = j + 0.5f;
        const glm::dvec3 p = glm::dvec3(cam.rayOrigin(x, y)) + t * glm::dvec3(cam.rayDirection(x, y));
        const glm::dvec4 clip = clipFromWorld * glm::dvec4(p, 1.0);
        EXPECT_NEAR(clip.w, 1.0, 1e-9);
        worst = std::max({worst, std::fabs((clip.x + 1.0) * 0.5 * cam.width - x),
                          std::fabs((clip.y + 1.0) * 0.5 * cam.height - y)});
        EXPECT_NEAR(clip.z, (t - 0.5) / 39.5, 1e-5) << t;
      }
  EXPECT_LE(worst, 1e-4);
  EXPECT_NE(cam.hash(), [&] {
    Camera c = cam;
    c.orthoHeight = 5;
    return c.hash();
  }());
  // A perspective camera's hash: the bundled scene's, as before the orthographic fields existed.
  Camera persp;
  persp.orthoHeight = 7;  // not read by a perspective camera
  EXPECT_EQ(persp.hash(), Camera().hash());

  auto bad = [&](const std::string& from, const std::string& to) {
    std::string text = ortho;
    text.replace(text.find(from), from.size(), to);
    return errorOf([&] { loadText(text, "bad.json", "ortho_bad"); });
  };
  EXPECT_NE(bad(R"("ortho_height": 4, )", "").find("bad.json: /camera: error: missing key \"ortho_height\""),
            std::string::npos);
  EXPECT_NE(bad(R"("ortho_height": 4)", R"("ortho_height": 4, "vfov_deg": 45)")
                .find("bad.json: /camera/vfov_deg: error: given with \"projection\": \"orthographic\""),
            std::string::npos);
  EXPECT_NE(bad(R"("ortho_height": 4)", R"("ortho_height": -1)").find("bad.json: /camera/ortho_height: error:"),
            std::string::npos);
  EXPECT_NE(bad(R"("orthographic")", R"("fisheye")")
                .find("bad.json: /camera/projection: error: got \"fisheye\"; expected perspective or orthographic"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              std::string text = mini(R"({"type": "plane"})");
              text.replace(text.find(R"("vfov_deg": 45)"), 14, R"("vfov_deg": 45, "ortho_height": 3)");
              loadText(text, "bad2.json", "ortho_bad2");
            }).find("bad2.json: /camera/ortho_height: error: given with a perspective camera"),
            std::string::npos);
}

TEST(ScenesProjector, TexFromWorldAxisEdgesAndReverse) {
  Scene s = loadScene(resolveScenePath("projector"));
  ASSERT_EQ(s.projectors.size(), 1u);
  const Projector& p = s.projectors[0];
  EXPECT_EQ(p.name, "slide");
  EXPECT_FLOAT_EQ(p.aspect, 32.0f / 24.0f);  // from the image when not given
  glm::mat4 m = p.texFromWorld();
  auto project = [&](glm::vec3 world) { return m * glm::vec4(world, 1.0f); };
  glm::vec4 axis = project(p.position + 7.0f * p.direction);
  EXPECT_NEAR(axis.x / axis.w, 0.5f, 1e-6f);
  EXPECT_NEAR(axis.y / axis.w, 0.5f, 1e-6f);
  EXPECT_NEAR(axis.w, 7.0f, 1e-5f);  // w: distance in front along the axis
  glm::vec3 right = glm::normalize(glm::cross(p.direction, p.up));
  glm::vec3 up = glm::cross(right, p.direction);
  float t = std::tan(glm::radians(p.fovDeg) / 2);
  glm::vec4 top = project(p.position + 5.0f * (p.direction + t * up));
  EXPECT_NEAR(top.y / top.w, 0.0f, 1e-5f) << "v = 0 at the image's top row";
  EXPECT_NEAR(top.x / top.w, 0.5f, 1e-5f);
  glm::vec4 rightEdge = project(p.position + 5.0f * (p.direction + t * p.aspect * right));
  EXPECT_NEAR(rightEdge.x / rightEdge.w, 1.0f, 1e-5f);
  glm::vec4 nearPt = project(p.position + p.nearPlane * p.direction),
            farPt = project(p.position + p.farPlane * p.direction);
  EXPECT_NEAR(nearPt.z / nearPt.w, 0.0f, 1e-5f);
  EXPECT_NEAR(farPt.z / farPt.w, 1.0f, 1e-5f);
  // Behind the projector: w < 0, yet the divided coordinates land inside [0,1]^2 (mirrored).
  glm::vec4 behind = project(p.position - 4.0f * p.direction + 4.0f * 0.3f * t * up);
  EXPECT_LT(behind.w, 0.0f);
  float u = behind.x / behind.w, v = behind.y / behind.w;
  EXPECT_TRUE(u >= 0 && u <= 1 && v >= 0 && v <= 1) << u << " " << v;
  EXPECT_GT(v, 0.5f) << "a point above the axis behind the projector maps below the center: mirrored";
  // The image: 32x24 RGB, red top-left, yellow bottom-right (v = 0 is the top row).
  ASSERT_EQ(p.image.width, 32);
  ASSERT_EQ(p.image.height, 24);
  ASSERT_EQ(p.image.channels, 3);
  EXPECT_NEAR(p.image.at(2, 5, 0), 1.0f, 1e-6f);
  EXPECT_NEAR(p.image.at(2, 5, 1), 25 / 255.0f, 1e-6f);
  EXPECT_NEAR(p.image.at(30, 23, 1), 230 / 255.0f, 1e-6f);
}

TEST(ScenesAlpha, FenceTextureAndNearestRepeatLookup) {
  Scene s = loadScene(resolveScenePath("alpha_fence"));
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[0].name, "default");
  const Material& fence = s.materials[1];
  EXPECT_EQ(fence.name, "fence");
  ASSERT_TRUE(fence.hasAlpha);
  EXPECT_EQ(fence.alphaTexture.width, 64);
  EXPECT_EQ(fence.alphaTexture.channels, 1);
  EXPECT_FLOAT_EQ(fence.alphaCutoff, 0.5f);
  const Object& quad = objectNamed(s, "fence");
  for (uint32_t m : quad.triangleMaterial) EXPECT_EQ(m, 1u);
  float maxU = 0;
  for (const auto& uv : quad.uvs) maxU = std::max(maxU, uv.x);
  EXPECT_FLOAT_EQ(maxU, 6.0f);  // uv_scale repeats the texture 6 times across
  const Image& a = fence.alphaTexture;
  // Texel centers: post columns 0..11, picket 32..43, rails rows 10..17 and 46..53.
  auto at = [&](float tx, float ty) { return sampleAlphaNearest(a, {tx / 64.0f, ty / 64.0f}); };
  EXPECT_EQ(at(5.5f, 30.5f), 1.0f);
  EXPECT_EQ(at(20.5f, 30.5f), 0.0f);
  EXPECT_EQ(at(20.5f, 12.5f), 1.0f);
  EXPECT_EQ(at(63.5f, 30.5f), 0.0f);
  EXPECT_EQ(at(11.99f, 30.5f), 1.0f);
  EXPECT_EQ(at(12.01f, 30.5f), 0.0f);
  // Repeat addressing: whole-number shifts in u and v change nothing, negatives wrap.
  EXPECT_EQ(sampleAlphaNearest(a, {5.5f / 64 + 3.0f, 30.5f / 64 - 2.0f}), 1.0f);
  EXPECT_EQ(sampleAlphaNearest(a, {-0.0001f, 30.5f / 64}), 0.0f);     // column 63
  EXPECT_EQ(sampleAlphaNearest(a, {-58.5f / 64, 30.5f / 64}), 1.0f);  // column 5
  EXPECT_EQ(sampleAlphaNearest(a, {1.0f, 30.5f / 64}), 1.0f);         // u = 1 wraps to column 0
}

TEST(ScenesLights, DirectionalFromElevationAzimuthAndOthers) {
  Scene s = loadScene(resolveScenePath("sphere_on_plane"));
  const Light* sun = s.findLight("sun");
  ASSERT_TRUE(sun);
  EXPECT_EQ(s.findLight("moon"), nullptr);
  glm::vec3 expected = -toLight(50, -120);
  EXPECT_NEAR(glm::length(sun->direction - expected), 0.0f, 1e-6f);
  Scene m = loadText(mini(
      R"({"type": "plane", "size": [4, 4]})",
      R"({"type": "spot", "name": "spot", "position": [0, 4, 0], "look_at": [0, 0, 0], "cone_deg": 50, "near": 0.2},
                             {"type": "point", "name": "bulb", "position": [1, 2, 3]},
                             {"type": "directional", "name": "sky", "direction": [0, -2, 0]})"));
  ASSERT_EQ(m.lights.size(), 3u);
  EXPECT_EQ(m.lights[0].type, LightType::Spot);
  EXPECT_NEAR(glm::length(m.lights[0].direction - glm::vec3(0, -1, 0)), 0.0f, 1e-6f);
  EXPECT_FLOAT_EQ(m.lights[0].coneDeg, 50.0f);
  EXPECT_FLOAT_EQ(m.lights[0].nearPlane, 0.2f);
  EXPECT_EQ(m.lights[1].type, LightType::Point);
  EXPECT_EQ(m.lights[1].position, glm::vec3(1, 2, 3));
  EXPECT_EQ(m.lights[2].direction, glm::vec3(0, -1, 0));  // normalized
}

TEST(ScenesLights, SizedLightsTakeRadiusAndAngularDiameter) {
  Scene m = loadText(mini(
      R"({"type": "plane", "size": [4, 4]})",
      R"({"type": "spot", "name": "spot", "position": [0, 4, 0], "look_at": [0, 0, 0], "cone_deg": 50, "radius": 0.3},
         {"type": "point", "name": "bulb", "position": [1, 2, 3], "radius": 0.5},
         {"type": "directional", "name": "sun", "elevation_deg": 45, "angular_diameter_deg": 0.53},
         {"type": "directional", "name": "hard", "elevation_deg": 45})"));
  ASSERT_EQ(m.lights.size(), 4u);
  EXPECT_FLOAT_EQ(m.lights[0].radius, 0.3f);
  EXPECT_FLOAT_EQ(m.lights[1].radius, 0.5f);
  EXPECT_FLOAT_EQ(m.lights[2].angularDiameterDeg, 0.53f);
  EXPECT_TRUE(m.lights[0].sized() && m.lights[1].sized() && m.lights[2].sized());
  EXPECT_FALSE(m.lights[3].sized());
  EXPECT_EQ(m.lights[3].radius, 0.0f);
  EXPECT_EQ(m.lights[3].angularDiameterDeg, 0.0f);
  // A size of 0 is the hard light; the scene hash still names the document as written.
  Scene zero = loadText(mini(R"({"type": "plane", "size": [4, 4]})",
                             R"({"type": "point", "position": [1, 2, 3], "radius": 0})"));
  EXPECT_FALSE(zero.lights[0].sized());

  EXPECT_NE(errorOf([&] {
              loadText(mini(R"({"type": "plane", "size": [4, 4]})",
                            R"({"type": "point", "position": [1, 2, 3], "radius": -0.1})"));
            }).find("/lights/0/radius: error: got -0.1; expected a radius 0..1e30"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              loadText(mini(R"({"type": "plane", "size": [4, 4]})",
                            R"({"type": "directional", "elevation_deg": 45, "angular_diameter_deg": 25})"));
            }).find("/lights/0/angular_diameter_deg: error: got 25; expected an angle in degrees 0..20"),
            std::string::npos);
  // Each type takes its own size key only.
  EXPECT_NE(errorOf([&] {
              loadText(mini(R"({"type": "plane", "size": [4, 4]})",
                            R"({"type": "directional", "elevation_deg": 45, "radius": 1})"));
            }).find("/lights/0/radius"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              loadText(mini(R"({"type": "plane", "size": [4, 4]})",
                            R"({"type": "point", "position": [1, 2, 3], "angular_diameter_deg": 1})"));
            }).find("/lights/0/angular_diameter_deg"),
            std::string::npos);
}

TEST(ScenesLights, ProjectorOnlySceneIsValid) {
  fs::path dir = tempDir("projonly");
  fs::copy_file(bundledScenesDir() + "/projector_image.png", dir / "img.png");
  std::string text =
      mini(R"({"type": "plane", "size": [4, 4]})", "",
           R"(, "projectors": [{"position": [0, 2, 2], "look_at": [0, 0, 0], "fov_deg": 30, "image": "img.png"}])");
  writeFileAtomic((dir / "p.json").string(), text);
  Scene s = loadScene((dir / "p.json").string());
  EXPECT_TRUE(s.lights.empty());
  ASSERT_EQ(s.projectors.size(), 1u);
  EXPECT_EQ(s.projectors[0].name, "projector");
}

TEST(ScenesOverrides, ReplaceValuesBeforeResolving) {
  std::string path = resolveScenePath("sphere_on_plane");
  Scene base = loadScene(path);
  Scene low = loadScene(path, {{"/lights/0/elevation_deg", 30}});
  EXPECT_NEAR(glm::length(low.lights[0].direction + toLight(30, -120)), 0.0f, 1e-6f);
  EXPECT_NE(low.hash, base.hash);
  // A new key in an existing object is allowed (and validated like any other).
  Scene rotated = loadScene(path, {{"/objects/1/transform/rotate_deg", {0, 45, 0}}});
  EXPECT_NE(rotated.hash, base.hash);
  Scene lifted = loadScene(path, {{"/objects/1/transform/translate/1", 1.5}});
  EXPECT_NEAR(lifted.boundsMax().y, 2.5f, 1e-3f);
  EXPECT_EQ(errorOf([&] {
              loadScene(path, {{"/lights/5/elevation_deg", 10}});
            }),
            path +
                ": override /lights/5/elevation_deg: error: no such value in the scene; expected a pointer to an "
                "existing value");
  EXPECT_EQ(errorOf([&] {
              loadScene(path, {{"/camera/width", 0}});
            }),
            path +
                ": /camera/width: error: got 0; expected an integer 1..16384 (the largest image every Vulkan device "
                "must support)");
  EXPECT_NE(errorOf([&] {
              loadScene(path, {{"/camera/fovy", 30}});
            }).find(path + ": /camera/fovy: error: unknown key \"fovy\""),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              loadScene(path, {{"lights", 1}});
            }).find("override lights: error: got \"lights\"; expected a JSON pointer"),
            std::string::npos);
}

TEST(ScenesObj, BunnyFromSharedAssets) {
  Scene s = loadScene(resolveScenePath("bunny"));
  const Object& bunny = objectNamed(s, "bunny");
  EXPECT_EQ(bunny.triangles.size(), 27864u);
  EXPECT_TRUE(bunny.uvs.empty());
  float minY = 1e9f, maxY = -1e9f;
  for (const auto& p : bunny.positions) {
    minY = std::min(minY, p.y);
    maxY = std::max(maxY, p.y);
  }
  // File bounds y 0.033345 .. 0.186998, scaled by 10 and moved down 0.33.
  EXPECT_NEAR(minY, 0.33345f - 0.33f, 1e-5f);
  EXPECT_NEAR(maxY, 1.86998f - 0.33f, 1e-5f);
}

TEST(ScenesObj, MtlMaterialsAndMapD) {
  fs::path dir = tempDir("objmtl");
  // A unit quad as two faces, uvs from OBJ (v up) and an MTL with a map_d alpha texture.
  writeFileAtomic((dir / "leaf.obj").string(),
                  "mtllib leaf.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                  "usemtl leaf\nf 1/1 2/2 3/3\nusemtl bark\nf 1/1 3/3 4/4\n");
  writeFileAtomic((dir / "leaf.mtl").string(),
                  "newmtl leaf\nKd 0.1 0.7 0.2\nmap_d tex/leaf_alpha.png\nnewmtl bark\nKd 0.4 0.3 0.2\n");
  fs::create_directories(dir / "tex");
  // 2x1 RGB picture: black (alpha 0) on the left, white (alpha 1) on the right.
  writeRgbPng((dir / "tex" / "leaf_alpha.png").string(), 2, 1, {0, 0, 0, 255, 255, 255});
  writeFileAtomic((dir / "s.json").string(), mini(R"({"type": "obj", "name": "tree", "path": "leaf.obj"})"));
  Scene s = loadScene((dir / "s.json").string());
  ASSERT_EQ(s.materials.size(), 3u);
  EXPECT_EQ(s.materials[1].name, "tree/leaf");
  EXPECT_EQ(s.materials[2].name, "tree/bark");
  EXPECT_TRUE(s.materials[1].hasAlpha);
  EXPECT_FALSE(s.materials[2].hasAlpha);
  EXPECT_NEAR(s.materials[1].albedo.y, 0.7f, 1e-6f);
  EXPECT_EQ(sampleAlphaNearest(s.materials[1].alphaTexture, {0.25f, 0.5f}), 0.0f);
  EXPECT_EQ(sampleAlphaNearest(s.materials[1].alphaTexture, {0.75f, 0.5f}), 1.0f);
  const Object& tree = s.objects[0];
  EXPECT_EQ(tree.triangleMaterial, (std::vector<uint32_t>{1, 2}));
  ASSERT_EQ(tree.uvs.size(), tree.positions.size());
  // OBJ's v grows up; ours grows down from the top row: vt (0, 0) at the bottom-left -> uv (0, 1).
  for (size_t i = 0; i < tree.positions.size(); ++i) {
    if (tree.positions[i] == glm::vec3(0, 0, 0)) {
      EXPECT_EQ(tree.uvs[i], glm::vec2(0, 1));
    }
  }
  // A scene material on an OBJ replaces its MTL materials.
  writeFileAtomic((dir / "s2.json").string(), mini(R"({"type": "obj", "path": "leaf.obj", "material": "stone"})",
                                                   R"({"type": "directional", "elevation_deg": 45})",
                                                   R"(, "materials": {"stone": {"two_sided": false}})"));
  Scene s2 = loadScene((dir / "s2.json").string());
  EXPECT_EQ(s2.materials.size(), 2u);
  EXPECT_EQ(s2.objects[0].triangleMaterial, (std::vector<uint32_t>{1, 1}));
  EXPECT_FALSE(s2.materials[1].twoSided);
}

TEST(ScenesObj, SharedDirFromEnvironment) {
  fs::path dir = tempDir("shared");
  fs::create_directories(dir / "assets");
  writeFileAtomic((dir / "assets" / "tri.obj").string(), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  writeFileAtomic((dir / "s.json").string(), mini(R"({"type": "obj", "path": "${SHARED}/tri.obj"})"));
  const char* old = std::getenv("SHADOWLAB_SHARED_DIR");
  std::string saved = old ? old : "";
  ::setenv("SHADOWLAB_SHARED_DIR", dir.string().c_str(), 1);
  EXPECT_EQ(sharedAssetsDir(), (dir / "assets").string());
  Scene s = loadScene((dir / "s.json").string());
  EXPECT_EQ(s.triangleCount(), 1u);
  ::setenv("SHADOWLAB_SHARED_DIR", (dir / "nowhere").string().c_str(), 1);
  std::string err = errorOf([&] { loadScene((dir / "s.json").string()); });
  EXPECT_NE(err.find("/objects/0/path: error: OBJ file " + (dir / "nowhere" / "tri.obj").string() + " not found"),
            std::string::npos)
      << err;
  if (old) ::setenv("SHADOWLAB_SHARED_DIR", saved.c_str(), 1);
  else ::unsetenv("SHADOWLAB_SHARED_DIR");
}

TEST(ScenesLoader, HashCoversResolvedFiles) {
  // Same JSON, different texture content: different hash.
  fs::path dir = tempDir("hash");
  std::string text =
      mini(R"({"type": "quad", "size": [1, 1], "material": "m"})", R"({"type": "directional", "elevation_deg": 45})",
           R"(, "materials": {"m": {"alpha_texture": "a.png"}})");
  writeFileAtomic((dir / "s.json").string(), text);
  writeRgbPng((dir / "a.png").string(), 1, 1, {0, 0, 0});
  std::string h1 = loadScene((dir / "s.json").string()).hash;
  writeRgbPng((dir / "a.png").string(), 1, 1, {255, 255, 255});
  std::string h2 = loadScene((dir / "s.json").string()).hash;
  EXPECT_NE(h1, h2);
  // Comments and whitespace do not change it: the hash is over the canonical document.
  writeFileAtomic((dir / "s.json").string(), "// a comment\n" + text + "\n\n");
  EXPECT_EQ(loadScene((dir / "s.json").string()).hash, h2);
}

// Sweeps put each declared failure value at the declared pointer: every one must load, and
// every value other than the file's own must change the scene (and its hash).
TEST(ScenesLoader, EveryFailureValueLoadsAndChangesTheScene) {
  for (const auto& n : bundledSceneNames()) {
    std::string path = resolveScenePath(n);
    Scene base = loadScene(path);
    nlohmann::json doc = nlohmann::json::parse(readFile(path), nullptr, true, true);
    double own = doc[nlohmann::json::json_pointer(base.failurePointer)].get<double>();
    std::set<std::string> hashes;
    for (double v : base.failureValues) {
      SCOPED_TRACE(n + " " + base.failurePointer + "=" + std::to_string(v));
      Scene s = loadScene(path, {{base.failurePointer, v}});
      if (v == own) EXPECT_EQ(s.hash, base.hash);
      else EXPECT_NE(s.hash, base.hash);
      hashes.insert(s.hash);
    }
    EXPECT_EQ(hashes.size(), std::set<double>(base.failureValues.begin(), base.failureValues.end()).size()) << n;
  }
}

}  // namespace scenes_loader_test
