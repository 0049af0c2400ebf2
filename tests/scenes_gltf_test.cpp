// glTF 2.0 files as scenes (scenes/FORMAT.md, "glTF files"): real files nobody on this project wrote
// (Debian's assimp-testmodels), good and malformed, and small files written here for each row of the
// mapping table, with the exact positions, directions and alphas the mapping gives.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"
#include "support/gltf_builder.h"
#include "support/input_error.h"
#include "support/test_models.h"

namespace scenes_gltf_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::GltfBuilder;
using shadowlab::testing::inputErrorOf;

namespace {

constexpr double kPi = 3.14159265358979323846;

class Gltf : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_scenes_gltf_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string dir() const { return dir_.string(); }
  // A JSON scene around a glTF object (`object` holds the object's extra keys).
  std::string wrapper(const std::string& gltfPath, const std::string& object = "", const std::string& extra = "") {
    const std::string path = dir() + "/wrapper.json";
    std::ofstream(path) << R"({"objects": [{"type": "gltf", "name": "asset", "path": ")" << gltfPath << "\"" << object
                        << "}]" << extra << "}";
    return path;
  }
  fs::path dir_;
};

// A unit square in xy (z = 0) as two triangles, the builder's first mesh.
GltfBuilder squareFile() {
  GltfBuilder b;
  const int pos = b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  const int idx = b.indices16({0, 1, 2, 0, 2, 3});
  b.mesh(pos, idx);
  return b;
}

std::vector<glm::vec3> corners(const Object& o, size_t triangle) {
  const glm::uvec3 t = o.triangles[triangle];
  return {o.positions[t.x], o.positions[t.y], o.positions[t.z]};
}

}  // namespace

// ----------------------------------------------------------------------------------------------
// Real files (assimp-testmodels).

TEST_F(Gltf, BoxTexturedIsTheSameSceneInItsThreeForms) {
  SHADOWLAB_REQUIRE_TEST_MODEL(external, "glTF2/BoxTextured-glTF/BoxTextured.gltf");
  SHADOWLAB_REQUIRE_TEST_MODEL(embedded, "glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf");
  SHADOWLAB_REQUIRE_TEST_MODEL(binary, "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
  const Scene a = loadScene(external), b = loadScene(embedded), c = loadScene(binary);
  // The box: 24 vertices, 12 triangles, under the glTF's root matrix (a z-up to y-up rotation).
  ASSERT_EQ(a.objects.size(), 1u);
  EXPECT_EQ(a.triangleCount(), 12u);
  for (const Scene* s : {&b, &c}) {
    ASSERT_EQ(s->objects.size(), 1u);
    EXPECT_EQ(s->objects[0].positions, a.objects[0].positions);
    EXPECT_EQ(s->objects[0].triangles, a.objects[0].triangles);
    EXPECT_EQ(s->objects[0].triangleMaterial, a.objects[0].triangleMaterial);
    EXPECT_EQ(s->camera.hash(), a.camera.hash());
  }
  // No light in the file: the default sun; no camera: the framing camera.
  ASSERT_EQ(a.lights.size(), 1u);
  EXPECT_EQ(a.lights[0].name, "sun");
  EXPECT_EQ(a.camera.width, 640);
  EXPECT_EQ(a.camera.height, 480);
}

TEST_F(Gltf, CamerasGivesEachOfItsCameras) {
  SHADOWLAB_REQUIRE_TEST_MODEL(path, "glTF2/cameras/Cameras.gltf");
  // Camera 0: perspective, yfov 0.7 rad, aspect 1, znear 0.01, zfar 100, at (0.5, 0.5, 3) looking down -z.
  for (const std::string& choice : {std::string(""), std::string(", \"camera\": 0")}) {
    const Scene s =
        choice.empty()
            ? loadScene(path)
            : loadScene(wrapper(path, choice, R"(, "lights": [{"type": "directional", "elevation_deg": 45}])"));
    EXPECT_EQ(s.camera.projection, Projection::Perspective);
    EXPECT_FLOAT_EQ(s.camera.vfovDeg, float(0.7 * 180.0 / kPi));
    EXPECT_EQ(s.camera.width, 640);
    EXPECT_EQ(s.camera.height, 640);
    EXPECT_EQ(s.camera.position, glm::vec3(0.5f, 0.5f, 3.0f));
    EXPECT_EQ(s.camera.lookAt, glm::vec3(0.5f, 0.5f, 2.0f));
    EXPECT_EQ(s.camera.up, glm::vec3(0, 1, 0));
    EXPECT_FLOAT_EQ(s.camera.nearPlane, 0.01f);
    EXPECT_FLOAT_EQ(s.camera.farPlane, 100.0f);
  }
  // Camera 1: orthographic, xmag = ymag = 1 (a 2 x 2 view: 640 x 640 pixels), znear 0.01, zfar 100,
  // at the same node placement.
  const Scene o =
      loadScene(wrapper(path, ", \"camera\": 1", R"(, "lights": [{"type": "directional", "elevation_deg": 45}])"));
  EXPECT_EQ(o.camera.projection, Projection::Orthographic);
  EXPECT_EQ(o.camera.orthoHeight, 2.0f);
  EXPECT_EQ(o.camera.width, 640);
  EXPECT_EQ(o.camera.height, 640);
  EXPECT_EQ(o.camera.position, glm::vec3(0.5f, 0.5f, 3.0f));
  EXPECT_EQ(o.camera.lookAt, glm::vec3(0.5f, 0.5f, 2.0f));
  EXPECT_EQ(o.camera.up, glm::vec3(0, 1, 0));
  EXPECT_FLOAT_EQ(o.camera.nearPlane, 0.01f);
  EXPECT_FLOAT_EQ(o.camera.farPlane, 100.0f);
  // Parallel rays down -z from the view's points: pixel (0, 0)'s corner is (0.5 - 1, 0.5 + 1).
  EXPECT_EQ(o.camera.rayDirection(0.5f, 0.5f), glm::vec3(0, 0, -1));
  EXPECT_EQ(o.camera.rayDirection(600.5f, 17.5f), glm::vec3(0, 0, -1));
  EXPECT_EQ(o.camera.rayOrigin(0.0f, 0.0f), glm::vec3(-0.5f, 1.5f, 3.0f));
  EXPECT_EQ(o.camera.rayOrigin(320.0f, 320.0f), glm::vec3(0.5f, 0.5f, 3.0f));
  EXPECT_NE(o.camera.hash(), loadScene(path).camera.hash());
  // The two renderers' projection: the view's corners at clip x, y = -1, +1 (Vulkan: y down).
  const glm::vec4 corner = o.camera.clipFromView() * o.camera.viewFromWorld() * glm::vec4(-0.5f, 1.5f, 0.0f, 1.0f);
  EXPECT_FLOAT_EQ(corner.x, -1.0f);
  EXPECT_FLOAT_EQ(corner.y, -1.0f);
  EXPECT_FLOAT_EQ(corner.w, 1.0f);
  const std::string missing = inputErrorOf([&] {
    loadScene(wrapper(path, ", \"camera\": 2", R"(, "lights": [{"type": "directional", "elevation_deg": 45}])"));
  });
  EXPECT_NE(missing.find("wrapper.json: /objects/0: error: camera 2 is out of range"), std::string::npos) << missing;
}

TEST_F(Gltf, TextureTransformTestLoads) {
  SHADOWLAB_REQUIRE_TEST_MODEL(path, "glTF2/textureTransform/TextureTransformTest.gltf");
  const Scene s = loadScene(path);
  EXPECT_GT(s.triangleCount(), 0u);
  EXPECT_FALSE(s.lights.empty());
}

TEST_F(Gltf, TwoCylinderEngineLoads) {
  SHADOWLAB_REQUIRE_TEST_MODEL(path, "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
  const Scene s = loadScene(path);
  EXPECT_EQ(s.triangleCount(), 121496u);
}

TEST_F(Gltf, GltfOneIsRefusedClearly) {
  SHADOWLAB_REQUIRE_TEST_MODEL(path, "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf");
  const std::string err = inputErrorOf([&] { loadScene(path); });
  EXPECT_NE(err.find("CesiumMilkTruck.gltf: /asset/version: error: glTF 1.0 is not supported; convert to glTF 2.0"),
            std::string::npos)
      << err;
}

// Each malformed file: an InputError naming the file, the place and the problem.
struct BadFile {
  const char* file;
  const char* expected;  // a part of the message
};

class GltfBadFile : public Gltf, public ::testing::WithParamInterface<BadFile> {};

TEST_P(GltfBadFile, IsAnInputErrorNamingTheProblem) {
  SHADOWLAB_REQUIRE_TEST_MODEL(path, std::string("glTF2/") + GetParam().file);
  const std::string err = inputErrorOf([&] { loadScene(path); });
  EXPECT_EQ(err.rfind(path, 0), 0u) << err;  // starts with the file
  EXPECT_NE(err.find(GetParam().expected), std::string::npos) << err;
}

INSTANTIATE_TEST_SUITE_P(
    AssimpTestModels, GltfBadFile,
    ::testing::Values(
        BadFile{"RecursiveNodes/RecursiveNodes.gltf",
                ": /nodes/1/children: error: the nodes form a cycle: /nodes/1 -> /nodes/0 -> /nodes/1"},
        BadFile{"IndexOutOfRange/IndexOutOfRange.gltf", "is out of range; the POSITION accessor has"},
        BadFile{"IndexOutOfRange/AllIndicesOutOfRange.gltf", "is out of range; the POSITION accessor has"},
        BadFile{"wrongTypes/badArray.gltf", ": /meshes/0/primitives: error: got an object; expected an array"},
        BadFile{"wrongTypes/badExtension.gltf",
                ": /materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform: error: got "
                "\"Not an object\"; expected an object"},
        BadFile{"wrongTypes/badNumber.gltf",
                ": /materials/0/normalTexture/scale: error: got \"not a number\"; expected a finite number"},
        BadFile{"wrongTypes/badObject.gltf",
                ": /materials/0/pbrMetallicRoughness: error: got an array of 1 value; expected an object"},
        BadFile{"wrongTypes/badString.gltf", ": /scenes/0/name: error: got 42; expected a string"},
        BadFile{"wrongTypes/badUint.gltf",
                ": /materials/0/pbrMetallicRoughness/baseColorTexture/index: error: got -1; expected an integer"},
        BadFile{"BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "expected finite positions"},
        BadFile{"MissingBin/BoxTextured.gltf", ": /buffers/0/uri: error: buffer file"},
        BadFile{"draco/2CylinderEngine.gltf",
                ": /extensionsRequired/0: error: the file requires the extension KHR_draco_mesh_compression"},
        BadFile{"SchemaFailures/sceneWrongType.gltf", ": /scene: error: got \"hello\"; expected an integer"}),
    [](const ::testing::TestParamInfo<BadFile>& info) {  // the file, e.g. wrongTypes_badUint_gltf
      std::string name = info.param.file;
      for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });

// ----------------------------------------------------------------------------------------------
// The mapping, on files written here.

TEST_F(Gltf, StripsFansAndEveryIndexTypeGiveTheSameTriangles) {
  GltfBuilder b;
  const int pos = b.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}});
  // TRIANGLES with u8, u16, u32 and no indices; a strip 0 1 2 3 (triangles 012, 213); a fan 0 1 3 2.
  const int n0 = b.node({{"mesh", b.mesh(pos, b.indices8({0, 1, 2, 2, 1, 3}))}});
  const int n1 = b.node({{"mesh", b.mesh(pos, b.indices16({0, 1, 2, 2, 1, 3}))}});
  const int n2 = b.node({{"mesh", b.mesh(pos, b.indices32({0, 1, 2, 2, 1, 3}))}});
  const int n3 = b.node({{"mesh", b.mesh(pos, -1, 5)}});
  const int n4 = b.node({{"mesh", b.mesh(pos, b.indices8({1, 3, 2, 0}), 6)}});
  b.scene({n0, n1, n2, n3, n4});
  const Scene s = loadScene(b.write(dir(), "modes"));
  const Object& o = s.objects[0];
  ASSERT_EQ(o.triangles.size(), 10u);
  // Every form gives triangles (0,0,0) (1,0,0) (0,1,0) and (0,1,0) (1,0,0) (1,1,0), the same winding.
  const std::vector<glm::vec3> first = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, second = {{0, 1, 0}, {1, 0, 0}, {1, 1, 0}};
  for (size_t m = 0; m < 3; ++m) {
    EXPECT_EQ(corners(o, 2 * m), first) << "mesh " << m;
    EXPECT_EQ(corners(o, 2 * m + 1), second) << "mesh " << m;
  }
  // The strip's second triangle is (v1, v3, v2) (glTF 2.0 3.7.2.1): the same triangle, corners rotated.
  EXPECT_EQ(corners(o, 6), first);
  EXPECT_EQ(corners(o, 7), (std::vector<glm::vec3>{{1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  // Fan 1 3 2 0: triangles (3, 2, 1) and (2, 0, 1).
  EXPECT_EQ(corners(o, 8), (std::vector<glm::vec3>{{1, 1, 0}, {0, 1, 0}, {1, 0, 0}}));
  EXPECT_EQ(corners(o, 9), (std::vector<glm::vec3>{{0, 1, 0}, {0, 0, 0}, {1, 0, 0}}));
}

TEST_F(Gltf, NormalizedStridedAndSparseAttributesAreRead) {
  GltfBuilder b;
  // Interleaved: position as normalized u16 (3 x 2 bytes) + 2 bytes padding, byteStride 8.
  const uint16_t data[] = {0, 0, 0, 0, 65535, 0, 0, 0, 0, 65535, 0, 0, 32768, 32768, 65535, 0};
  const int v = b.view(data, sizeof data, 8);
  const int pos = b.accessor(v, 5123, 4, "VEC3", true);
  // Sparse: replace vertex 3 by (2, 2, 2) (float values).
  const uint8_t sparseIdx[] = {3};
  const float sparseVal[] = {2, 2, 2};
  const int iv = b.view(sparseIdx, 1), vv = b.view(sparseVal, sizeof sparseVal);
  b.doc["accessors"][pos]["sparse"] = {
      {"count", 1}, {"indices", {{"bufferView", iv}, {"componentType", 5121}}}, {"values", {{"bufferView", vv}}}};
  b.doc["accessors"][pos]["componentType"] = 5126;  // sparse values share the accessor's type: floats
  // ...so the base must be floats too: rewrite it as floats with a stride of 16 (12 + 4 padding).
  const float base[] = {0, 0, 0, 9, 1, 0, 0, 9, 0, 1, 0, 9, 0.5f, 0.5f, 1, 9};
  b.doc["accessors"][pos]["bufferView"] = b.view(base, sizeof base, 16);
  b.doc["accessors"][pos].erase("normalized");
  // A second mesh with the normalized u16 positions of `v` (stride 8): integer positions are
  // KHR_mesh_quantization's.
  b.doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  const int npos = b.accessor(v, 5123, 4, "VEC3", true);
  b.node({{"mesh", b.mesh(pos, b.indices8({0, 1, 3, 0, 3, 2}))}});
  b.node({{"mesh", b.mesh(npos, b.indices8({0, 1, 3}))}});
  b.scene({0, 1});
  const Scene s = loadScene(b.write(dir(), "attributes"));
  const Object& o = s.objects[0];
  ASSERT_EQ(o.triangles.size(), 3u);
  EXPECT_EQ(corners(o, 0), (std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {2, 2, 2}}));
  EXPECT_EQ(corners(o, 1), (std::vector<glm::vec3>{{0, 0, 0}, {2, 2, 2}, {0, 1, 0}}));
  EXPECT_EQ(corners(o, 2),
            (std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {float(32768 / 65535.0), float(32768 / 65535.0), 1}}));
}

TEST_F(Gltf, NodesComposeParentTimesLocalAndInstanceMeshes) {
  GltfBuilder b = squareFile();
  // Parent: translate (10, 0, 0) and scale 2 (TRS). Children: the square under a matrix that
  // translates by (0, 0, 5), and under TRS rotating 90 degrees about z.
  const double h = std::sqrt(0.5);
  const int c0 = b.node({{"mesh", 0}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1}}});
  const int c1 = b.node({{"mesh", 0}, {"rotation", {0, 0, h, h}}});
  const int parent = b.node({{"translation", {10, 0, 0}}, {"scale", {2, 2, 2}}, {"children", {c0, c1}}});
  b.scene({parent});
  const Scene s = loadScene(b.write(dir(), "nodes"));
  const Object& o = s.objects[0];
  ASSERT_EQ(o.positions.size(), 8u);
  // c0: (x, y, 0) -> 2 * (x, y, 5) + (10, 0, 0).
  EXPECT_EQ(o.positions[2], glm::vec3(12, 2, 10));
  // c1: (1, 0, 0) rotated to (0, 1, 0), scaled by 2, translated: (10, 2, 0), within float rounding.
  EXPECT_NEAR(o.positions[5].x, 10.0f, 1e-5f);
  EXPECT_NEAR(o.positions[5].y, 2.0f, 1e-5f);
  EXPECT_EQ(o.triangles.size(), 4u);
}

TEST_F(Gltf, ChosenSceneAndCycleAndOutOfRangeNodes) {
  GltfBuilder b = squareFile();
  b.node({{"mesh", 0}});
  b.node({{"mesh", 0}, {"translation", {0, 0, 3}}});
  b.doc["scenes"] = {{{"nodes", {0}}}, {{"nodes", {1}}}};
  b.doc["scene"] = 0;
  const std::string path = b.write(dir(), "scenes");
  const std::string lights = R"(, "lights": [{"type": "directional", "elevation_deg": 45}])";
  EXPECT_EQ(loadScene(wrapper(path, "", lights)).objects[0].positions[0].z, 0.0f);
  EXPECT_EQ(loadScene(wrapper(path, ", \"scene\": 1", lights)).objects[0].positions[0].z, 3.0f);
  EXPECT_NE(inputErrorOf([&] {
              loadScene(wrapper(path, ", \"scene\": 2", lights));
            }).find("wrapper.json: /objects/0: error: scene 2 is out of range"),
            std::string::npos);
  b.doc["nodes"][1]["children"] = {5};
  const std::string bad = b.write(dir(), "badchild");
  EXPECT_NE(
      inputErrorOf([&] { loadScene(bad); }).find("badchild.gltf: /nodes/1/children/0: error: node 5 is out of range"),
      std::string::npos);
}

TEST_F(Gltf, PointsAndLinesAreSkippedWithOneWarningAndNoTriangleIsAnError) {
  GltfBuilder b = squareFile();
  const int pos = b.positions({{0, 0, 0}, {1, 0, 0}});
  b.mesh(pos, -1, 0);  // POINTS
  b.mesh(pos, -1, 1);  // LINES
  b.doc["meshes"][0]["primitives"].push_back(b.doc["meshes"][2]["primitives"][0]);
  b.node({{"mesh", 0}});
  b.node({{"mesh", 1}});
  b.scene({0, 1});
  ::testing::internal::CaptureStderr();
  const Scene s = loadScene(b.write(dir(), "mixed"));
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.triangleCount(), 2u);
  EXPECT_NE(err.find("mixed.gltf: warning: skipped 2 POINTS/LINES primitives"), std::string::npos) << err;
  b.doc["scenes"][0]["nodes"] = {1};
  const std::string only = b.write(dir(), "points");
  EXPECT_NE(inputErrorOf([&] { loadScene(only); }).find("points.gltf: /meshes: error: the glTF scene has no triangle"),
            std::string::npos);
}

TEST_F(Gltf, PunctualLightsLookDownTheirNodesMinusZAndIgnoreScale) {
  GltfBuilder b = squareFile();
  b.node({{"mesh", 0}});
  const double h = std::sqrt(0.5);
  b.light({{"type", "directional"}, {"name", "key light"}});
  b.light({{"type", "spot"}, {"spot", {{"outerConeAngle", 0.5}}}});
  b.light({{"type", "point"}});
  // -Z rotated by -90 degrees about x: (0, -1, 0); scale 3 must not matter.
  const nlohmann::json down = {0 - h, 0, 0, h};
  b.node({{"rotation", down}, {"scale", {3, 3, 3}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
  b.node({{"rotation", down}, {"translation", {1, 4, 2}}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
  b.node({{"translation", {0, 2, 0}}, {"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
  b.scene({0, 1, 2, 3});
  const Scene s = loadScene(b.write(dir(), "lights"));
  ASSERT_EQ(s.lights.size(), 3u);
  EXPECT_EQ(s.lights[0].name, "key_light");
  EXPECT_EQ(s.lights[0].type, LightType::Directional);
  EXPECT_NEAR(s.lights[0].direction.y, -1.0f, 1e-6f);
  EXPECT_NEAR(glm::length(s.lights[0].direction), 1.0f, 1e-6f);
  EXPECT_EQ(s.lights[1].name, "spot");
  EXPECT_EQ(s.lights[1].type, LightType::Spot);
  EXPECT_EQ(s.lights[1].position, glm::vec3(1, 4, 2));
  EXPECT_FLOAT_EQ(s.lights[1].coneDeg, float(2 * 0.5 * 180 / kPi));
  EXPECT_EQ(s.lights[2].type, LightType::Point);
  EXPECT_EQ(s.lights[2].position, glm::vec3(0, 2, 0));
  // An override on a glTF path addresses the glTF document.
  const Scene narrow =
      loadScene(b.write(dir(), "lights"), {{"/extensions/KHR_lights_punctual/lights/1/spot/outerConeAngle", 0.25}});
  EXPECT_FLOAT_EQ(narrow.lights[1].coneDeg, float(2 * 0.25 * 180 / kPi));
  EXPECT_NE(narrow.hash, s.hash);
}

TEST_F(Gltf, MaskMaterialsBecomeAlphaTestedWithTheTextureTransformApplied) {
  // The repository's checker: RGBA 8x8, alpha 255 and 0 in 1-texel squares (make_assets.py).
  const std::string checker = std::string(SHADOWLAB_SOURCE_DIR) + "/scenes/data/gltf_checker_alpha.png";
  fs::copy_file(checker, dir_ / "checker.png");
  GltfBuilder b;
  const int pos = b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  const int uv = b.uvs({{0, 1}, {1, 1}, {1, 0}, {0, 0}});
  b.doc["images"] = {{{"uri", "checker.png"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = {
      {{"alphaMode", "MASK"},
       {"alphaCutoff", 0.25},
       {"doubleSided", true},
       {"pbrMetallicRoughness",
        {{"baseColorFactor", {1, 1, 1, 0.5}},
         {"baseColorTexture",
          {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"offset", {0.5, 0}}, {"scale", {2, 4}}}}}}}}}}},
      {{"alphaMode", "BLEND"}, {"doubleSided", true}}};
  b.mesh(pos, b.indices8({0, 1, 2, 0, 2, 3}), -1, 0, uv);
  b.mesh(pos, b.indices8({0, 1, 2}), -1, 1);
  b.node({{"mesh", 0}});
  b.node({{"mesh", 1}, {"translation", {0, 0, 1}}});
  b.scene({0, 1});
  ::testing::internal::CaptureStderr();
  const Scene s = loadScene(b.write(dir(), "mask"));
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("mask.gltf: warning: 1 material with alphaMode BLEND drawn as OPAQUE"), std::string::npos) << err;
  const Object& o = s.objects[0];
  const Material& m = s.materials[o.triangleMaterial[0]];
  ASSERT_TRUE(m.hasAlpha);
  EXPECT_EQ(m.name, "mask/material0");
  EXPECT_FLOAT_EQ(m.alphaCutoff, 0.25f);
  ASSERT_EQ(m.alphaTexture.width, 8);
  // alpha = baseColorFactor.a x texture alpha: 0.5 where the checker is opaque, 0 elsewhere.
  EXPECT_EQ(m.alphaTexture.at(0, 0, 0) + m.alphaTexture.at(1, 0, 0), 0.5f);
  // uv' = offset + scale * uv (no rotation): (0, 1) -> (0.5, 4), (1, 0) -> (2.5, 0).
  ASSERT_EQ(o.uvs.size(), o.positions.size());
  EXPECT_EQ(o.uvs[0], glm::vec2(0.5f, 4.0f));
  EXPECT_EQ(o.uvs[2], glm::vec2(2.5f, 0.0f));
  // The BLEND primitive: the scene's default material (double-sided, opaque).
  EXPECT_EQ(o.triangleMaterial[2], 0u);
}

TEST_F(Gltf, SingleSidedAndDefaultMaterialsCullBackFaces) {
  GltfBuilder b = squareFile();
  b.node({{"mesh", 0}});
  b.scene({0});
  const Scene s = loadScene(b.write(dir(), "default"));
  const Material& m = s.materials[s.objects[0].triangleMaterial[0]];
  EXPECT_EQ(m.name, "default/default");
  EXPECT_FALSE(m.twoSided);
  EXPECT_FALSE(m.hasAlpha);
}

TEST_F(Gltf, RequiredExtensionsUrisAndTypesAreChecked) {
  GltfBuilder b = squareFile();
  b.node({{"mesh", 0}});
  b.scene({0});
  b.doc["extensionsUsed"] = {"EXT_unknown_optional"};
  EXPECT_EQ(loadScene(b.write(dir(), "optional")).triangleCount(), 2u);  // optional: ignored
  b.doc["extensionsRequired"] = {"KHR_lights_punctual", "EXT_meshopt_compression"};
  EXPECT_NE(inputErrorOf([&] { loadScene(b.write(dir(), "required")); })
                .find("required.gltf: /extensionsRequired/1: error: the file requires the extension "
                      "EXT_meshopt_compression, which shadowlab does not support"),
            std::string::npos);
  b.doc.erase("extensionsRequired");
  const std::string path = b.write(dir(), "remote");
  nlohmann::json doc = nlohmann::json::parse(std::ifstream(path));
  doc["buffers"][0]["uri"] = "https://example.com/remote.bin";
  std::ofstream(path) << doc.dump();
  EXPECT_NE(inputErrorOf([&] { loadScene(path); }).find("remote.gltf: /buffers/0/uri: error: got the URI"),
            std::string::npos);
  // An accessor past its buffer view, and a buffer view past its buffer.
  b.doc["accessors"][0]["count"] = 5;
  EXPECT_NE(
      inputErrorOf([&] { loadScene(b.write(dir(), "short")); })
          .find("short.gltf: /accessors/0: error: accessor 0 (POSITION of /meshes/0/primitives/0): needs bytes 0..60 "
                "of bufferView 0, which holds 48 bytes"),
      std::string::npos);
  b.doc["accessors"][0]["count"] = 4;
  b.doc["bufferViews"][1]["byteLength"] = 400;
  EXPECT_NE(
      inputErrorOf([&] { loadScene(b.write(dir(), "view")); }).find("view.gltf: /bufferViews/1: error: buffer view"),
      std::string::npos);
}

TEST_F(Gltf, AJsonWrapperKeepsItsCameraAndLightsAroundTheAsset) {
  GltfBuilder b = squareFile();
  b.node({{"mesh", 0}});
  b.scene({0});
  b.light({{"type", "point"}, {"name", "sun"}});
  b.doc["nodes"][0]["extensions"] = {{"KHR_lights_punctual", {{"light", 0}}}};
  const std::string path = b.write(dir(), "asset");
  const Scene s = loadScene(
      wrapper(path, R"(, "transform": {"translate": [0, 0, -2]})",
              R"(, "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "vfov_deg": 40, "width": 32, "height": 24},
                                       "lights": [{"type": "directional", "name": "sun", "elevation_deg": 45}])"));
  EXPECT_EQ(s.camera.width, 32);
  ASSERT_EQ(s.lights.size(), 2u);
  EXPECT_EQ(s.lights[0].name, "sun");
  EXPECT_EQ(s.lights[1].name, "sun_2");  // the glTF's light, renamed past the JSON one, moved by the transform
  EXPECT_EQ(s.lights[1].position, glm::vec3(0, 0, -2));
  EXPECT_EQ(s.objects[0].positions[0], glm::vec3(0, 0, -2));
  // Without a JSON camera and without a glTF camera: the framing camera looks at the bounds' center.
  const Scene f = loadScene(path);
  EXPECT_EQ(f.camera.lookAt, glm::vec3(0.5f, 0.5f, 0.0f));
}

TEST_F(Gltf, CamerasAreChosenByNameOrIndexAndNoZfarReachesPastTheBounds) {
  GltfBuilder b = squareFile();
  b.node({{"mesh", 0}});
  b.doc["cameras"] = {
      {{"name", "wide"}, {"type", "perspective"}, {"perspective", {{"yfov", 1.0}, {"znear", 0.5}, {"zfar", 50}}}},
      {{"name", "close up"},
       {"type", "perspective"},
       {"perspective", {{"yfov", 0.5}, {"znear", 0.25}, {"aspectRatio", 2.0}}}}};
  b.node({{"camera", 0}, {"translation", {0, 0, 10}}});
  b.node({{"camera", 1}, {"translation", {0.5, 0.5, 4}}});
  b.scene({0, 1, 2});
  const std::string path = b.write(dir(), "cams");
  const std::string lights = R"(, "lights": [{"type": "directional", "elevation_deg": 45}])";
  const Scene first = loadScene(path);  // the first perspective camera a node places
  EXPECT_EQ(first.camera.position, glm::vec3(0, 0, 10));
  EXPECT_FLOAT_EQ(first.camera.farPlane, 50.0f);
  const Scene named = loadScene(wrapper(path, ", \"camera\": \"close up\"", lights));
  EXPECT_EQ(named.camera.position, glm::vec3(0.5f, 0.5f, 4));
  EXPECT_FLOAT_EQ(named.camera.vfovDeg, float(0.5 * 180 / kPi));
  EXPECT_EQ(named.camera.width, 640);
  EXPECT_EQ(named.camera.height, 320);
  EXPECT_FLOAT_EQ(named.camera.nearPlane, 0.25f);
  // No zfar: twice the distance to the farthest corner of the bounds (the square's (0, 0, 0) and
  // (1, 1, 0) corners are both sqrt(0.5 + 16) away).
  EXPECT_FLOAT_EQ(named.camera.farPlane, 2 * std::sqrt(16.5f));
  EXPECT_EQ(loadScene(wrapper(path, ", \"camera\": 1", lights)).camera.position, named.camera.position);
  const std::string err = inputErrorOf([&] { loadScene(wrapper(path, ", \"camera\": \"tele\"", lights)); });
  EXPECT_NE(err.find("wrapper.json: /objects/0: error: no camera named \"tele\" in "), std::string::npos) << err;
  EXPECT_NE(err.find("expected one of \"wide\", \"close up\""), std::string::npos) << err;
  // A JSON camera and a glTF object's camera: one too many.
  const std::string both = inputErrorOf([&] {
    loadScene(wrapper(
        path, ", \"camera\": 0",
        lights +
            R"(, "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "vfov_deg": 40, "width": 32, "height": 24})"));
  });
  EXPECT_NE(both.find("wrapper.json: /camera: error: both a JSON camera and a glTF object's \"camera\""),
            std::string::npos)
      << both;
}

}  // namespace scenes_gltf_test
