// An OBJ face shaped like a C casts a C: the reference (Embree) shadow of a single concave OBJ face
// on the ground, pixel by pixel against the closed form. Both renderers draw the loader's
// triangles, so a face cut into the wrong triangles (a fan over the C's notch) would shadow the
// notch in both and no metric would notice; this test checks the truth itself.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace reference_obj_face_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHeight = 1.0;  // the C floats at y = 1
// The sun travels along (3, -1, 0): from a ground point, the light is up along (-3, 1, 0), so the
// C's shadow is the C moved by +3 in x (it falls beside the C, where the camera sees the ground).
constexpr double kShift = 3.0;

// The C in the xz plane: the ring sector of radii 0.5 and 1 around the origin, its notch (the gap
// between its arms) towards +x, between -45 and +45 degrees.
bool inC(double x, double z) {
  const double r = std::hypot(x, z), a = std::atan2(-z, x);
  return r > 0.5 && r < 1.0 && std::fabs(a) > kPi / 4;
}
bool inNotch(double x, double z) {
  const double r = std::hypot(x, z), a = std::atan2(-z, x);
  return r > 0.5 && r < 1.0 && std::fabs(a) < kPi / 4;
}

std::string cObj(int arc) {
  std::ostringstream s;
  s.precision(9);
  const double from = kPi / 4, to = 2 * kPi - kPi / 4;
  for (int i = 0; i < arc; ++i) {
    const double a = from + (to - from) * i / (arc - 1);
    s << "v " << std::cos(a) << " " << kHeight << " " << -std::sin(a) << "\n";
  }
  for (int i = arc - 1; i >= 0; --i) {
    const double a = from + (to - from) * i / (arc - 1);
    s << "v " << 0.5 * std::cos(a) << " " << kHeight << " " << -0.5 * std::sin(a) << "\n";
  }
  s << "f";
  for (int i = 1; i <= 2 * arc; ++i) s << " " << i;
  s << "\n";
  return s.str();
}

}  // namespace

TEST(ReferenceObjFace, ConcaveFaceCastsItsOwnShape) {
  const fs::path dir = fs::temp_directory_path() / ("shadowlab_reference_obj_face_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // 64 corners per arc: the polygon stays within 0.0003 of the true arcs (1 - cos(pi / 84)), far
  // below the one-pixel margin (about 0.045 world units) kept from every boundary.
  writeFileAtomic((dir / "c.obj").string(), cObj(64));
  writeFileAtomic((dir / "c.json").string(), R"({
    "camera": {"position": [1.5, 10, 0], "look_at": [1.5, 0, 0], "up": [0, 0, -1], "vfov_deg": 40,
               "width": 160, "height": 160},
    "objects": [{"type": "plane", "name": "ground", "size": [16, 16]},
                {"type": "obj", "name": "c", "path": "c.obj"}],
    "lights": [{"type": "directional", "direction": [3, -1, 0]}]})");
  const Scene scene = loadScene((dir / "c.json").string());
  const Frame frame = renderReference(scene, ReferenceOptions{});
  const auto& objectId = frame.get("object_id");
  const auto& vis = frame.get("light.sun.vis");

  // What a ray through image point (x, y) sees: 2 the C, 1 lit ground, 0 shadowed ground, -1 else.
  const Camera& cam = scene.camera;
  const glm::dvec3 origin(cam.position);
  auto truth = [&](float x, float y) {
    const glm::dvec3 d(cam.rayDirection(x, y));
    if (d.y >= 0) return -1;
    const glm::dvec3 atC = origin + d * ((kHeight - origin.y) / d.y);
    if (inC(atC.x, atC.z)) return 2;
    const glm::dvec3 g = origin + d * (-origin.y / d.y);
    if (std::fabs(g.x) > 8 || std::fabs(g.z) > 8) return -1;
    return inC(g.x - kShift, g.z) ? 0 : 1;
  };
  int compared = 0, mismatches = 0, notchLit = 0, armsShadowed = 0;
  std::string first;
  for (int j = 0; j < cam.height; ++j)
    for (int i = 0; i < cam.width; ++i) {
      const int centre = truth(i + 0.5f, j + 0.5f);
      bool uniform = true;
      for (float dy : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
        for (float dx : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f}) uniform &= truth(i + 0.5f + dx, j + 0.5f + dy) == centre;
      if (!uniform || centre < 0) continue;
      ++compared;
      const size_t p = size_t(j) * cam.width + i;
      const int got =
          objectId[p] == 2.0f ? 2 : (objectId[p] == 1.0f ? (vis[p] == 1.0f ? 1 : (vis[p] == 0.0f ? 0 : -2)) : -3);
      if (got != centre && ++mismatches <= 10)
        first += "  pixel (" + std::to_string(i) + ", " + std::to_string(j) + "): got " + std::to_string(got) +
                 ", expected " + std::to_string(centre) + "\n";
      if (centre == 1 || centre == 0) {
        const glm::dvec3 d(cam.rayDirection(i + 0.5f, j + 0.5f));
        const glm::dvec3 g = origin + d * (-origin.y / d.y);
        if (inNotch(g.x - kShift, g.z) && got == 1) ++notchLit;
        if (inC(g.x - kShift, g.z) && got == 0) ++armsShadowed;
      }
    }
  EXPECT_EQ(mismatches, 0) << "of " << compared << " compared pixels:\n" << first;
  // Not vacuous: the ground under the notch is lit, under the C's arms shadowed, in many pixels.
  EXPECT_GT(notchLit, 100);
  EXPECT_GT(armsShadowed, 400);
  EXPECT_GT(compared, 15000);
}

}  // namespace reference_obj_face_test
