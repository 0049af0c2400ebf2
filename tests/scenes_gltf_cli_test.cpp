// glTF files through the real binary: real assets (assimp-testmodels) run `shadowlab run` end to end
// inside a JSON scene that adds ground and sun; a glTF 1.0 file and malformed files exit 2 with a
// message naming the file and the problem, and write nothing.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "support/cli.h"
#include "support/gltf_builder.h"
#include "support/test_models.h"

namespace scenes_gltf_cli_test {

namespace fs = std::filesystem;
using shadowlab::testing::CliRun;
using shadowlab::testing::freshTempDir;
using shadowlab::testing::GltfBuilder;
using shadowlab::testing::runShadowlab;

namespace {

// A JSON scene around the asset: a ground under its bounds and a sun, a small camera.
std::string wrap(const fs::path& dir, const std::string& asset, const std::string& transform,
                 const std::string& camera) {
  const fs::path p = dir / "wrapped.json";
  std::ofstream(p) << R"({"camera": )" << camera << R"(,
    "objects": [{"type": "plane", "name": "ground", "size": [4000, 4000]},
                {"type": "gltf", "name": "asset", "path": ")"
                   << asset << R"(", "transform": )" << transform << R"(}],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 50, "azimuth_deg": 30}]})";
  return p.string();
}

// The width and height of a PNG (its IHDR chunk, big-endian at bytes 16..23).
std::pair<uint32_t, uint32_t> pngSize(const fs::path& png) {
  std::ifstream in(png, std::ios::binary);
  unsigned char b[24] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  auto be = [&](int at) {
    return uint32_t(b[at]) << 24 | uint32_t(b[at + 1]) << 16 | uint32_t(b[at + 2]) << 8 | b[at + 3];
  };
  return {be(16), be(20)};
}

}  // namespace

TEST(GltfCli, SetCameraWidthAndHeightSizeTheImageOfAGltfScene) {
  const fs::path dir = freshTempDir("gltf_cli_size");
  GltfBuilder b;
  b.mesh(b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  const std::string glb = b.write(dir.string(), "square", GltfBuilder::Form::Binary);
  const CliRun r =
      runShadowlab("reference '" + glb + "' --set scene:/camera/width=320 --set scene:/camera/height=240 -o '" +
                       (dir / "out").string() + "'",
                   dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json meta = nlohmann::json::parse(std::ifstream(dir / "out" / "reference.json"));
  EXPECT_EQ(meta["width"], 320);
  EXPECT_EQ(meta["height"], 240);
  EXPECT_EQ(pngSize(dir / "out" / "reference.png"), std::make_pair(320u, 240u));
  // A JSON scene without a camera around the glTF: its camera is the glTF's, sized the same way.
  std::ofstream(dir / "wrapper.json") << R"({"objects": [{"type": "gltf", "name": "square", "path": "square.glb"}],
    "lights": [{"type": "directional", "elevation_deg": 45}]})";
  const CliRun w = runShadowlab("reference '" + (dir / "wrapper.json").string() +
                                    "' --set scene:/camera/width=64 -o '" + (dir / "wrapped").string() + "'",
                                dir);
  ASSERT_EQ(w.code, 0) << w.err;
  EXPECT_EQ(pngSize(dir / "wrapped" / "reference.png"), std::make_pair(64u, 480u));
  // A bad size names the argument, and nothing is written.
  const CliRun bad =
      runShadowlab("reference '" + glb + "' --set scene:/camera/width=0 -o '" + (dir / "bad").string() + "'", dir);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_EQ(bad.err.rfind("--set scene:/camera/width=0: error: got 0; expected an integer 1..16384", 0), 0u) << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  fs::remove_all(dir);
}

TEST(GltfCli, ABufferOutsideTheFolderExitsTwoWithoutQuotingItAndWritesNothing) {
  const fs::path dir = freshTempDir("gltf_cli_escape");
  GltfBuilder b;
  b.mesh(b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));
  b.node({{"mesh", 0}});
  b.scene({0});
  const std::string path = b.write(dir.string(), "escape");
  nlohmann::json doc = nlohmann::json::parse(std::ifstream(path));
  for (const std::string uri :
       {"../../../../../../../../etc/passwd", "..%2F..%2F..%2F..%2F..%2F..%2F..%2Fetc%2Fpasswd"}) {
    doc["buffers"][0]["uri"] = uri;
    std::ofstream(path) << doc.dump();
    const CliRun r = runShadowlab("reference '" + path + "' -o '" + (dir / "out").string() + "'", dir);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(
        r.err.rfind(path + ": /buffers/0/uri: error: the URI names /etc/passwd, outside the glTF file's folder", 0), 0u)
        << r.err;
    EXPECT_EQ(r.err.find("root:"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  fs::remove_all(dir);
}

TEST(GltfCli, TwoCylinderEngineRunsEndToEndInsideAJsonScene) {
  SHADOWLAB_REQUIRE_TEST_MODEL(asset, "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
  const fs::path dir = freshTempDir("gltf_cli_engine");
  // The engine spans about 800 units around its origin; lift it above the ground at y = 0.
  const std::string scene = wrap(
      dir, asset, R"({"translate": [0, 300, 0]})",
      R"({"position": [900, 900, 1300], "look_at": [0, 200, 0], "vfov_deg": 45, "width": 96, "height": 64, "near": 1, "far": 5000})");
  const CliRun r = runShadowlab("run '" + scene + "' -o '" + (dir / "out").string() + "'", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json metrics = nlohmann::json::parse(std::ifstream(dir / "out" / "metrics.json"));
  EXPECT_TRUE(metrics.is_object());
  fs::remove_all(dir);
}

TEST(GltfCli, GltfOneCesiumMilkTruckExitsTwoAndWritesNothing) {
  SHADOWLAB_REQUIRE_TEST_MODEL(asset, "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf");
  const fs::path dir = freshTempDir("gltf_cli_truck");
  const std::string scene =
      wrap(dir, asset, R"({"translate": [0, 0, 0]})",
           R"({"position": [5, 4, 8], "look_at": [0, 1, 0], "vfov_deg": 45, "width": 64, "height": 48})");
  const CliRun r = runShadowlab("run '" + scene + "' -o '" + (dir / "out").string() + "'", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("CesiumMilkTruck.gltf: /asset/version: error: glTF 1.0 is not supported; convert to glTF 2.0"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

TEST(GltfCli, MalformedFilesExitTwoNamingTheFileAndWriteNothing) {
  const fs::path dir = freshTempDir("gltf_cli_bad");
  for (const char* rel : {"glTF2/RecursiveNodes/RecursiveNodes.gltf", "glTF2/IndexOutOfRange/IndexOutOfRange.gltf",
                          "glTF2/MissingBin/BoxTextured.gltf", "glTF2/draco/2CylinderEngine.gltf",
                          "glTF2/IncorrectVertexArrays/Cube.gltf"}) {
    SCOPED_TRACE(rel);
    SHADOWLAB_REQUIRE_TEST_MODEL(asset, rel);
    const CliRun r = runShadowlab("reference '" + asset + "' -o '" + (dir / "out").string() + "'", dir);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.find(asset + ": /"), 0u) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  fs::remove_all(dir);
}

TEST(GltfCli, AGltfPathIsASceneForScenesCheck) {
  SHADOWLAB_REQUIRE_TEST_MODEL(asset, "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
  const fs::path dir = freshTempDir("gltf_cli_path");
  const CliRun r = runShadowlab("scenes --check '" + asset + "'", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("ok: 1 objects, 12 triangles, 1 lights"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("BoxTextured.glb: warning: no KHR_lights_punctual light"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

TEST(GltfCli, AGltfPathRunsSweepsWithOverridesAndRefusesALightPath) {
  SHADOWLAB_REQUIRE_TEST_MODEL(asset, "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
  const fs::path dir = freshTempDir("gltf_cli_sweep");
  std::ofstream(dir / "sweep.json") << R"({"scenes": [")" << asset << R"("], "grid": {"map.size": [256]}})";
  // scene:/pointer addresses the glTF document: the box's root node moved up by 0.5.
  const CliRun r = runShadowlab("sweep --sweep '" + (dir / "sweep.json").string() +
                                    "' --grid scene:/nodes/0/matrix/13=0,0.5 --no-report --cache '" +
                                    (dir / "cache").string() + "' -o '" + (dir / "out").string() + "'",
                                dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json results = nlohmann::json::parse(std::ifstream(dir / "out" / "results.json"));
  ASSERT_EQ(results["rows"].size(), 2u) << results.dump();
  // The pointer is resolved in the glTF document: one it lacks is an error naming the --grid
  // argument first, then the file and the pointer.
  const CliRun bad =
      runShadowlab("sweep --sweep '" + (dir / "sweep.json").string() +
                       "' --grid scene:/nodes/9/matrix/13=0.5 --no-report -o '" + (dir / "bad").string() + "'",
                   dir);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--grid scene:/nodes/9/matrix/13=0.5: error: no such value in the glTF document; expected a "
                         "pointer to an existing value (" +
                         asset + ": override /nodes/9/matrix/13)"),
            std::string::npos)
      << bad.err;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  const CliRun s = runShadowlab(
      "stability '" + asset + "' --light-path elevation_deg=60:10:3 -o '" + (dir / "stability").string() + "'", dir);
  EXPECT_EQ(s.code, 2) << s.err;
  EXPECT_NE(s.err.find("--light-path: error: scene " + asset + " is a glTF file"), std::string::npos) << s.err;
  EXPECT_FALSE(fs::exists(dir / "stability"));
  fs::remove_all(dir);
}

}  // namespace scenes_gltf_cli_test
