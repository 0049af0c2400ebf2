// `shadowlab export`: every bundled scene written as a .glb and loaded back is the same scene (the
// same triangles bit for bit, ids, names, materials, lights, camera rays and camera hash) and traces
// the same truth (hit, object_id and every light's vis identical on a 160x90 image). The shadowlab
// extras the loader learns to read are checked like any other input, and a file whose standard
// values an editor changed takes those over the extras. The CLI writes the file or nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/gltf_export.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"
#include "support/cli.h"

namespace reference_gltf_export_test {

namespace fs = std::filesystem;
using namespace shadowlab;
using nlohmann::json;
using shadowlab::testing::CliRun;
using shadowlab::testing::freshTempDir;
using shadowlab::testing::runShadowlab;

namespace {

bool sameBits(glm::vec3 a, glm::vec3 b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool sameBits(glm::vec2 a, glm::vec2 b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

Scene loadSmall(const std::string& path) { return loadScene(path, {{"/camera/width", 160}, {"/camera/height", 90}}); }

std::string exportTo(const Scene& scene, const fs::path& file) {
  writeFileAtomic(file.string(), exportGlb(scene, "shadowlab test").glb);
  return file.string();
}

// The JSON chunk of a GLB, and a GLB with the same BIN chunk around new JSON.
json glbJson(const std::string& glb) {
  uint32_t len;
  std::memcpy(&len, glb.data() + 12, 4);
  return json::parse(glb.substr(20, len));
}
std::string withJson(const std::string& glb, const json& doc) {
  uint32_t len;
  std::memcpy(&len, glb.data() + 12, 4);
  const std::string binChunk = glb.substr(20 + len);
  std::string text = doc.dump();
  while (text.size() % 4) text.push_back(' ');
  std::string out = "glTF";
  auto put = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  put(2);
  put(uint32_t(12 + 8 + text.size() + binChunk.size()));
  put(uint32_t(text.size()));
  out += "JSON" + text + binChunk;
  return out;
}

// Every field that decides the truth, compared exactly; `what` names the scene in failures.
void expectSameScene(const Scene& a, const Scene& b, const std::string& what) {
  ASSERT_EQ(a.objects.size(), b.objects.size()) << what;
  for (size_t i = 0; i < a.objects.size(); ++i) {
    const Object &oa = a.objects[i], &ob = b.objects[i];
    EXPECT_EQ(oa.name, ob.name) << what;
    EXPECT_EQ(oa.id, ob.id) << what << " " << oa.name;
    EXPECT_EQ(oa.castsShadow, ob.castsShadow) << what << " " << oa.name;
    ASSERT_EQ(oa.triangles.size(), ob.triangles.size()) << what << " " << oa.name;
    size_t badPositions = 0, badMaterials = 0, badUvs = 0;
    for (size_t t = 0; t < oa.triangles.size(); ++t) {
      const Material &ma = a.materials[oa.triangleMaterial[t]], &mb = b.materials[ob.triangleMaterial[t]];
      const bool sameMaterial =
          ma.twoSided == mb.twoSided && ma.hasAlpha == mb.hasAlpha &&
          (!ma.hasAlpha ||
           (sameBits(ma.alphaCutoff, mb.alphaCutoff) && ma.alphaTexture.width == mb.alphaTexture.width &&
            ma.alphaTexture.height == mb.alphaTexture.height && ma.alphaTexture.pixels == mb.alphaTexture.pixels));
      badMaterials += !sameMaterial;
      for (int k = 0; k < 3; ++k) {
        badPositions += !sameBits(oa.positions[oa.triangles[t][k]], ob.positions[ob.triangles[t][k]]);
        if (ma.hasAlpha) badUvs += !sameBits(oa.uvs[oa.triangles[t][k]], ob.uvs[ob.triangles[t][k]]);
      }
    }
    EXPECT_EQ(badPositions, 0u) << what << " " << oa.name << ": triangle corners whose position bits differ";
    EXPECT_EQ(badMaterials, 0u) << what << " " << oa.name << ": triangles whose material differs";
    EXPECT_EQ(badUvs, 0u) << what << " " << oa.name << ": alpha-tested corners whose uv bits differ";
  }
  ASSERT_EQ(a.lights.size(), b.lights.size()) << what;
  for (size_t i = 0; i < a.lights.size(); ++i) {
    const Light &la = a.lights[i], &lb = b.lights[i];
    EXPECT_EQ(la.name, lb.name) << what;
    EXPECT_EQ(la.type, lb.type) << what << " " << la.name;
    EXPECT_TRUE(sameBits(la.direction, lb.direction)) << what << " " << la.name;
    if (la.type != LightType::Directional) {
      EXPECT_TRUE(sameBits(la.position, lb.position)) << what << " " << la.name;
      EXPECT_TRUE(sameBits(la.nearPlane, lb.nearPlane)) << what << " " << la.name;
      EXPECT_TRUE(sameBits(la.radius, lb.radius)) << what << " " << la.name;
    }
    if (la.type == LightType::Spot) {
      EXPECT_TRUE(sameBits(la.coneDeg, lb.coneDeg)) << what << " " << la.name;
    }
    EXPECT_TRUE(sameBits(la.angularDiameterDeg, lb.angularDiameterDeg)) << what << " " << la.name;
  }
  const Camera &ca = a.camera, &cb = b.camera;
  EXPECT_EQ(ca.hash(), cb.hash()) << what;
  EXPECT_EQ(ca.projection, cb.projection) << what;
  EXPECT_TRUE(sameBits(ca.nearPlane, cb.nearPlane) && sameBits(ca.farPlane, cb.farPlane)) << what;
  for (const glm::vec2 px :
       {glm::vec2(0.5f, 0.5f), glm::vec2(80.5f, 45.5f), glm::vec2(159.5f, 89.5f), glm::vec2(17.25f, 71.75f)}) {
    EXPECT_TRUE(sameBits(ca.rayDirection(px.x, px.y), cb.rayDirection(px.x, px.y))) << what << " at " << px.x;
    EXPECT_TRUE(sameBits(ca.rayOrigin(px.x, px.y), cb.rayOrigin(px.x, px.y))) << what << " at " << px.x;
  }
}

void expectSamePlane(const Frame& a, const Frame& b, const std::string& name, const std::string& what) {
  ASSERT_TRUE(a.has(name) && b.has(name)) << what << ": " << name;
  const std::vector<float>&pa = a.get(name), &pb = b.get(name);
  ASSERT_EQ(pa.size(), pb.size());
  size_t differ = 0;
  for (size_t i = 0; i < pa.size(); ++i) differ += !sameBits(pa[i], pb[i]);
  EXPECT_EQ(differ, 0u) << what << ": pixels of " << name << " that differ";
}

}  // namespace

TEST(GltfExport, EveryBundledSceneRoundTripsToTheSameTruth) {
  const fs::path dir = freshTempDir("gltf_export_round_trip");
  const std::vector<std::string> names = bundledSceneNames();
  ASSERT_GE(names.size(), 9u);
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    const Scene a = loadSmall(resolveScenePath(name));
    const Scene b = loadScene(exportTo(a, dir / (name + ".glb")));
    expectSameScene(a, b, name);
    // Projectors are not exported (a note says so): the truth is compared with them left out.
    Scene aLit = a;
    aLit.projectors.clear();
    ReferenceOptions options;
    options.lightSamples = 16;
    const Frame fa = renderReference(aLit, options), fb = renderReference(b, options);
    ASSERT_EQ(fa.width, 160);
    ASSERT_EQ(fb.width, 160);
    ASSERT_EQ(fb.height, 90);
    expectSamePlane(fa, fb, "hit", name);
    expectSamePlane(fa, fb, "object_id", name);
    for (const Light& l : a.lights) expectSamePlane(fa, fb, "light." + l.name + ".vis", name);
    // The truth is not trivially equal: something is hit and something is in shadow.
    const std::vector<float>& vis = fa.get("light." + a.lights.front().name + ".vis");
    const std::vector<float>& hit = fa.get("hit");
    size_t hits = 0, shadowed = 0;
    for (size_t i = 0; i < vis.size(); ++i) hits += hit[i] > 0, shadowed += hit[i] > 0 && vis[i] < 1;
    EXPECT_GT(hits, 0u);
    EXPECT_GT(shadowed, 0u);
    // Exporting the loaded export again gives the same scene again.
    expectSameScene(b, loadScene(exportTo(b, dir / (name + "_again.glb"))), name + " (again)");
  }
}

// The floats of accessor `a` (tightly packed, as the exporter writes them) from the BIN chunk.
std::vector<float> accessorFloats(const std::string& glb, const json& doc, int a) {
  uint32_t jsonLen;
  std::memcpy(&jsonLen, glb.data() + 12, 4);
  const size_t bin = 20 + jsonLen + 8;
  const json& acc = doc["accessors"][size_t(a)];
  const json& view = doc["bufferViews"][acc["bufferView"].get<size_t>()];
  const size_t n = acc["count"].get<size_t>() * (acc["type"] == "VEC3" ? 3 : acc["type"] == "VEC2" ? 2 : 1);
  std::vector<float> out(n);
  std::memcpy(out.data(), glb.data() + bin + view["byteOffset"].get<size_t>(), n * 4);
  return out;
}

TEST(GltfExport, NormalsAreUnitFaceNormalsAndBoundsHoldThePositions) {
  const GltfExport e = exportGlb(loadSmall(resolveScenePath("sphere_on_plane")), "shadowlab test");
  const json doc = glbJson(e.glb);
  size_t triangles = 0;
  for (const json& m : doc["meshes"])
    for (const json& p : m["primitives"]) {
      const json& posAcc = doc["accessors"][p["attributes"]["POSITION"].get<size_t>()];
      const std::vector<float> pos = accessorFloats(e.glb, doc, p["attributes"]["POSITION"].get<int>());
      const std::vector<float> nrm = accessorFloats(e.glb, doc, p["attributes"]["NORMAL"].get<int>());
      ASSERT_EQ(pos.size(), nrm.size());
      for (size_t v = 0; v < pos.size(); v += 3)
        for (int k = 0; k < 3; ++k) {
          ASSERT_GE(pos[v + k], posAcc["min"][k].get<float>());
          ASSERT_LE(pos[v + k], posAcc["max"][k].get<float>());
        }
      for (size_t t = 0; t < pos.size(); t += 9, ++triangles) {
        const glm::dvec3 a(pos[t], pos[t + 1], pos[t + 2]), b(pos[t + 3], pos[t + 4], pos[t + 5]),
            c(pos[t + 6], pos[t + 7], pos[t + 8]);
        const glm::dvec3 n(nrm[t], nrm[t + 1], nrm[t + 2]);
        ASSERT_NEAR(glm::length(n), 1.0, 1e-6);
        // The face normal: perpendicular to the edges, on the counter-clockwise side (front face).
        const glm::dvec3 cross = glm::cross(b - a, c - a);
        if (glm::length(cross) > 1e-12) {
          ASSERT_GT(glm::dot(glm::normalize(cross), n), 1 - 1e-6);
        }
        for (int k = 3; k < 9; k += 3) ASSERT_EQ(nrm[t + k], nrm[t]);  // flat: one normal per face
      }
    }
  EXPECT_EQ(triangles, 65026u);
}

TEST(GltfExport, TheFileCarriesWhatEnginesNeed) {
  const Scene scene = loadSmall(resolveScenePath("alpha_fence"));
  const GltfExport e = exportGlb(scene, "shadowlab 9.9.9");
  const json doc = glbJson(e.glb);
  EXPECT_EQ(doc["asset"]["version"], "2.0");
  EXPECT_EQ(doc["asset"]["generator"], "shadowlab 9.9.9");
  EXPECT_EQ(doc["extensionsUsed"], json::array({"KHR_lights_punctual"}));
  ASSERT_EQ(doc["meshes"].size(), scene.objects.size());
  size_t normals = 0;
  for (const json& m : doc["meshes"])
    for (const json& p : m["primitives"]) {
      ASSERT_TRUE(p["attributes"].contains("NORMAL"));
      ASSERT_TRUE(p.contains("indices"));
      ++normals;
    }
  EXPECT_GT(normals, 0u);
  // The fence's material: MASK with its cutoff, a PNG in a buffer view, sampled NEAREST / REPEAT.
  bool mask = false;
  for (const json& m : doc["materials"])
    if (m.value("alphaMode", "") == "MASK") {
      mask = true;
      EXPECT_EQ(m["alphaCutoff"].get<double>(), 0.5);
      EXPECT_TRUE(m.contains("doubleSided"));
    }
  EXPECT_TRUE(mask);
  ASSERT_EQ(doc["images"].size(), 1u);
  EXPECT_EQ(doc["images"][0]["mimeType"], "image/png");
  EXPECT_TRUE(doc["images"][0].contains("bufferView"));
  EXPECT_EQ(doc["samplers"][0]["magFilter"], 9728);
  EXPECT_EQ(doc["samplers"][0]["minFilter"], 9728);
  EXPECT_EQ(doc["samplers"][0]["wrapS"], 10497);
  EXPECT_EQ(doc["samplers"][0]["wrapT"], 10497);
  const json& cam = doc["cameras"][0]["perspective"];
  EXPECT_DOUBLE_EQ(cam["aspectRatio"].get<double>(), 160.0 / 90.0);
  EXPECT_NEAR(cam["yfov"].get<double>(), scene.camera.vfovDeg * M_PI / 180.0, 1e-12);
}

TEST(GltfExport, SpotConeAndNotesAreWrittenDown) {
  const fs::path dir = freshTempDir("gltf_export_spot");
  // A spot light, a sized point light that casts from a clear spot, a projector and an object
  // that casts no shadow: the parts glTF has no field for are named in the notes and asset.extras.
  std::ofstream(dir / "spot.json")
      << R"({"camera": {"position": [0, 3, 6], "look_at": [0, 0, 0], "vfov_deg": 50, "width": 64,
      "height": 48},
    "objects": [{"type": "plane", "name": "ground", "size": [10, 10]},
                {"type": "box", "name": "crate", "size": [1, 1, 1], "casts_shadow": false,
                 "transform": {"translate": [0, 0.5, 0]}}],
    "lights": [{"type": "spot", "name": "lamp", "position": [1, 4, 1], "look_at": [0, 0, 0], "cone_deg": 50},
               {"type": "point", "name": "bulb", "position": [-2, 3, 0], "radius": 0.25, "near": 0.2}],
    "projectors": [{"name": "slide", "position": [0, 4, 1], "look_at": [0, 0, 0], "fov_deg": 30, "image": "../img.png"}]})";
  // The projector's image: any PNG (the exporter never reads it, the loader does).
  {
    std::vector<uint8_t> rgb(4 * 4 * 3, 128);
    writeRgbPng((dir.parent_path() / "img.png").string(), 4, 4, rgb);
  }
  const Scene a = loadScene((dir / "spot.json").string());
  const GltfExport e = exportGlb(a, "shadowlab test");
  const json doc = glbJson(e.glb);
  const json& lamp = doc["extensions"]["KHR_lights_punctual"]["lights"][0];
  EXPECT_EQ(lamp["type"], "spot");
  const double outer = lamp["spot"]["outerConeAngle"].get<double>();
  EXPECT_NEAR(outer, 25.0 * M_PI / 180.0, 1e-7);
  EXPECT_LT(lamp["spot"]["innerConeAngle"].get<double>(), outer);
  EXPECT_GT(lamp["spot"]["innerConeAngle"].get<double>(), outer * (1 - 1e-15));
  const json notes = doc["asset"]["extras"]["shadowlab"]["not_exported"];
  ASSERT_EQ(notes.size(), e.notes.size());
  std::string all;
  for (const auto& n : e.notes) all += n + "\n";
  EXPECT_NE(all.find("projector \"slide\""), std::string::npos) << all;
  EXPECT_NE(all.find("object \"crate\": casts no shadow"), std::string::npos) << all;
  EXPECT_NE(all.find("light \"bulb\": its radius"), std::string::npos) << all;
  writeFileAtomic((dir / "spot.glb").string(), e.glb);
  const Scene b = loadScene((dir / "spot.glb").string());
  expectSameScene(a, b, "spot");
  EXPECT_FALSE(b.objects[1].castsShadow);
  EXPECT_TRUE(b.projectors.empty());
  Scene aLit = a;
  aLit.projectors.clear();
  ReferenceOptions options;
  options.lightSamples = 16;
  const Frame fa = renderReference(aLit, options), fb = renderReference(b, options);
  expectSamePlane(fa, fb, "hit", "spot");
  expectSamePlane(fa, fb, "object_id", "spot");
  expectSamePlane(fa, fb, "light.lamp.vis", "spot");
  expectSamePlane(fa, fb, "light.bulb.vis", "spot");
  fs::remove(dir.parent_path() / "img.png");
}

TEST(GltfExport, AnOrthographicCameraRoundTrips) {
  const fs::path dir = freshTempDir("gltf_export_ortho");
  std::ofstream(dir / "ortho.json") << R"({"camera": {"projection": "orthographic", "position": [2, 5, 4],
      "look_at": [0, 0, 0], "up": [0.1, 1, 0], "ortho_height": 6.5, "width": 96, "height": 40, "near": 0.5, "far": 40},
    "objects": [{"type": "plane", "name": "ground", "size": [10, 10]},
                {"type": "sphere", "name": "ball", "radius": 0.7, "segments": 24, "rings": 12,
                 "transform": {"translate": [0, 1, 0]}}],
    "lights": [{"type": "directional", "name": "sun", "elevation_deg": 90}]})";
  const Scene a = loadScene((dir / "ortho.json").string());
  const GltfExport e = exportGlb(a, "shadowlab test");
  const json cam = glbJson(e.glb)["cameras"][0];
  EXPECT_EQ(cam["type"], "orthographic");
  EXPECT_EQ(cam["orthographic"]["ymag"].get<double>(), 3.25);
  EXPECT_DOUBLE_EQ(cam["orthographic"]["xmag"].get<double>(), 3.25 * 96 / 40);
  writeFileAtomic((dir / "ortho.glb").string(), e.glb);
  const Scene b = loadScene((dir / "ortho.glb").string());
  EXPECT_TRUE(b.camera.orthographic());
  expectSameScene(a, b, "ortho");
  const Frame fa = renderReference(a, {}), fb = renderReference(b, {});
  expectSamePlane(fa, fb, "hit", "ortho");
  expectSamePlane(fa, fb, "object_id", "ortho");
  expectSamePlane(fa, fb, "light.sun.vis", "ortho");
}

TEST(GltfExport, ExtrasThatDisagreeWithTheNodesLoseToThem) {
  const fs::path dir = freshTempDir("gltf_export_edited");
  const Scene a = loadSmall(resolveScenePath("grazing"));
  const std::string glb = exportGlb(a, "shadowlab test").glb;
  json doc = glbJson(glb);
  // An editor moved the camera node by one unit: the node's camera is the one used, with a warning.
  size_t camNode = 0;
  for (size_t i = 0; i < doc["nodes"].size(); ++i)
    if (doc["nodes"][i].contains("camera")) camNode = i;
  doc["nodes"][camNode]["translation"][0] = doc["nodes"][camNode]["translation"][0].get<double>() + 1.0;
  writeFileAtomic((dir / "moved.glb").string(), withJson(glb, doc));
  const Scene b = loadScene((dir / "moved.glb").string());
  EXPECT_NE(a.camera.hash(), b.camera.hash());
  EXPECT_NEAR(b.camera.position.x, a.camera.position.x + 1.0f, 1e-5);
  // Without the extras the node alone places the camera within float rounding of the original.
  json plain = glbJson(glb);
  plain["nodes"][camNode].erase("extras");
  writeFileAtomic((dir / "plain.glb").string(), withJson(glb, plain));
  const Scene c = loadScene((dir / "plain.glb").string());
  EXPECT_LT(glm::length(c.camera.position - a.camera.position), 1e-5f);
  EXPECT_LT(glm::length(glm::normalize(c.camera.lookAt - c.camera.position) -
                        glm::normalize(a.camera.lookAt - a.camera.position)),
            1e-6f);
  EXPECT_EQ(c.camera.width, 640);  // the glTF camera alone has no pixel size
}

TEST(GltfExport, BadExtrasAreErrorsAtTheirPointer) {
  const fs::path dir = freshTempDir("gltf_export_bad_extras");
  const Scene a = loadSmall(resolveScenePath("grazing"));
  const std::string glb = exportGlb(a, "shadowlab test").glb;
  struct Case {
    std::string pointer;
    json value;
    std::string expected;
  };
  const json doc = glbJson(glb);
  size_t camNode = 0, lightNode = 0;
  for (size_t i = 0; i < doc["nodes"].size(); ++i) {
    if (doc["nodes"][i].contains("camera")) camNode = i;
    if (doc["nodes"][i].contains("extensions")) lightNode = i;
  }
  const std::string cam = "/nodes/" + std::to_string(camNode) + "/extras/shadowlab/camera";
  const std::string light = "/nodes/" + std::to_string(lightNode) + "/extras/shadowlab/light";
  const std::vector<Case> cases = {
      {"/nodes/0/extras/shadowlab/object/id", 0, "/nodes/0/extras/shadowlab/object/id: error: got 0"},
      {"/nodes/1/extras/shadowlab/object/id", doc["nodes"][0]["extras"]["shadowlab"]["object"]["id"],
       "is already used by another node"},
      {"/nodes/0/extras/shadowlab/object/casts_shadow", "no", "/object/casts_shadow: error: got \"no\""},
      {"/nodes/0/extras/shadowlab/object/colour", 1, "unknown key \"colour\""},
      {"/nodes/0/extras/shadowlab", 3, "/nodes/0/extras/shadowlab: error: got 3"},
      {cam + "/width", 0, cam + "/width: error: got 0"},
      {cam + "/width", 1e9, cam + "/width: error"},
      {cam + "/vfov_deg", 180, cam + "/vfov_deg: error: got 180"},
      {cam + "/position/1", "up", cam + "/position/1: error"},
      {cam + "/position", json::array({1, 2}), cam + "/position: error"},
      {light + "/direction", json::array({0, -2, 0}), light + "/direction: error: has length 2"},
      {light + "/angular_diameter_deg", 90, light + "/angular_diameter_deg: error: got 90"},
  };
  for (const Case& c : cases) {
    json bad = doc;
    bad[json::json_pointer(c.pointer)] = c.value;
    const fs::path p = dir / "bad.glb";
    writeFileAtomic(p.string(), withJson(glb, bad));
    try {
      loadScene(p.string());
      ADD_FAILURE() << c.pointer << ": loaded without an error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << c.pointer << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
  }
  // One mesh node without its object extras among marked ones.
  json bad = doc;
  bad["nodes"][1].erase("extras");
  writeFileAtomic((dir / "bad.glb").string(), withJson(glb, bad));
  EXPECT_THROW(
      {
        try {
          loadScene((dir / "bad.glb").string());
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("/nodes/1: error: a mesh node without extras.shadowlab.object"),
                    std::string::npos)
              << e.what();
          throw;
        }
      },
      InputError);
}

TEST(GltfExportCli, ExportsAndTheReferenceReadsIt) {
  const fs::path dir = freshTempDir("gltf_export_cli");
  const CliRun r = runShadowlab("export grazing -o '" + (dir / "g.glb").string() + "'", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("g.glb: note: failure axis /lights/0/elevation_deg: not exported"), std::string::npos) << r.err;
  const CliRun ref = runShadowlab("reference '" + (dir / "g.glb").string() +
                                      "' --set scene:/camera/width=64 --set scene:/camera/height=36 -o '" +
                                      (dir / "ref").string() + "'",
                                  dir);
  ASSERT_EQ(ref.code, 0) << ref.err;
  EXPECT_TRUE(fs::exists(dir / "ref" / "reference.exr"));
  const CliRun help = runShadowlab("--help", dir);
  EXPECT_NE(help.out.find("export"), std::string::npos) << help.out;
  // --set applies to the scene before it is exported.
  const CliRun sized =
      runShadowlab("export grazing --set scene:/camera/width=32 -o '" + (dir / "s.glb").string() + "'", dir);
  ASSERT_EQ(sized.code, 0) << sized.err;
  EXPECT_EQ(loadScene((dir / "s.glb").string()).camera.width, 32);
}

TEST(GltfExportCli, BadInputExitsTwoAndWritesNothing) {
  const fs::path dir = freshTempDir("gltf_export_cli_bad");
  struct Case {
    std::string args, expected;
    fs::path output;
  };
  const std::vector<Case> cases = {
      {"export no_such_scene -o '" + (dir / "a.glb").string() + "'", "no_such_scene", dir / "a.glb"},
      {"export grazing -o '" + (dir / "missing" / "b.glb").string() + "'", "does not exist", dir / "missing"},
      {"export grazing -o '" + (dir / "c.gltf").string() + "'", "expected a .glb file name", dir / "c.gltf"},
      {"export grazing -o '" + (dir / "d.txt").string() + "'", "expected a .glb file name", dir / "d.txt"},
      {"export grazing --set scene:/camera/width=0 -o '" + (dir / "e.glb").string() + "'", "/camera/width",
       dir / "e.glb"},
      {"export grazing --set shadow_map_size=64 -o '" + (dir / "f.glb").string() + "'", "takes no method keys",
       dir / "f.glb"},
      {"export grazing", "--out", dir / "none"},
  };
  for (const Case& c : cases) {
    const CliRun r = runShadowlab(c.args, dir);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(c.output)) << c.args;
  }
  // A folder named like a .glb is refused and stays what it was.
  fs::create_directories(dir / "folder.glb");
  const CliRun r = runShadowlab("export grazing -o '" + (dir / "folder.glb").string() + "'", dir);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(fs::is_directory(dir / "folder.glb"));
  EXPECT_TRUE(fs::is_empty(dir / "folder.glb"));
}

}  // namespace reference_gltf_export_test
