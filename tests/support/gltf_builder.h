#pragma once
// Writes small glTF 2.0 files for tests: one binary buffer, accessors over it, meshes, nodes,
// materials, cameras and KHR_lights_punctual lights, saved as .gltf + .bin, as one .gltf with a
// data: URI, or as one .glb. The document is plain JSON (`doc`), so a test adds or breaks anything.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace shadowlab::testing {

inline std::string base64(const std::vector<uint8_t>& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8) | bytes[i + 2];
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], k[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint32_t(bytes[i]) << 16;
    out += {k[v >> 18], k[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = (uint32_t(bytes[i]) << 16) | (uint32_t(bytes[i + 1]) << 8);
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], '='};
  }
  return out;
}

struct GltfBuilder {
  nlohmann::json doc = {{"asset", {{"version", "2.0"}}}};
  std::vector<uint8_t> bin;

  int push(const char* array, nlohmann::json item) {
    doc[array].push_back(std::move(item));
    return int(doc[array].size()) - 1;
  }
  // A buffer view over `bytes` (4-byte aligned), with byteStride when given.
  int view(const void* data, size_t bytes, int stride = 0) {
    while (bin.size() % 4) bin.push_back(0);
    const size_t offset = bin.size();
    bin.insert(bin.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + bytes);
    nlohmann::json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
    if (stride) v["byteStride"] = stride;
    return push("bufferViews", v);
  }
  int accessor(int view, int componentType, size_t count, const char* type, bool normalized = false,
               size_t byteOffset = 0) {
    nlohmann::json a = {{"bufferView", view}, {"componentType", componentType}, {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    if (byteOffset) a["byteOffset"] = byteOffset;
    return push("accessors", a);
  }
  int positions(const std::vector<glm::vec3>& p) {
    return accessor(view(p.data(), p.size() * sizeof(glm::vec3)), 5126, p.size(), "VEC3");
  }
  int uvs(const std::vector<glm::vec2>& t) {
    return accessor(view(t.data(), t.size() * sizeof(glm::vec2)), 5126, t.size(), "VEC2");
  }
  int indices32(const std::vector<uint32_t>& i) {
    return accessor(view(i.data(), i.size() * 4), 5125, i.size(), "SCALAR");
  }
  int indices16(const std::vector<uint16_t>& i) {
    return accessor(view(i.data(), i.size() * 2), 5123, i.size(), "SCALAR");
  }
  int indices8(const std::vector<uint8_t>& i) { return accessor(view(i.data(), i.size()), 5121, i.size(), "SCALAR"); }
  // One mesh of one primitive.
  int mesh(int position, int indices = -1, int mode = -1, int material = -1, int texcoord0 = -1) {
    nlohmann::json prim = {{"attributes", {{"POSITION", position}}}};
    if (indices >= 0) prim["indices"] = indices;
    if (mode >= 0) prim["mode"] = mode;
    if (material >= 0) prim["material"] = material;
    if (texcoord0 >= 0) prim["attributes"]["TEXCOORD_0"] = texcoord0;
    return push("meshes", {{"primitives", {prim}}});
  }
  int node(nlohmann::json n) { return push("nodes", std::move(n)); }
  void scene(const std::vector<int>& roots) {
    doc["scenes"] = {{{"nodes", roots}}};
    doc["scene"] = 0;
  }
  int light(nlohmann::json l) {
    doc["extensionsUsed"] = {"KHR_lights_punctual"};
    doc["extensions"]["KHR_lights_punctual"]["lights"].push_back(std::move(l));
    return int(doc["extensions"]["KHR_lights_punctual"]["lights"].size()) - 1;
  }

  enum class Form { External, Embedded, Binary };
  // Writes dir/name.gltf (+ name.bin) or dir/name.glb; returns the path of the main file.
  std::string write(const std::string& dir, const std::string& name, Form form = Form::External) const {
    nlohmann::json d = doc;
    while (d.contains("buffers")) d.erase("buffers");
    if (!bin.empty()) {
      nlohmann::json buffer = {{"byteLength", bin.size()}};
      if (form == Form::External) buffer["uri"] = name + ".bin";
      if (form == Form::Embedded) buffer["uri"] = "data:application/octet-stream;base64," + base64(bin);
      d["buffers"] = {buffer};
    }
    if (form == Form::External) {
      std::ofstream(dir + "/" + name + ".bin", std::ios::binary)
          .write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
    }
    if (form != Form::Binary) {
      const std::string path = dir + "/" + name + ".gltf";
      std::ofstream(path) << d.dump(1);
      return path;
    }
    std::string json = d.dump();
    while (json.size() % 4) json += ' ';
    std::vector<uint8_t> b = bin;
    while (b.size() % 4) b.push_back(0);
    const uint32_t total = uint32_t(12 + 8 + json.size() + (b.empty() ? 0 : 8 + b.size()));
    std::vector<uint8_t> out;
    auto u32 = [&](uint32_t v) {
      uint8_t x[4];
      std::memcpy(x, &v, 4);
      out.insert(out.end(), x, x + 4);
    };
    u32(0x46546C67);
    u32(2);
    u32(total);
    u32(uint32_t(json.size()));
    u32(0x4E4F534A);
    out.insert(out.end(), json.begin(), json.end());
    if (!b.empty()) {
      u32(uint32_t(b.size()));
      u32(0x004E4942);
      out.insert(out.end(), b.begin(), b.end());
    }
    const std::string path = dir + "/" + name + ".glb";
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size()));
    return path;
  }
};

}  // namespace shadowlab::testing
