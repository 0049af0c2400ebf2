// The table of glTF 2.0 property types (gltf_schema.h): one row per property, named by the schema
// (object kind) it belongs to, from the glTF 2.0 JSON schema and the KHR_lights_punctual and
// KHR_texture_transform extensions' schemas.
#include "gltf_schema.h"

#include <cmath>
#include <map>
#include <vector>

#include "json_util.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::gltf {

namespace {

using nlohmann::json;

enum class Ty { Object, Array, String, Number, Index, Bool };

struct Prop {
  const char* key;
  Ty type;
  const char* schema = nullptr;  // Object: its schema; Array of objects: the elements' schema
  Ty elem = Ty::Number;          // Array: the elements' type
  int length = 0;                // Array: exact length when > 0, at least 1 when < 0
};

// Object kinds by name; "*index" is an object whose every value is an index (attributes).
const std::map<std::string, std::vector<Prop>>& schemas() {
  static const std::map<std::string, std::vector<Prop>> kSchemas = {
      {"glTF",
       {{"asset", Ty::Object, "asset"},
        {"scene", Ty::Index},
        {"scenes", Ty::Array, "scene", Ty::Object},
        {"nodes", Ty::Array, "node", Ty::Object},
        {"meshes", Ty::Array, "mesh", Ty::Object},
        {"accessors", Ty::Array, "accessor", Ty::Object},
        {"bufferViews", Ty::Array, "bufferView", Ty::Object},
        {"buffers", Ty::Array, "buffer", Ty::Object},
        {"materials", Ty::Array, "material", Ty::Object},
        {"textures", Ty::Array, "texture", Ty::Object},
        {"images", Ty::Array, "image", Ty::Object},
        {"samplers", Ty::Array, "sampler", Ty::Object},
        {"cameras", Ty::Array, "camera", Ty::Object},
        {"extensionsUsed", Ty::Array, nullptr, Ty::String},
        {"extensionsRequired", Ty::Array, nullptr, Ty::String},
        {"extensions", Ty::Object, "glTF.extensions"}}},
      {"glTF.extensions", {{"KHR_lights_punctual", Ty::Object, "KHR_lights_punctual"}}},
      {"KHR_lights_punctual", {{"lights", Ty::Array, "light", Ty::Object}}},
      {"light",
       {{"name", Ty::String},
        {"type", Ty::String},
        {"color", Ty::Array, nullptr, Ty::Number, 3},
        {"intensity", Ty::Number},
        {"range", Ty::Number},
        {"spot", Ty::Object, "light.spot"}}},
      {"light.spot", {{"innerConeAngle", Ty::Number}, {"outerConeAngle", Ty::Number}}},
      {"asset",
       {{"version", Ty::String}, {"minVersion", Ty::String}, {"generator", Ty::String}, {"copyright", Ty::String}}},
      {"scene", {{"name", Ty::String}, {"nodes", Ty::Array, nullptr, Ty::Index}}},
      {"node",
       {{"name", Ty::String},
        {"children", Ty::Array, nullptr, Ty::Index, -1},
        {"mesh", Ty::Index},
        {"camera", Ty::Index},
        {"skin", Ty::Index},
        {"matrix", Ty::Array, nullptr, Ty::Number, 16},
        {"rotation", Ty::Array, nullptr, Ty::Number, 4},
        {"scale", Ty::Array, nullptr, Ty::Number, 3},
        {"translation", Ty::Array, nullptr, Ty::Number, 3},
        {"weights", Ty::Array, nullptr, Ty::Number},
        {"extensions", Ty::Object, "node.extensions"}}},
      {"node.extensions", {{"KHR_lights_punctual", Ty::Object, "node.KHR_lights_punctual"}}},
      {"node.KHR_lights_punctual", {{"light", Ty::Index}}},
      {"mesh",
       {{"name", Ty::String},
        {"primitives", Ty::Array, "primitive", Ty::Object, -1},
        {"weights", Ty::Array, nullptr, Ty::Number}}},
      {"primitive",
       {{"attributes", Ty::Object, "*index"},
        {"indices", Ty::Index},
        {"material", Ty::Index},
        {"mode", Ty::Index},
        {"targets", Ty::Array, "*index", Ty::Object}}},
      {"accessor",
       {{"name", Ty::String},
        {"bufferView", Ty::Index},
        {"byteOffset", Ty::Index},
        {"componentType", Ty::Index},
        {"normalized", Ty::Bool},
        {"count", Ty::Index},
        {"type", Ty::String},
        {"max", Ty::Array, nullptr, Ty::Number},
        {"min", Ty::Array, nullptr, Ty::Number},
        {"sparse", Ty::Object, "accessor.sparse"}}},
      {"accessor.sparse",
       {{"count", Ty::Index}, {"indices", Ty::Object, "sparse.indices"}, {"values", Ty::Object, "sparse.values"}}},
      {"sparse.indices", {{"bufferView", Ty::Index}, {"byteOffset", Ty::Index}, {"componentType", Ty::Index}}},
      {"sparse.values", {{"bufferView", Ty::Index}, {"byteOffset", Ty::Index}}},
      {"bufferView",
       {{"name", Ty::String},
        {"buffer", Ty::Index},
        {"byteOffset", Ty::Index},
        {"byteLength", Ty::Index},
        {"byteStride", Ty::Index},
        {"target", Ty::Index}}},
      {"buffer", {{"name", Ty::String}, {"uri", Ty::String}, {"byteLength", Ty::Index}}},
      {"material",
       {{"name", Ty::String},
        {"pbrMetallicRoughness", Ty::Object, "pbrMetallicRoughness"},
        {"normalTexture", Ty::Object, "normalTextureInfo"},
        {"occlusionTexture", Ty::Object, "occlusionTextureInfo"},
        {"emissiveTexture", Ty::Object, "textureInfo"},
        {"emissiveFactor", Ty::Array, nullptr, Ty::Number, 3},
        {"alphaMode", Ty::String},
        {"alphaCutoff", Ty::Number},
        {"doubleSided", Ty::Bool}}},
      {"pbrMetallicRoughness",
       {{"baseColorFactor", Ty::Array, nullptr, Ty::Number, 4},
        {"baseColorTexture", Ty::Object, "textureInfo"},
        {"metallicFactor", Ty::Number},
        {"roughnessFactor", Ty::Number},
        {"metallicRoughnessTexture", Ty::Object, "textureInfo"}}},
      {"textureInfo",
       {{"index", Ty::Index}, {"texCoord", Ty::Index}, {"extensions", Ty::Object, "textureInfo.extensions"}}},
      {"normalTextureInfo",
       {{"index", Ty::Index},
        {"texCoord", Ty::Index},
        {"scale", Ty::Number},
        {"extensions", Ty::Object, "textureInfo.extensions"}}},
      {"occlusionTextureInfo",
       {{"index", Ty::Index},
        {"texCoord", Ty::Index},
        {"strength", Ty::Number},
        {"extensions", Ty::Object, "textureInfo.extensions"}}},
      {"textureInfo.extensions", {{"KHR_texture_transform", Ty::Object, "KHR_texture_transform"}}},
      {"KHR_texture_transform",
       {{"offset", Ty::Array, nullptr, Ty::Number, 2},
        {"rotation", Ty::Number},
        {"scale", Ty::Array, nullptr, Ty::Number, 2},
        {"texCoord", Ty::Index}}},
      {"texture", {{"name", Ty::String}, {"sampler", Ty::Index}, {"source", Ty::Index}}},
      {"image", {{"name", Ty::String}, {"uri", Ty::String}, {"mimeType", Ty::String}, {"bufferView", Ty::Index}}},
      {"sampler",
       {{"name", Ty::String},
        {"magFilter", Ty::Index},
        {"minFilter", Ty::Index},
        {"wrapS", Ty::Index},
        {"wrapT", Ty::Index}}},
      {"camera",
       {{"name", Ty::String},
        {"type", Ty::String},
        {"perspective", Ty::Object, "camera.perspective"},
        {"orthographic", Ty::Object, "camera.orthographic"}}},
      {"camera.perspective",
       {{"aspectRatio", Ty::Number}, {"yfov", Ty::Number}, {"zfar", Ty::Number}, {"znear", Ty::Number}}},
      {"camera.orthographic",
       {{"xmag", Ty::Number}, {"ymag", Ty::Number}, {"zfar", Ty::Number}, {"znear", Ty::Number}}},
  };
  return kSchemas;
}

const char* expectedText(Ty t) {
  switch (t) {
    case Ty::Object: return "an object";
    case Ty::Array: return "an array";
    case Ty::String: return "a string";
    case Ty::Number: return "a finite number";
    case Ty::Index: return "an integer 0..2147483647";
    case Ty::Bool: return "true or false";
  }
  return "";
}

bool hasType(const json& j, Ty t) {
  switch (t) {
    case Ty::Object: return j.is_object();
    case Ty::Array: return j.is_array();
    case Ty::String: return j.is_string();
    case Ty::Number: return j.is_number() && std::isfinite(j.get<double>());
    case Ty::Index:
      if (j.is_number_unsigned()) return j.get<uint64_t>() <= 2147483647ull;
      if (j.is_number_integer()) return j.get<int64_t>() >= 0 && j.get<int64_t>() <= 2147483647ll;
      return false;
    case Ty::Bool: return j.is_boolean();
  }
  return false;
}

void check(const std::string& file, const json& j, const std::string& ptr, const std::string& schema);

void checkValue(const std::string& file, const json& v, const std::string& ptr, Ty type, const char* schema) {
  if (!hasType(v, type))
    throw InputError(formatError(file, ptr, "got " + detail::describe(v) + "; expected " + expectedText(type)));
  if (type == Ty::Object && schema) check(file, v, ptr, schema);
}

void check(const std::string& file, const json& j, const std::string& ptr, const std::string& schema) {
  if (schema == "*index") {
    for (const auto& item : j.items())
      checkValue(file, item.value(), detail::childPointer(ptr, item.key()), Ty::Index, nullptr);
    return;
  }
  for (const Prop& p : schemas().at(schema)) {
    auto it = j.find(p.key);
    if (it == j.end()) continue;
    const std::string at = detail::childPointer(ptr, p.key);
    checkValue(file, *it, at, p.type, p.type == Ty::Object ? p.schema : nullptr);
    if (p.type != Ty::Array) continue;
    if (p.length > 0 && it->size() != size_t(p.length))
      throw InputError(
          formatError(file, at, "got " + detail::describe(*it) + "; expected " + std::to_string(p.length) + " values"));
    if (p.length < 0 && it->empty())
      throw InputError(formatError(file, at, "got an empty array; expected at least one value"));
    for (size_t i = 0; i < it->size(); ++i) checkValue(file, (*it)[i], detail::childPointer(at, i), p.elem, p.schema);
  }
}

}  // namespace

void checkSchema(const std::string& file, const nlohmann::json& doc) { check(file, doc, "", "glTF"); }

}  // namespace shadowlab::gltf
