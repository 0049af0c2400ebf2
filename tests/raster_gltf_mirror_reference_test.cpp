// A mirrored glTF node (a world transform with a negative determinant, glTF 2.0 "Transformations")
// reverses its mesh's winding: a single-sided mesh under "scale": [-1, 1, 1] must keep its front
// faces, so it casts the shadow of its mirror image. The twin scene is built so that the answers
// must match: its mesh is the mirror image of the plain scene's (x negated, each triangle's
// winding reversed so that it faces up, as an exporter writes it), placed under a node that
// mirrors it back. Both scenes then hold the same world triangles, so both renderers must give
// the same frames, bit for bit; without the winding reversal the twin's triangles face down, both
// renderers cull them from the light, and its shadow is gone.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"
#include "support/gltf_builder.h"
#include "support/raster_device.h"
#include "support/same_frames.h"

namespace raster_gltf_mirror_reference_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::differingValues;
using shadowlab::testing::GltfBuilder;

namespace {

using GltfMirror = shadowlab::testing::ValidatedRasterTest;

fs::path freshDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("shadowlab_gltf_mirror_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

size_t shadowedPixels(const Frame& f) {
  size_t n = 0;
  for (float v : f.get("light.sun.vis")) n += v == 0.0f;
  return n;
}

// An asymmetric single-sided occluder at y = 1 (an L of three triangles, right of x = 0), each
// triangle counter-clockwise seen from above: its front faces look up, at the sun.
const std::vector<glm::vec3> kOccluder = {{0.2f, 1, -0.6f}, {1.4f, 1, -0.6f}, {1.4f, 1, -0.2f}, {0.2f, 1, -0.2f},
                                          {0.6f, 1, -0.2f}, {0.2f, 1, 0.9f},  {0.6f, 1, 0.9f}};
const std::vector<uint16_t> kUp = {0, 3, 2, 0, 2, 1, 3, 5, 6};

// The JSON scene around the glTF: a ground, a camera looking down on it, the sun above.
std::string wrapper(const std::string& gltf) {
  return R"({
    "camera": {"position": [0, 6, 2.5], "look_at": [0, 0, 0], "vfov_deg": 40, "width": 96, "height": 72},
    "objects": [{"type": "plane", "name": "ground", "size": [8, 8]},
                {"type": "gltf", "name": "occluder", "path": ")" +
         gltf + R"("}],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 70, "azimuth_deg": 20}]
  })";
}

}  // namespace

TEST_F(GltfMirror, AMirroredNodeCastsTheShadowOfItsMirrorImage) {
  const fs::path dir = freshDir("twin");
  GltfBuilder plain;
  plain.mesh(plain.positions(kOccluder), plain.indices16(kUp));
  plain.node({{"mesh", 0}});
  plain.scene({0});
  plain.write(dir.string(), "plain", GltfBuilder::Form::Binary);

  std::vector<glm::vec3> mirrored;
  for (const glm::vec3& v : kOccluder) mirrored.emplace_back(-v.x, v.y, v.z);
  std::vector<uint16_t> reversed;
  for (size_t t = 0; t < kUp.size(); t += 3) reversed.insert(reversed.end(), {kUp[t], kUp[t + 2], kUp[t + 1]});
  GltfBuilder twin;
  twin.mesh(twin.positions(mirrored), twin.indices16(reversed));
  twin.node({{"mesh", 0}, {"scale", {-1, 1, 1}}});
  twin.scene({0});
  twin.write(dir.string(), "twin", GltfBuilder::Form::Binary);

  std::ofstream(dir / "plain.json") << wrapper("plain.glb");
  std::ofstream(dir / "twin.json") << wrapper("twin.glb");
  const Scene a = loadScene((dir / "plain.json").string()), b = loadScene((dir / "twin.json").string());
  // The same world triangles, corner for corner and in the same winding (front faces up).
  ASSERT_EQ(a.objects[1].triangles.size(), 3u);
  ASSERT_EQ(b.objects[1].triangles.size(), 3u);
  for (size_t t = 0; t < 3; ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(b.objects[1].positions[b.objects[1].triangles[t][k]],
                a.objects[1].positions[a.objects[1].triangles[t][k]])
          << "triangle " << t << " corner " << k;
  // Single-sided: glTF's default material culls back faces in both renderers.
  EXPECT_FALSE(b.materials[b.objects[1].triangleMaterial[0]].twoSided);

  ReferenceOptions o;
  o.threads = 2;
  const Frame ta = renderReference(a, o), tb = renderReference(b, o);
  // The occluder's shadow is on the ground: the comparison is not between two unshadowed frames.
  EXPECT_GT(shadowedPixels(ta), 50u);
  EXPECT_EQ(shadowedPixels(tb), shadowedPixels(ta));
  EXPECT_EQ(differingValues(ta, tb, "reference"), 0u);
  REQUIRE_DEVICE();
  const Frame ra = R->render(a, Method{}, "sun"), rb = R->render(b, Method{}, "sun");
  EXPECT_GT(shadowedPixels(ra), 50u);
  EXPECT_EQ(differingValues(ra, rb, "raster"), 0u);
  fs::remove_all(dir);
}

}  // namespace raster_gltf_mirror_reference_test
