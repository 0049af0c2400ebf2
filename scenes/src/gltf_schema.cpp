// The table of glTF 2.0 property types (gltf_schema.h): one row per property, named by the schema
// (object kind) it belongs to, from the glTF 2.0 JSON schema and the KHR_lights_punctual and
// KHR_texture_transform extensions' schemas.
#include "gltf_schema.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "json_util.h"
#include "shadowlab/scenes/number_text.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab::gltf {

namespace {

using nlohmann::json;

constexpr double kUnitQuaternionTolerance = 1e-3;

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

[[noreturn]] void fail(const std::string& file, const std::string& ptr, const std::string& what) {
  throw InputError(formatError(file, ptr, what));
}

namespace {

// The value at `key` of object `o` (at `ptr`), which glTF 2.0 requires.
const json& required(const std::string& file, const json& o, const std::string& ptr, const char* key,
                     const std::string& expected) {
  auto it = o.find(key);
  if (it == o.end()) fail(file, ptr, std::string("missing key \"") + key + "\"; expected " + expected);
  return *it;
}

bool listsExtension(const json& doc, const char* name) {
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    auto it = doc.find(list);
    if (it == doc.end()) continue;
    for (const json& e : *it)
      if (e == name) return true;
  }
  return false;
}

const char* componentTypeName(int64_t t) {
  switch (t) {
    case 5120: return "byte";
    case 5121: return "unsigned byte";
    case 5122: return "short";
    case 5123: return "unsigned short";
    case 5125: return "unsigned int";
    case 5126: return "float";
    default: return "unknown";
  }
}

void checkCamera(const std::string& file, const json& c, const std::string& ptr) {
  const json& type = required(file, c, ptr, "type", "\"perspective\" or \"orthographic\"");
  if (type != "perspective" && type != "orthographic")
    fail(file, ptr + "/type", "got " + detail::describe(type) + "; expected \"perspective\" or \"orthographic\"");
  const std::string kind = type.get<std::string>();
  const std::string at = ptr + "/" + kind;
  const json& p = required(file, c, ptr, kind.c_str(), "the " + kind + " object its type names");
  if (kind == "perspective") {
    required(file, p, at, "yfov", "the vertical field of view in radians");
    required(file, p, at, "znear", "the near plane's distance");
    // glTF 2.0: aspectRatio is exclusiveMinimum 0; tinygltf reads 0 as "absent".
    if (p.contains("aspectRatio") && !(p["aspectRatio"].get<double>() > 0))
      fail(file, at + "/aspectRatio",
           "got " + detail::describe(p["aspectRatio"]) + "; expected a positive width / height ratio");
  } else {
    for (const char* key : {"xmag", "ymag", "zfar", "znear"})
      required(file, p, at, key, "xmag, ymag, zfar and znear (glTF 2.0 requires all four for an orthographic camera)");
  }
}

}  // namespace

void checkRules(const std::string& file, const nlohmann::json& doc) {
  const json& asset = required(file, doc, "", "asset", "a glTF 2.0 \"asset\" object (is this a glTF file?)");
  const json& version = required(file, asset, "/asset", "version", "\"2.0\"");
  const std::string v = version.get<std::string>();
  const bool twoX = v.size() > 2 && v.compare(0, 2, "2.") == 0 &&
                    std::all_of(v.begin() + 2, v.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!twoX)
    fail(file, "/asset/version",
         "got " + detail::describe(version) + "; expected \"2.x\" (shadowlab reads glTF 2.0 and its minor versions)");
  if (asset.contains("minVersion") && asset["minVersion"] != "2.0")
    fail(file, "/asset/minVersion", "got " + detail::describe(asset["minVersion"]) + "; expected \"2.0\"");

  if (doc.contains("cameras"))
    for (size_t i = 0; i < doc["cameras"].size(); ++i)
      checkCamera(file, doc["cameras"][i], "/cameras/" + std::to_string(i));

  if (doc.contains("buffers"))
    for (size_t i = 0; i < doc["buffers"].size(); ++i) {
      const std::string ptr = "/buffers/" + std::to_string(i);
      const json& n = required(file, doc["buffers"][i], ptr, "byteLength", "the buffer's length in bytes");
      if (n.get<int64_t>() < 1) fail(file, ptr + "/byteLength", "got " + detail::describe(n) + "; expected at least 1");
    }

  if (doc.contains("bufferViews"))
    for (size_t i = 0; i < doc["bufferViews"].size(); ++i) {
      const json& bv = doc["bufferViews"][i];
      const std::string ptr = "/bufferViews/" + std::to_string(i);
      required(file, bv, ptr, "buffer", "a buffer index");
      required(file, bv, ptr, "byteLength", "the view's length in bytes");
      if (bv.contains("byteStride")) {
        const int64_t stride = bv["byteStride"].get<int64_t>();
        if (stride < 4 || stride > 252 || stride % 4)
          fail(file, ptr + "/byteStride", "got " + std::to_string(stride) + "; expected a multiple of 4 in 4..252");
      }
    }

  if (doc.contains("accessors"))
    for (size_t i = 0; i < doc["accessors"].size(); ++i) {
      const json& a = doc["accessors"][i];
      const std::string ptr = "/accessors/" + std::to_string(i);
      required(file, a, ptr, "componentType", "5120, 5121, 5122, 5123, 5125 or 5126");
      required(file, a, ptr, "count", "the number of elements");
      const json& type = required(file, a, ptr, "type", "SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4");
      static const std::vector<std::string> kTypes = {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"};
      if (std::find(kTypes.begin(), kTypes.end(), type.get<std::string>()) == kTypes.end())
        fail(file, ptr + "/type",
             "got " + detail::describe(type) + "; expected SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4");
      if (!a.contains("sparse")) continue;
      const json& sparse = a["sparse"];
      required(file, sparse, ptr + "/sparse", "count", "the number of substituted elements");
      const json& indices = required(file, sparse, ptr + "/sparse", "indices", "an object (bufferView, componentType)");
      required(file, indices, ptr + "/sparse/indices", "bufferView", "a buffer view index");
      required(file, indices, ptr + "/sparse/indices", "componentType", "5121, 5123 or 5125");
      const json& values = required(file, sparse, ptr + "/sparse", "values", "an object (bufferView)");
      required(file, values, ptr + "/sparse/values", "bufferView", "a buffer view index");
    }

  if (doc.contains("images"))
    for (size_t i = 0; i < doc["images"].size(); ++i) {
      const json& im = doc["images"][i];
      const std::string ptr = "/images/" + std::to_string(i);
      if (im.contains("uri") == im.contains("bufferView"))
        fail(
            file, ptr,
            std::string(im.contains("uri") ? "both \"uri\" and \"bufferView\"" : "neither \"uri\" nor \"bufferView\"") +
                "; expected exactly one of them");
      if (im.contains("bufferView") && !im.contains("mimeType"))
        fail(file, ptr, "missing key \"mimeType\"; expected \"image/png\" or \"image/jpeg\" beside a bufferView");
    }

  if (doc.contains("meshes"))
    for (size_t m = 0; m < doc["meshes"].size(); ++m) {
      const std::string ptr = "/meshes/" + std::to_string(m);
      const json& prims = required(file, doc["meshes"][m], ptr, "primitives", "an array of primitives");
      for (size_t p = 0; p < prims.size(); ++p)
        required(file, prims[p], ptr + "/primitives/" + std::to_string(p), "attributes",
                 "an object of attributes (POSITION at least)");
    }

  if (doc.contains("nodes"))
    for (size_t i = 0; i < doc["nodes"].size(); ++i) {
      const json& n = doc["nodes"][i];
      if (!n.contains("rotation")) continue;
      double sq = 0;
      for (const json& c : n["rotation"]) sq += c.get<double>() * c.get<double>();
      const double length = std::sqrt(sq);
      // Exporters write quaternions as floats, normalized in float: 1e-3 passes their rounding
      // with a wide margin and still refuses a zero or a plainly unnormalized quaternion (which
      // a renderer would either refuse or silently normalize).
      if (!(std::fabs(length - 1.0) <= kUnitQuaternionTolerance))
        fail(file, "/nodes/" + std::to_string(i) + "/rotation",
             "got a quaternion of length " + numberText(length) + "; expected a unit quaternion (length 1 within " +
                 numberText(kUnitQuaternionTolerance) + ")");
    }

  // glTF 2.0 ("Meshes"): POSITION is float; integer positions are KHR_mesh_quantization's.
  if (doc.contains("meshes") && !listsExtension(doc, "KHR_mesh_quantization"))
    for (size_t m = 0; m < doc["meshes"].size(); ++m) {
      const json& mesh = doc["meshes"][m];
      if (!mesh.contains("primitives")) continue;
      for (size_t p = 0; p < mesh["primitives"].size(); ++p) {
        const json& prim = mesh["primitives"][p];
        if (!prim.contains("attributes") || !prim["attributes"].contains("POSITION")) continue;
        const size_t a = prim["attributes"]["POSITION"].get<size_t>();
        if (!doc.contains("accessors") || a >= doc["accessors"].size() ||
            !doc["accessors"][a].contains("componentType"))
          continue;  // the converter names a missing accessor
        const int64_t type = doc["accessors"][a]["componentType"].get<int64_t>();
        if (type != 5126)
          fail(file, "/accessors/" + std::to_string(a) + "/componentType",
               "got " + std::to_string(type) + " (" + componentTypeName(type) + ") for the POSITION of /meshes/" +
                   std::to_string(m) + "/primitives/" + std::to_string(p) +
                   "; expected 5126 (float), or KHR_mesh_quantization in extensionsUsed for integer positions");
      }
    }
}

}  // namespace shadowlab::gltf
