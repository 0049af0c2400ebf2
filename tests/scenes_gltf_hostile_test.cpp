// glTF files that break the glTF 2.0 rules or reach outside their folder: each is an InputError
// (exit 2 in the CLI) naming the file and the JSON pointer of the problem, saying what was found and
// what was expected, and never quoting the bytes of a file it read.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/loader.h"
#include "support/gltf_builder.h"
#include "support/input_error.h"
#include "support/test_models.h"

namespace scenes_gltf_hostile_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using shadowlab::testing::GltfBuilder;
using shadowlab::testing::inputErrorOf;

namespace {

class GltfHostile : public ::testing::Test {
 protected:
  void SetUp() override {
    ::unsetenv("SHADOWLAB_ASSET_ROOT");  // the tests set it where they mean to
    dir_ = fs::temp_directory_path() / ("shadowlab_gltf_hostile_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    ::unsetenv("SHADOWLAB_ASSET_ROOT");
    fs::remove_all(dir_);
  }
  std::string dir() const { return dir_.string(); }
  fs::path dir_;
};

// A unit square in xy as two triangles under one node: a valid file to break one thing of.
GltfBuilder square() {
  GltfBuilder b;
  const int pos = b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  b.mesh(pos, b.indices16({0, 1, 2, 0, 2, 3}));
  b.node({{"mesh", 0}});
  b.scene({0});
  return b;
}

// `path`'s document with the buffer's uri replaced (the builder writes the uri itself).
void setBufferUri(const std::string& path, const std::string& uri) {
  nlohmann::json doc = nlohmann::json::parse(std::ifstream(path));
  doc["buffers"][0]["uri"] = uri;
  std::ofstream(path) << doc.dump();
}

// Expects `err` to contain `part`, printing the whole message otherwise.
#define EXPECT_HAS(err, part) EXPECT_NE((err).find(part), std::string::npos) << (err)

}  // namespace

// ----------------------------------------------------------------------------------------------
// Values glTF 2.0 forbids.

TEST_F(GltfHostile, AspectRatioZeroOrNegativeIsRefused) {
  GltfBuilder b = square();
  b.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}, {"aspectRatio", 0}}}}};
  b.node({{"camera", 0}, {"translation", {0, 0, 5}}});
  b.scene({0, 1});
  for (const int aspect : {0, -1}) {
    b.doc["cameras"][0]["perspective"]["aspectRatio"] = aspect;
    const std::string err = inputErrorOf([&] { loadScene(b.write(dir(), "aspect")); });
    EXPECT_HAS(err, "aspect.gltf: /cameras/0/perspective/aspectRatio: error: got " + std::to_string(aspect) +
                        "; expected a positive width / height ratio");
  }
  b.doc["cameras"][0]["perspective"]["aspectRatio"] = 2.0;
  EXPECT_EQ(loadScene(b.write(dir(), "aspect")).camera.height, 320);
}

TEST_F(GltfHostile, OnlyGltfTwoPointXIsRead) {
  GltfBuilder b = square();
  b.doc["asset"]["version"] = "3.0";
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "v3")); }),
             "v3.gltf: /asset/version: error: got \"3.0\"; expected \"2.x\"");
  b.doc["asset"]["version"] = "2.1";
  EXPECT_EQ(loadScene(b.write(dir(), "v21")).triangleCount(), 2u);
  b.doc["asset"]["minVersion"] = "2.1";
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "min")); }),
             "min.gltf: /asset/minVersion: error: got \"2.1\"; expected \"2.0\"");
}

TEST_F(GltfHostile, TrianglesNeedAMultipleOfThreeIndicesOrVertices) {
  GltfBuilder b;
  const int pos = b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  b.mesh(pos);                                   // 4 vertices, no indices
  b.mesh(pos, b.indices16({0, 1, 2, 0, 2}), 4);  // 5 indices
  b.node({{"mesh", 0}});
  b.scene({0});
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "verts")); }),
             "verts.gltf: /meshes/0/primitives/0/attributes/POSITION: error: accessor 0 holds 4 vertices for "
             "TRIANGLES without indices; expected a multiple of 3");
  b.doc["nodes"][0]["mesh"] = 1;
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "indices")); }),
             "indices.gltf: /meshes/1/primitives/0/indices: error: accessor 1 holds 5 indices for TRIANGLES; "
             "expected a multiple of 3");
}

TEST_F(GltfHostile, IncorrectVertexArraysCubeIsRefusedNotTruncated) {
  SHADOWLAB_REQUIRE_TEST_MODEL(path, "glTF2/IncorrectVertexArrays/Cube.gltf");
  const std::string err = inputErrorOf([&] { loadScene(path); });
  EXPECT_EQ(err.rfind(path + ": /meshes/1/primitives/0/attributes/POSITION: error: accessor 6 holds 35 vertices for "
                             "TRIANGLES without indices; expected a multiple of 3",
                      0),
            0u)
      << err;
}

TEST_F(GltfHostile, IntegerPositionsNeedKhrMeshQuantization) {
  GltfBuilder b;
  const uint8_t xyz[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0};
  b.mesh(b.accessor(b.view(xyz, sizeof xyz), 5121, 3, "VEC3"));
  b.node({{"mesh", 0}});
  b.scene({0});
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "bytes")); }),
             "bytes.gltf: /accessors/0/componentType: error: got 5121 (unsigned byte) for the POSITION of "
             "/meshes/0/primitives/0; expected 5126 (float), or KHR_mesh_quantization in extensionsUsed");
  b.doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  b.doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  const Scene s = loadScene(b.write(dir(), "quantized"));
  ASSERT_EQ(s.triangleCount(), 1u);
  EXPECT_EQ(s.objects[0].positions[2], glm::vec3(1, 1, 0));
}

TEST_F(GltfHostile, RotationsAreUnitQuaternions) {
  GltfBuilder b = square();
  for (const auto& [q, length] : std::vector<std::pair<nlohmann::json, const char*>>{
           {{0, 0, 0, 0}, "0"}, {{0, 0, 0, 2}, "2"}, {{0, 0.5, 0, 0.5}, "0.7071067811865476"}}) {
    b.doc["nodes"][0]["rotation"] = q;
    EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "rotation")); }),
               std::string("rotation.gltf: /nodes/0/rotation: error: got a quaternion of length ") + length +
                   "; expected a unit quaternion (length 1 within 0.001)");
  }
  // A quaternion normalized in float, as exporters write it.
  b.doc["nodes"][0]["rotation"] = {0, 0.70710677f, 0, 0.70710677f};
  EXPECT_EQ(loadScene(b.write(dir(), "rotation")).triangleCount(), 2u);
}

TEST_F(GltfHostile, TinygltfsChecksAreMadeFirstAtTheirPointers) {
  GltfBuilder b = square();
  b.doc["cameras"] = {{{"type", "orthographic"}, {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"znear", 0.1}}}}};
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "ortho")); }),
             "ortho.gltf: /cameras/0/orthographic: error: missing key \"zfar\"; expected xmag, ymag, zfar and znear");
  b.doc.erase("cameras");
  b.doc["accessors"][0].erase("count");
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "count")); }),
             "count.gltf: /accessors/0: error: missing key \"count\"; expected the number of elements");
  b.doc["accessors"][0]["count"] = 4;
  b.doc["accessors"][0]["type"] = "VEC7";
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "type")); }),
             "type.gltf: /accessors/0/type: error: got \"VEC7\"; expected SCALAR, VEC2");
  b.doc["accessors"][0]["type"] = "VEC3";
  b.doc["accessors"][0]["sparse"] = {{"count", 1}};
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "sparse")); }),
             "sparse.gltf: /accessors/0/sparse: error: missing key \"indices\"");
  b.doc["accessors"][0].erase("sparse");
  const nlohmann::json attributes = b.doc["meshes"][0]["primitives"][0]["attributes"];
  b.doc["meshes"][0]["primitives"][0].erase("attributes");
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "attributes")); }),
             "attributes.gltf: /meshes/0/primitives/0: error: missing key \"attributes\"");
  b.doc["meshes"][0]["primitives"][0]["attributes"] = attributes;
  b.doc["bufferViews"][0]["byteStride"] = 256;
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "stride")); }),
             "stride.gltf: /bufferViews/0/byteStride: error: got 256; expected a multiple of 4 in 4..252");
  b.doc["bufferViews"][0]["byteStride"] = 12;
  // A GLB whose buffer has no uri and whose BIN chunk is gone.
  const std::string glb = b.write(dir(), "nobin", GltfBuilder::Form::Binary);
  std::ifstream in(glb, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  uint32_t jsonLength;
  std::memcpy(&jsonLength, bytes.data() + 12, 4);
  bytes.resize(20 + jsonLength);
  const uint32_t total = uint32_t(bytes.size());
  std::memcpy(bytes.data() + 8, &total, 4);
  std::ofstream(glb, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  EXPECT_HAS(inputErrorOf([&] { loadScene(glb); }),
             "nobin.glb: /buffers/0: error: the buffer has no uri and the GLB file has no BIN chunk");
}

TEST_F(GltfHostile, ABadDataUriIsQuotedByAShortPrefixOnly) {
  GltfBuilder b = square();
  const std::string path = b.write(dir(), "data", GltfBuilder::Form::Embedded);
  const std::string body(4 << 20, '!');
  setBufferUri(path, "data:application/octet-stream;base64," + body);
  std::string err = inputErrorOf([&] { loadScene(path); });
  EXPECT_HAS(err,
             "data.gltf: /buffers/0/uri: error: the data: URI \"data:application/octet-stream;base64,!!!!!!!!!!!...");
  EXPECT_HAS(err, "is not valid base64");
  EXPECT_LT(err.size(), 400u) << err.substr(0, 400);
  setBufferUri(path, "data:text/html;base64,AAAA");
  err = inputErrorOf([&] { loadScene(path); });
  EXPECT_HAS(err,
             "data.gltf: /buffers/0/uri: error: got a data: URI starting \"data:text/html;base64,\"; expected one "
             "starting data:application/octet-stream;base64,");
  setBufferUri(path, "data:application/octet-stream;base64,AAAA");
  EXPECT_HAS(inputErrorOf([&] { loadScene(path); }),
             "data.gltf: /buffers/0/uri: error: the data: URI decodes to 3 bytes; expected byteLength 60 bytes");
}

TEST_F(GltfHostile, AnImageSaysWhatItsBytesAreAndWhatItsMimeTypeSays) {
  GltfBuilder b = square();
  std::ifstream png(std::string(SHADOWLAB_SOURCE_DIR) + "/scenes/data/gltf_checker_alpha.png", std::ios::binary);
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(png)), std::istreambuf_iterator<char>());
  b.doc["images"] = {{{"bufferView", b.view(bytes.data(), bytes.size())}, {"mimeType", "image/jpeg"}}};
  b.doc["textures"] = {{{"source", 0}}};
  b.doc["materials"] = {{{"alphaMode", "MASK"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  const std::vector<glm::vec2> uv = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  b.doc["meshes"][0]["primitives"][0]["material"] = 0;
  b.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = b.uvs(uv);
  EXPECT_HAS(
      inputErrorOf([&] { loadScene(b.write(dir(), "mime")); }),
      "mime.gltf: /images/0/mimeType: error: got \"image/jpeg\" for an image whose bytes are image/png; expected "
      "\"image/png\"");
  const char gif[] = "GIF89a\x01\x00\x01\x00\x00\x00\x00";
  b.doc["images"][0]["bufferView"] = b.view(gif, sizeof gif);
  b.doc["images"][0]["mimeType"] = "image/png";
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "gif")); }),
             "gif.gltf: /images/0: error: the image's 14 bytes are GIF (the mimeType \"image/png\"); expected PNG or "
             "JPEG bytes");
  b.doc["images"][0].erase("mimeType");
  EXPECT_HAS(inputErrorOf([&] { loadScene(b.write(dir(), "nomime")); }),
             "nomime.gltf: /images/0: error: missing key \"mimeType\"; expected \"image/png\" or \"image/jpeg\" beside "
             "a bufferView");
  b.doc["images"][0]["mimeType"] = "image/png";
  b.doc["images"][0]["bufferView"] = b.view(bytes.data(), bytes.size());
  EXPECT_TRUE(loadScene(b.write(dir(), "good")).materials.back().hasAlpha);
}

TEST_F(GltfHostile, AGltfCameraThatFailsIsCitedInTheGltfFile) {
  GltfBuilder b = square();
  b.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}};
  b.node({{"camera", 0}, {"translation", {3e38, 3e38, 3e38}}});
  b.scene({0, 1});
  const std::string err = inputErrorOf([&] { loadScene(b.write(dir(), "far")); });
  EXPECT_HAS(err, "far.gltf: /cameras/0: error: the camera's matrices or rays are not finite");
  EXPECT_EQ(err.find("/camera:"), std::string::npos) << err;
}

// ----------------------------------------------------------------------------------------------
// Files outside the glTF file's folder.

TEST_F(GltfHostile, BufferUrisOutsideTheFolderAreRefusedWithoutReadingThem) {
  GltfBuilder b = square();
  fs::create_directories(dir_ / "scene");
  const std::string path = b.write(dir() + "/scene", "escape");
  fs::create_symlink("/etc/passwd", dir_ / "scene" / "link.bin");
  std::ofstream(dir_ / "scenery.bin") << std::string(60, '\0');  // a sibling folder's prefix, not inside
  for (const std::string uri : {"../../../../../../../../etc/passwd", "..%2F..%2F..%2F..%2F..%2F..%2F..%2Fetc%2Fpasswd",
                                "/etc/passwd", "%2Fetc%2Fpasswd", "link.bin", "../scenery.bin"}) {
    SCOPED_TRACE(uri);
    setBufferUri(path, uri);
    const std::string err = inputErrorOf([&] { loadScene(path); });
    EXPECT_HAS(err, "escape.gltf: /buffers/0/uri: error: the URI names ");
    EXPECT_HAS(err, ", outside the glTF file's folder; expected a file inside that folder");
    EXPECT_EQ(err.find("root:"), std::string::npos) << err;  // nothing of /etc/passwd's text
  }
  // tinygltf decodes "%zz" to a NUL, which ends the path where the C library opens it: the checked
  // path and the opened path would differ.
  for (const std::string uri : {"../etc%zz/../scene/escape.bin", "../etc%00/../scene/escape.bin"}) {
    SCOPED_TRACE(uri);
    setBufferUri(path, uri);
    EXPECT_HAS(inputErrorOf([&] { loadScene(path); }),
               "escape.gltf: /buffers/0/uri: error: the URI decodes to a path holding a NUL character");
  }
  setBufferUri(path, "file:///etc/passwd");
  EXPECT_HAS(inputErrorOf([&] { loadScene(path); }),
             "escape.gltf: /buffers/0/uri: error: got the URI \"file:///etc/passwd\"; expected a data: URI or a "
             "relative file path");
  // An image URI, even one no material reads.
  setBufferUri(path, "escape.bin");
  nlohmann::json doc = nlohmann::json::parse(std::ifstream(path));
  doc["images"] = {{{"uri", "../../../../../../../etc/passwd"}}};
  std::ofstream(path) << doc.dump();
  EXPECT_HAS(inputErrorOf([&] { loadScene(path); }), "escape.gltf: /images/0/uri: error: the URI names /etc/passwd");
}

TEST_F(GltfHostile, AssetRootAllowsAWiderFolder) {
  GltfBuilder b = square();
  fs::create_directories(dir_ / "scene");
  fs::create_directories(dir_ / "shared");
  const std::string path = b.write(dir() + "/scene", "asset");
  fs::rename(dir_ / "scene" / "asset.bin", dir_ / "shared" / "asset.bin");
  setBufferUri(path, "../shared/asset.bin");
  EXPECT_HAS(inputErrorOf([&] { loadScene(path); }), "outside the glTF file's folder");
  ::setenv("SHADOWLAB_ASSET_ROOT", dir().c_str(), 1);
  EXPECT_EQ(loadScene(path).triangleCount(), 2u);
  // Still nothing outside both.
  setBufferUri(path, "/etc/passwd");
  EXPECT_HAS(inputErrorOf([&] { loadScene(path); }),
             "the URI names /etc/passwd, outside the glTF file's folder and outside SHADOWLAB_ASSET_ROOT");
}

TEST_F(GltfHostile, ABufferFileIsARegularFileOfItsByteLength) {
  GltfBuilder b = square();
  const std::string path = b.write(dir(), "sized");
  // A device inside an allowed root: refused before it is read (reading /dev/zero never ends).
  ::setenv("SHADOWLAB_ASSET_ROOT", "/dev", 1);
  setBufferUri(path, "/dev/zero");
  EXPECT_HAS(inputErrorOf([&] { loadScene(path); }),
             "sized.gltf: /buffers/0/uri: error: buffer file /dev/zero: a character device, not a regular file");
  setBufferUri(path, "sized.bin");
  std::ofstream(dir_ / "sized.bin") << std::string(48, '\0');
  EXPECT_HAS(inputErrorOf([&] { loadScene(path); }),
             "/buffers/0/uri: error: buffer file " + dir() + "/sized.bin holds 48 bytes; expected byteLength 60 bytes");
}

TEST_F(GltfHostile, AGltfPathThatIsNotAGltfFileSaysWhatItIs) {
  auto wrapper = [&](const std::string& gltf) {
    const std::string p = dir() + "/wrapper.json";
    std::ofstream(p) << R"({"objects": [{"type": "gltf", "name": "asset", "path": ")" << gltf
                     << R"("}], "lights": [{"type": "directional", "elevation_deg": 45}]})";
    return p;
  };
  EXPECT_HAS(inputErrorOf([&] { loadScene(wrapper("/dev/zero")); }),
             "wrapper.json: /objects/0/path: error: glTF file /dev/zero: a character device, not a regular file; "
             "expected a .gltf or .glb file");
  EXPECT_HAS(inputErrorOf([&] { loadScene(wrapper(dir())); }), "a directory, not a file");
  EXPECT_HAS(inputErrorOf([&] { loadScene(wrapper(dir() + "/missing.glb")); }), "missing.glb: not found");
  // Text that is not JSON: said so, without quoting it.
  const std::string passwd = inputErrorOf([&] { loadScene(wrapper("/etc/passwd")); });
  EXPECT_HAS(passwd, "/etc/passwd:1:1: error: not a glTF file: invalid JSON (syntax error");
  EXPECT_EQ(passwd.find("root"), std::string::npos) << passwd;
  EXPECT_EQ(passwd.find("last read"), std::string::npos) << passwd;
  // A number too large for a double (nlohmann's out_of_range, which once ended the process): its
  // line:col, as every JSON file of the project.
  std::ofstream(dir_ / "huge.gltf") << "{\"asset\": {\"version\": \"2.0\"},\n \"bufferViews\": [{\"byteLength\": 1e99918}]}";
  EXPECT_HAS(inputErrorOf([&] { loadScene(wrapper(dir() + "/huge.gltf")); }),
             "huge.gltf:2:33: error: not a glTF file: invalid JSON (number overflow parsing '1e99918'; expected a "
             "finite number");
  // A JSON scene where a glTF was expected.
  std::ofstream(dir_ / "scene.json") << R"({"objects": [], "lights": []})";
  EXPECT_HAS(inputErrorOf([&] { loadScene(wrapper(dir() + "/scene.json")); }),
             "scene.json: error: missing key \"asset\"; expected a glTF 2.0 \"asset\" object (is this a glTF file?)");
  // A .glb path that is a device: not read.
  fs::create_symlink("/dev/zero", dir_ / "zero.glb");
  EXPECT_HAS(inputErrorOf([&] { loadScene(dir() + "/zero.glb"); }), "a character device, not a regular file");
}

// ----------------------------------------------------------------------------------------------
// Overrides.

TEST_F(GltfHostile, OverrideErrorsNameTheArgumentFirst) {
  GltfBuilder b = square();
  b.doc["cameras"] = {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}};
  b.node({{"camera", 0}, {"translation", {0, 0, 5}}});
  b.scene({0, 1});
  const std::string path = b.write(dir(), "set");
  EXPECT_HAS(
      inputErrorOf([&] {
        loadScene(path,
                  {{"/cameras/0/perspective/aspectRatio", 0, "--set scene:/cameras/0/perspective/aspectRatio=0"}});
      }),
      "--set scene:/cameras/0/perspective/aspectRatio=0: error: got 0; expected a positive width / height ratio (" +
          path + ": /cameras/0/perspective/aspectRatio)");
  EXPECT_HAS(inputErrorOf([&] {
               loadScene(path, {{"/nodes/7/scale", {1, 1, 1}, "--set scene:/nodes/7/scale=[1,1,1]"}});
             }),
             "--set scene:/nodes/7/scale=[1,1,1]: error: no such value in the glTF document; expected a pointer to an "
             "existing value (" +
                 path + ": override /nodes/7/scale)");
  // Without an origin (a library call), the file and place come first as before.
  EXPECT_HAS(inputErrorOf([&] {
               loadScene(path, {{"/cameras/0/perspective/aspectRatio", -2}});
             }),
             path + ": /cameras/0/perspective/aspectRatio: error: got -2");
}

TEST_F(GltfHostile, CameraWidthAndHeightSetTheImageSizeOfAGltfCamera) {
  GltfBuilder b = square();
  const std::string path = b.write(dir(), "sized");  // no camera: the framing camera, 640x480
  const Scene plain = loadScene(path);
  const Scene small = loadScene(path, {{"/camera/width", 320, "--set scene:/camera/width=320"},
                                       {"/camera/height", 200, "--set scene:/camera/height=200"}});
  EXPECT_EQ(small.camera.width, 320);
  EXPECT_EQ(small.camera.height, 200);
  EXPECT_EQ(small.camera.position, plain.camera.position);
  EXPECT_NE(small.hash, plain.hash);  // another image size is another reference
  EXPECT_HAS(inputErrorOf([&] {
               loadScene(path, {{"/camera/width", 0, "--set scene:/camera/width=0"}});
             }),
             "--set scene:/camera/width=0: error: got 0; expected an integer 1..16384 (the largest image every Vulkan "
             "device must support) (the image size of " +
                 path + ")");
  // A JSON scene without a camera around the glTF: the same.
  const std::string wrapper = dir() + "/wrapper.json";
  std::ofstream(wrapper) << R"({"objects": [{"type": "gltf", "name": "asset", "path": "sized.gltf"}],
                               "lights": [{"type": "directional", "elevation_deg": 45}]})";
  EXPECT_EQ(loadScene(wrapper, {{"/camera/height", 100, "--set scene:/camera/height=100"}}).camera.height, 100);
}

// The fuzz target's regression inputs (tests/fuzz/regressions/gltf/), replayed the way fuzz_gltf.cpp
// does (the input as m.gltf, or m.glb after the GLB magic, beside a 96-byte m.bin): each loads or is
// an InputError, and none quotes a file it reached for.
TEST_F(GltfHostile, FuzzRegressionInputsAreInputErrorsOrScenes) {
  const fs::path regressions = fs::path(SHADOWLAB_SOURCE_DIR) / "tests/fuzz/regressions/gltf";
  std::ofstream(dir_ / "m.bin", std::ios::binary) << std::string(96, '\0');
  size_t replayed = 0;
  for (const auto& entry : fs::directory_iterator(regressions)) {
    SCOPED_TRACE(entry.path().filename().string());
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const fs::path input = dir_ / (bytes.rfind("glTF", 0) == 0 ? "m.glb" : "m.gltf");
    std::ofstream(input, std::ios::binary) << bytes;
    try {
      loadScene(input.string());
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).find("root:"), std::string::npos) << e.what();
    }
    fs::remove(input);
    ++replayed;
  }
  EXPECT_GE(replayed, 15u);
}

TEST_F(GltfHostile, ASceneFileThatIsADeviceIsNotRead) {
  // Reading /dev/zero as a scene never ends: refused by what it is.
  EXPECT_HAS(inputErrorOf([&] { loadScene("/dev/zero"); }),
             "/dev/zero: error: cannot read the scene file: a character device, not a regular file");
  fs::create_symlink("/dev/zero", dir_ / "zero.gltf");
  EXPECT_HAS(inputErrorOf([&] { loadScene(dir() + "/zero.gltf"); }), "a character device, not a regular file");
}

}  // namespace scenes_gltf_hostile_test
