// Scene -> glTF 2.0 binary (gltf_export.h; the mapping is scenes/FORMAT.md, "Exporting a scene as
// glTF"). The JSON is built with nlohmann (doubles print as the shortest text that reads back to
// the same double, so every float the scene holds survives exactly) and packed into a GLB container
// here: tinygltf 2.7's writer, as shadowlab builds it (gltf_tinygltf.h: no stb_image_write), cannot
// embed an image that is already PNG bytes, and its Value type makes the shadowlab extras verbose.
// The file is read back by the same loader as any glTF file (gltf_loader.cpp).
#include "shadowlab/scenes/gltf_export.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "image_io.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

json vec3Json(glm::vec3 v) { return json::array({double(v.x), double(v.y), double(v.z)}); }

// glTF stores x, y, z, w.
json quatJson(const glm::dquat& q) { return json::array({q.x, q.y, q.z, q.w}); }

// The rotation taking a node's -Z to `forward` and its +Y to the part of `up` orthogonal to it
// (glTF cameras and lights look down their node's -Z). Computed in double, as CameraRays does.
glm::dquat lookRotation(glm::dvec3 forward, glm::dvec3 up) {
  forward = glm::normalize(forward);
  glm::dvec3 right = glm::cross(forward, up);
  if (!(glm::length(right) > 1e-12)) {
    // Any up works for a light whose direction is (anti)parallel to the chosen one.
    up = std::abs(forward.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
    right = glm::cross(forward, up);
  }
  right = glm::normalize(right);
  const glm::dvec3 trueUp = glm::cross(right, forward);
  glm::dmat3 basis(right, trueUp, -forward);  // columns: the node's +X, +Y, +Z in world space
  return glm::normalize(glm::quat_cast(basis));
}

class Writer {
 public:
  // A buffer view over `bytes` appended to the BIN chunk (4-byte aligned, as accessors need).
  int view(const void* data, size_t size, int target) {
    while (bin_.size() % 4) bin_.push_back(0);
    json v = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", size}};
    if (target) v["target"] = target;
    const auto* p = static_cast<const uint8_t*>(data);
    bin_.insert(bin_.end(), p, p + size);
    views_.push_back(std::move(v));
    return int(views_.size()) - 1;
  }
  int accessor(json a) {
    accessors_.push_back(std::move(a));
    return int(accessors_.size()) - 1;
  }
  json& views() { return views_; }
  json& accessors() { return accessors_; }
  std::vector<uint8_t>& bin() { return bin_; }

 private:
  std::vector<uint8_t> bin_;
  json views_ = json::array();
  json accessors_ = json::array();
};

constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963, kFloat = 5126, kUnsignedInt = 5125;

// The alpha texture as an RGBA PNG (white, alpha = the texture), 8 bits; `exact` is false when
// some texel is not k / 255 as the PNG reader decodes it (image_io.h), so that the file says so.
std::vector<uint8_t> alphaPng(const Image& alpha, bool& exact) {
  exact = true;
  std::vector<uint8_t> rgba(size_t(alpha.width) * size_t(alpha.height) * 4, 255);
  for (size_t i = 0; i < size_t(alpha.width) * size_t(alpha.height); ++i) {
    const float a = alpha.pixels[i * size_t(alpha.channels)];
    const float clamped = std::clamp(std::isfinite(a) ? a : 0.0f, 0.0f, 1.0f);
    const uint8_t byte = uint8_t(std::lround(clamped * 255.0f));
    if (float(byte) * (1.0f / 255.0f) != a) exact = false;
    rgba[i * 4 + 3] = byte;
  }
  // image_io writes files: a private temporary one, read back and removed.
  std::string name = (fs::temp_directory_path() / "shadowlab-export-XXXXXX.png").string();
  const int fd = mkstemps(name.data(), 4);
  if (fd < 0) throw DriverError("shadowlab export: cannot create a temporary file for a PNG texture");
  close(fd);
  const std::string err = image_io::writePng(name, alpha.width, alpha.height, 4, rgba.data());
  std::vector<uint8_t> bytes;
  if (err.empty()) {
    std::ifstream in(name, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::error_code ec;
  fs::remove(name, ec);
  if (!err.empty() || bytes.empty()) throw DriverError("shadowlab export: cannot encode a PNG texture: " + err);
  return bytes;
}

void put32(std::string& out, uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(char((v >> (8 * k)) & 0xff));
}

std::string lightTypeKey(LightType t) {
  for (const auto& k : lightTypeKinds())
    if (k.kind == t) return k.key;
  return "";
}

}  // namespace

bool isGlbPath(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".glb";
}

GltfExport exportGlb(const Scene& scene, const std::string& generator) {
  GltfExport result;
  Writer w;
  json doc;
  json nodes = json::array(), meshes = json::array(), materials = json::array();
  json images = json::array(), textures = json::array(), samplers = json::array();
  json sceneNodes = json::array();

  // Materials: one per scene material, in order (index 0, the default, included).
  for (size_t m = 0; m < scene.materials.size(); ++m) {
    const Material& mat = scene.materials[m];
    json j = {{"name", mat.name},
              {"doubleSided", mat.twoSided},
              {"pbrMetallicRoughness",
               {{"baseColorFactor", {double(mat.albedo.r), double(mat.albedo.g), double(mat.albedo.b), 1.0}},
                {"metallicFactor", 0.0},
                {"roughnessFactor", 1.0}}}};
    if (mat.hasAlpha) {
      j["alphaMode"] = "MASK";
      j["alphaCutoff"] = double(mat.alphaCutoff);
      if (samplers.empty())
        // What both renderers sample: NEAREST, REPEAT (scene.h, sampleAlphaNearest).
        samplers.push_back({{"magFilter", 9728}, {"minFilter", 9728}, {"wrapS", 10497}, {"wrapT", 10497}});
      bool exact = true;
      const std::vector<uint8_t> png = alphaPng(mat.alphaTexture, exact);
      if (!exact)
        result.notes.push_back("material \"" + mat.name +
                               "\": alpha texture rounded to 8 bits (its values are not all k/255): the truth of the "
                               "exported file may differ near the cutoff");
      images.push_back({{"name", mat.name + "_alpha"},
                        {"mimeType", "image/png"},
                        {"bufferView", w.view(png.data(), png.size(), 0)}});
      textures.push_back({{"sampler", 0}, {"source", int(images.size()) - 1}});
      j["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", int(textures.size()) - 1}};
    }
    materials.push_back(std::move(j));
  }

  // Objects: one node and one mesh each, in object order; a primitive per run of triangles with
  // one material, so the triangle order (the primitive id) is kept. Vertices are split per face:
  // NORMAL is the geometric face normal (shadowlab has no shading normals).
  for (const Object& o : scene.objects) {
    json prims = json::array();
    const bool uv = !o.uvs.empty();
    for (size_t t0 = 0; t0 < o.triangles.size();) {
      size_t t1 = t0;
      while (t1 < o.triangles.size() && o.triangleMaterial[t1] == o.triangleMaterial[t0]) ++t1;
      const size_t n = t1 - t0;
      std::vector<glm::vec3> pos, nrm;
      std::vector<glm::vec2> uvs;
      std::vector<uint32_t> idx;
      pos.reserve(3 * n), nrm.reserve(3 * n), idx.reserve(3 * n);
      glm::vec3 lo(INFINITY), hi(-INFINITY);
      for (size_t t = t0; t < t1; ++t) {
        const glm::uvec3 tri = o.triangles[t];
        const glm::vec3 a = o.positions[tri.x], b = o.positions[tri.y], c = o.positions[tri.z];
        glm::dvec3 normal = glm::cross(glm::dvec3(b) - glm::dvec3(a), glm::dvec3(c) - glm::dvec3(a));
        // A degenerate triangle has no normal; glTF wants a unit one, and nothing sees this one.
        normal = glm::length(normal) > 0 ? glm::normalize(normal) : glm::dvec3(0, 0, 1);
        for (uint32_t k = 0; k < 3; ++k) {
          const glm::vec3 p = o.positions[tri[int(k)]];
          lo = glm::min(lo, p), hi = glm::max(hi, p);
          idx.push_back(uint32_t(pos.size()));
          pos.push_back(p);
          nrm.push_back(glm::vec3(normal));
          if (uv) uvs.push_back(o.uvs[tri[int(k)]]);
        }
      }
      json attrs;
      attrs["POSITION"] = w.accessor({{"bufferView", w.view(pos.data(), pos.size() * 12, kArrayBuffer)},
                                      {"componentType", kFloat},
                                      {"count", pos.size()},
                                      {"type", "VEC3"},
                                      {"min", vec3Json(lo)},
                                      {"max", vec3Json(hi)}});
      attrs["NORMAL"] = w.accessor({{"bufferView", w.view(nrm.data(), nrm.size() * 12, kArrayBuffer)},
                                    {"componentType", kFloat},
                                    {"count", nrm.size()},
                                    {"type", "VEC3"}});
      if (uv)
        attrs["TEXCOORD_0"] = w.accessor({{"bufferView", w.view(uvs.data(), uvs.size() * 8, kArrayBuffer)},
                                          {"componentType", kFloat},
                                          {"count", uvs.size()},
                                          {"type", "VEC2"}});
      const int indices = w.accessor({{"bufferView", w.view(idx.data(), idx.size() * 4, kElementArrayBuffer)},
                                      {"componentType", kUnsignedInt},
                                      {"count", idx.size()},
                                      {"type", "SCALAR"}});
      prims.push_back({{"attributes", attrs}, {"indices", indices}, {"material", o.triangleMaterial[t0]}, {"mode", 4}});
      t0 = t1;
    }
    if (prims.empty()) {
      result.notes.push_back("object \"" + o.name + "\": no triangles; not exported");
      continue;
    }
    meshes.push_back({{"name", o.name}, {"primitives", prims}});
    // glTF has no "casts no shadow": the object's extras say it (and shadowlab reads it back).
    nodes.push_back({{"name", o.name},
                     {"mesh", int(meshes.size()) - 1},
                     {"extras", {{"shadowlab", {{"object", {{"id", o.id}, {"casts_shadow", o.castsShadow}}}}}}}});
    sceneNodes.push_back(int(nodes.size()) - 1);
    if (!o.castsShadow)
      result.notes.push_back("object \"" + o.name +
                             "\": casts no shadow, which glTF cannot say (in the node's extras.shadowlab.object)");
  }

  // The camera: a node at its position looking down -Z, the exact shadowlab camera in its extras
  // (the loader prefers it where it agrees with the node: FORMAT.md).
  {
    const Camera& c = scene.camera;
    const double aspect = double(c.width) / double(c.height);
    json cam;
    if (c.orthographic()) {
      const double ymag = 0.5 * double(c.orthoHeight);
      cam = {{"type", "orthographic"},
             {"orthographic",
              {{"xmag", ymag * aspect}, {"ymag", ymag}, {"znear", double(c.nearPlane)}, {"zfar", double(c.farPlane)}}}};
    } else {
      cam = {{"type", "perspective"},
             {"perspective",
              {{"yfov", double(c.vfovDeg) * kPi / 180.0},
               {"aspectRatio", aspect},
               {"znear", double(c.nearPlane)},
               {"zfar", double(c.farPlane)}}}};
    }
    cam["name"] = "camera";
    json exact = {{"position", vec3Json(c.position)},
                  {"look_at", vec3Json(c.lookAt)},
                  {"up", vec3Json(c.up)},
                  {"width", c.width},
                  {"height", c.height},
                  {"near", double(c.nearPlane)},
                  {"far", double(c.farPlane)}};
    if (c.orthographic()) exact["ortho_height"] = double(c.orthoHeight);
    else exact["vfov_deg"] = double(c.vfovDeg);
    doc["cameras"] = json::array({cam});
    const glm::dquat q = lookRotation(glm::dvec3(c.lookAt) - glm::dvec3(c.position), glm::dvec3(c.up));
    nodes.push_back({{"name", "camera"},
                     {"camera", 0},
                     {"translation", vec3Json(c.position)},
                     {"rotation", quatJson(q)},
                     {"extras", {{"shadowlab", {{"camera", exact}}}}}});
    sceneNodes.push_back(int(nodes.size()) - 1);
  }

  // Lights: KHR_lights_punctual, one node each; the exact direction, position and what the
  // extension has no field for (a sized light, a depth-map near plane, the exact cone) in extras.
  json lights = json::array();
  for (const Light& l : scene.lights) {
    json kl = {{"name", l.name}, {"type", lightTypeKey(l.type)}, {"color", {1.0, 1.0, 1.0}}, {"intensity", 1.0}};
    json exact = {{"direction", vec3Json(l.direction)}};
    if (l.type != LightType::Directional) {
      exact["position"] = vec3Json(l.position);
      exact["near"] = double(l.nearPlane);
      exact["radius"] = double(l.radius);
    } else {
      exact["angular_diameter_deg"] = double(l.angularDiameterDeg);
    }
    if (l.type == LightType::Spot) {
      // shadowlab's cone is hard-edged (lit up to coneDeg / 2, dark beyond): the inner cone is the
      // largest angle below the outer one, since KHR_lights_punctual wants inner < outer.
      const double outer = double(l.coneDeg) * 0.5 * kPi / 180.0;
      kl["spot"] = {{"outerConeAngle", outer}, {"innerConeAngle", std::nextafter(outer, 0.0)}};
      exact["cone_deg"] = double(l.coneDeg);
    }
    lights.push_back(std::move(kl));
    json node = {{"name", l.name},
                 {"rotation", quatJson(lookRotation(glm::dvec3(l.direction), glm::dvec3(0, 1, 0)))},
                 {"extensions", {{"KHR_lights_punctual", {{"light", int(lights.size()) - 1}}}}},
                 {"extras", {{"shadowlab", {{"light", exact}}}}}};
    if (l.type != LightType::Directional) node["translation"] = vec3Json(l.position);
    nodes.push_back(std::move(node));
    sceneNodes.push_back(int(nodes.size()) - 1);
    if (l.sized())
      result.notes.push_back("light \"" + l.name + "\": its " +
                             (l.type == LightType::Directional ? std::string("angular diameter") : "radius") +
                             " has no KHR_lights_punctual field (in the node's extras.shadowlab.light)");
  }

  for (const Projector& p : scene.projectors)
    result.notes.push_back("projector \"" + p.name + "\": glTF has no projected texture; not exported");
  for (const CameraPath& p : scene.paths)
    result.notes.push_back("camera path \"" + p.name + "\" (" + toString(p.kind) + "): not exported");
  if (!scene.failurePointer.empty())
    result.notes.push_back("failure axis " + scene.failurePointer + ": not exported (it addresses the scene file)");

  doc["asset"] = {
      {"version", "2.0"},
      {"generator", generator},
      {"extras", {{"shadowlab", {{"scene", scene.name}, {"scene_hash", scene.hash}, {"not_exported", result.notes}}}}}};
  if (!lights.empty()) {
    doc["extensionsUsed"] = json::array({"KHR_lights_punctual"});
    doc["extensions"] = {{"KHR_lights_punctual", {{"lights", lights}}}};
  }
  doc["scene"] = 0;
  doc["scenes"] = json::array({{{"name", scene.name}, {"nodes", sceneNodes}}});
  doc["nodes"] = nodes;
  doc["meshes"] = meshes;
  doc["materials"] = materials;
  if (!images.empty()) {
    doc["images"] = images;
    doc["textures"] = textures;
    doc["samplers"] = samplers;
  }
  std::vector<uint8_t>& bin = w.bin();
  while (bin.size() % 4) bin.push_back(0);
  doc["buffers"] = json::array({{{"byteLength", bin.size()}}});
  doc["bufferViews"] = w.views();
  doc["accessors"] = w.accessors();

  // GLB (glTF 2.0, "Binary glTF Layout"): a 12-byte header, the JSON chunk padded with spaces, the
  // BIN chunk padded with zeros, each length a multiple of 4.
  std::string text = doc.dump(-1, ' ', false, json::error_handler_t::replace);
  while (text.size() % 4) text.push_back(' ');
  const uint64_t total = 12 + 8 + uint64_t(text.size()) + 8 + uint64_t(bin.size());
  if (total > 0xffffffffull)
    throw InputError("shadowlab export: error: scene " + scene.name + " makes a " + std::to_string(total) +
                     "-byte file; expected at most 4 GiB (a GLB holds its length in 32 bits)");
  std::string& out = result.glb;
  out.reserve(size_t(total));
  out += "glTF";
  put32(out, 2);
  put32(out, uint32_t(total));
  put32(out, uint32_t(text.size()));
  out += "JSON";
  out += text;
  put32(out, uint32_t(bin.size()));
  out += std::string("BIN\0", 4);
  out.append(reinterpret_cast<const char*>(bin.data()), bin.size());
  return result;
}

}  // namespace shadowlab
