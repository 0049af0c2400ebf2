// glTF scenes give the truth (and the raster) of the scenes they describe, bit for bit:
//  - the same geometry as OBJ and as glTF: identical reference and raster channels;
//  - an alpha-MASK glTF (cards with a checker alpha texture under a KHR_lights_punctual spot) and
//    the equivalent JSON alpha scene (an OBJ of the cards with an alpha_texture material and a JSON
//    spot light): identical reference and raster channels;
//  - BoxTextured (assimp-testmodels) as .gltf + .bin, as one embedded .gltf and as .glb: identical truth.
// Bit-identical means every channel's every float; only the frames' scene hashes differ (the files do).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"
#include "support/gltf_builder.h"
#include "support/raster_device.h"
#include "support/same_frames.h"
#include "support/test_models.h"

namespace raster_gltf_reference_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::differingValues;
using shadowlab::testing::GltfBuilder;

namespace {

using GltfTruth = shadowlab::testing::ValidatedRasterTest;

fs::path freshDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("shadowlab_gltf_truth_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The object's triangles as corner positions (and uvs when it has them): what both renderers draw,
// whatever the vertex numbering (the OBJ loader numbers vertices in its own order of first use).
std::vector<float> corners(const Object& o) {
  std::vector<float> out;
  for (const auto& t : o.triangles)
    for (unsigned v : {t.x, t.y, t.z}) {
      out.insert(out.end(), {o.positions[v].x, o.positions[v].y, o.positions[v].z});
      if (!o.uvs.empty()) out.insert(out.end(), {o.uvs[v].x, o.uvs[v].y});
    }
  return out;
}

Frame truth(const Scene& s) {
  ReferenceOptions o;
  o.threads = 2;
  return renderReference(s, o);
}

std::string floatText(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// The JSON scene around one mesh object: ground, a camera, a sun and a spot.
std::string meshScene(const std::string& object) {
  return R"({
    "camera": {"position": [2.5, 3, 4], "look_at": [0, 0.5, 0], "vfov_deg": 45, "width": 160, "height": 120},
    "objects": [{"type": "plane", "name": "ground", "size": [8, 8]}, )" +
         object + R"(],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 55, "azimuth_deg": 20},
               {"type": "spot", "name": "spot", "position": [0.5, 4, 1], "look_at": [0, 0, 0], "cone_deg": 70}]
  })";
}

}  // namespace

TEST_F(GltfTruth, SameGeometryAsObjAndAsGltfGivesIdenticalTruthAndRaster) {
  const fs::path dir = freshDir("identity");
  // A bumpy 6x6-cell sheet over the ground with pseudo-random heights (floats with every bit used),
  // triangles sharing vertices.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> height(0.6f, 1.4f);
  const int n = 7;
  std::vector<glm::vec3> verts;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) verts.emplace_back(-1.5f + 0.5f * i, height(rng), -1.5f + 0.5f * j);
  std::vector<glm::uvec3> tris;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const unsigned a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      tris.push_back({a, c, b});
      tris.push_back({b, c, d});
    }
  // The OBJ, as written.
  {
    std::ofstream obj(dir / "sheet.obj");
    for (const auto& v : verts) obj << "v " << floatText(v.x) << " " << floatText(v.y) << " " << floatText(v.z) << "\n";
    for (const auto& t : tris) obj << "f " << t.x + 1 << " " << t.y + 1 << " " << t.z + 1 << "\n";
  }
  // The glTF: the same vertices and triangles.
  std::vector<uint32_t> indices;
  for (const auto& t : tris) indices.insert(indices.end(), {t.x, t.y, t.z});
  GltfBuilder g;
  g.doc["materials"] = {{{"doubleSided", true}}};
  g.mesh(g.positions(verts), g.indices32(indices), -1, 0);
  g.node({{"mesh", 0}});
  g.scene({0});
  g.write(dir.string(), "sheet", GltfBuilder::Form::Binary);
  std::ofstream(dir / "obj.json") << meshScene(R"({"type": "obj", "name": "sheet", "path": "sheet.obj"})");
  std::ofstream(dir / "gltf.json") << meshScene(R"({"type": "gltf", "name": "sheet", "path": "sheet.glb"})");
  const Scene a = loadScene((dir / "obj.json").string()), b = loadScene((dir / "gltf.json").string());
  ASSERT_EQ(corners(a.objects[1]), corners(b.objects[1]));
  const Frame ta = truth(a), tb = truth(b);
  EXPECT_EQ(differingValues(ta, tb, "reference"), 0u);
  // The sheet shadows the ground under both lights: the comparison is not between two empty frames.
  size_t shadowed = 0;
  for (float v : ta.get("light.sun.vis")) shadowed += v == 0.0f;
  EXPECT_GT(shadowed, 500u);
  REQUIRE_DEVICE();
  for (const std::string light : {"sun", "spot"})
    EXPECT_EQ(differingValues(R->render(a, Method{}, light), R->render(b, Method{}, light), "raster " + light), 0u);
}

TEST_F(GltfTruth, AlphaMaskGltfGivesTheTruthOfTheEquivalentJsonAlphaScene) {
  const fs::path dir = freshDir("mask");
  fs::copy_file(fs::path(SHADOWLAB_SOURCE_DIR) / "scenes/data/gltf_checker_alpha.png", dir / "checker.png");
  // Three 1 x 1.5 cards in xy, 0.75 m apart in z, at dyadic positions (exact in float and double).
  const std::vector<glm::vec3> card = {{-0.5f, -0.75f, 0}, {0.5f, -0.75f, 0}, {0.5f, 0.75f, 0}, {-0.5f, 0.75f, 0}};
  const std::vector<glm::vec2> uv = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  const std::vector<glm::vec3> places = {{-0.25f, 1, -0.75f}, {0, 1, 0}, {0.25f, 1, 0.75f}};
  GltfBuilder g;
  g.doc["images"] = {{{"uri", "checker.png"}}};
  g.doc["textures"] = {{{"source", 0}}};
  g.doc["extensionsUsed"] = {"KHR_texture_transform"};
  g.doc["materials"] = {
      {{"alphaMode", "MASK"},
       {"doubleSided", true},
       {"pbrMetallicRoughness",
        {{"baseColorTexture", {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}}}}}};
  g.mesh(g.positions(card), g.indices8({0, 1, 2, 0, 2, 3}), -1, 0, g.uvs(uv));
  std::vector<int> roots;
  for (const auto& p : places) roots.push_back(g.node({{"mesh", 0}, {"translation", {p.x, p.y, p.z}}}));
  // The spot: at (0, 4, 0) looking straight down (a matrix with exact columns: -z maps to -y).
  const double outer = 0.5;
  g.light({{"type", "spot"}, {"name", "spot"}, {"spot", {{"outerConeAngle", outer}}}});
  roots.push_back(g.node({{"matrix", {1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 4, 0, 1}},
                          {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}));
  g.scene(roots);
  g.write(dir.string(), "cards", GltfBuilder::Form::Embedded);
  const std::string camera =
      R"("camera": {"position": [2, 2.5, 3.5], "look_at": [0, 0.6, 0], "vfov_deg": 50, "width": 160, "height": 120})";
  std::ofstream(dir / "gltf.json") << "{" << camera << R"(,
    "objects": [{"type": "plane", "name": "ground", "size": [6, 6]},
                {"type": "gltf", "name": "cards", "path": "cards.gltf"}]})";
  // The JSON alpha scene: the same cards as one OBJ (vt = 1 - v: OBJ's v grows up) with an
  // alpha_texture material, and the same spot as a JSON light.
  {
    std::ofstream obj(dir / "cards.obj");
    for (size_t c = 0; c < places.size(); ++c) {
      for (const auto& v : card) {
        const glm::vec3 p = v + places[c];
        obj << "v " << floatText(p.x) << " " << floatText(p.y) << " " << floatText(p.z) << "\n";
      }
      for (const auto& t : uv) obj << "vt " << floatText(2 * t.x) << " " << floatText(1 - 2 * t.y) << "\n";
      const size_t b = 4 * c + 1;
      obj << "f " << b << "/" << b << " " << b + 1 << "/" << b + 1 << " " << b + 2 << "/" << b + 2 << "\n";
      obj << "f " << b << "/" << b << " " << b + 2 << "/" << b + 2 << " " << b + 3 << "/" << b + 3 << "\n";
    }
  }
  char cone[64];
  std::snprintf(cone, sizeof cone, "%.17g", 2.0 * outer * 180.0 / 3.14159265358979323846);
  std::ofstream(dir / "json.json") << "{" << camera << R"(,
    "materials": {"checker": {"alpha_texture": "checker.png", "alpha_cutoff": 0.5, "two_sided": true}},
    "objects": [{"type": "plane", "name": "ground", "size": [6, 6]},
                {"type": "obj", "name": "cards", "path": "cards.obj", "material": "checker"}],
    "lights": [{"type": "spot", "name": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "cone_deg": )"
                                   << cone << "}]}";
  const Scene a = loadScene((dir / "json.json").string()), b = loadScene((dir / "gltf.json").string());
  ASSERT_EQ(a.lights.size(), 1u);
  ASSERT_EQ(b.lights.size(), 1u);
  EXPECT_EQ(a.lights[0].direction, b.lights[0].direction);
  EXPECT_EQ(a.lights[0].coneDeg, b.lights[0].coneDeg);
  ASSERT_EQ(corners(a.objects[1]), corners(b.objects[1]));
  const Frame ta = truth(a), tb = truth(b);
  EXPECT_EQ(differingValues(ta, tb, "reference"), 0u);
  // The holes show: on the ground under the cards, both lit and shadowed points.
  size_t lit = 0, dark = 0;
  const auto& vis = ta.get("light.spot.vis");
  const auto& obj = ta.get("object_id");
  for (size_t i = 0; i < vis.size(); ++i)
    if (obj[i] == 1.0f) (vis[i] == 0.0f ? dark : lit)++;
  EXPECT_GT(dark, 300u);
  EXPECT_GT(lit, 300u);
  REQUIRE_DEVICE();
  EXPECT_EQ(differingValues(R->render(a, Method{}), R->render(b, Method{}), "raster"), 0u);
}

TEST_F(GltfTruth, BoxTexturedGivesBitIdenticalTruthInItsThreeForms) {
  SHADOWLAB_REQUIRE_TEST_MODEL(external, "glTF2/BoxTextured-glTF/BoxTextured.gltf");
  SHADOWLAB_REQUIRE_TEST_MODEL(embedded, "glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf");
  SHADOWLAB_REQUIRE_TEST_MODEL(binary, "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
  const Frame a = truth(loadScene(external));
  size_t hits = 0;
  for (float h : a.get("hit")) hits += h > 0;
  EXPECT_GT(hits, 1000u);  // the box fills part of the framing camera's picture
  EXPECT_EQ(differingValues(a, truth(loadScene(embedded)), "embedded"), 0u);
  EXPECT_EQ(differingValues(a, truth(loadScene(binary)), "glb"), 0u);
}

}  // namespace raster_gltf_reference_test
