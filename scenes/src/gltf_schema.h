#pragma once
// The value types of the glTF 2.0 properties shadowlab reads, checked before tinygltf parses the
// document: tinygltf skips an optional property of the wrong type without a word ("name": 42,
// "scale": "not a number", "index": -1), which would silently change a scene. Internal to
// shadowlab_scenes (gltf_loader.cpp).
#include <string>

#include <nlohmann/json.hpp>

namespace shadowlab::gltf {

// Throws InputError "file: /json/pointer: error: got ...; expected ..." at the first value whose
// type differs from glTF 2.0's JSON schema (for the properties in gltf_schema.cpp's table; other
// properties and extensions are not read and not checked).
void checkSchema(const std::string& file, const nlohmann::json& doc);

// The glTF 2.0 rules on values (after checkSchema) that tinygltf either lets through or reports
// without a JSON pointer: asset.version 2.x, the required properties of cameras, buffers, buffer
// views, accessors (and their sparse parts) and mesh primitives, aspectRatio > 0, byteStride 4..252
// in steps of 4, unit rotation quaternions, and integer POSITION components only under
// KHR_mesh_quantization. Throws InputError at the first value that breaks one.
void checkRules(const std::string& file, const nlohmann::json& doc);

// Throws InputError "file: ptr: error: what" (formatError): the glTF reader's one way to refuse.
[[noreturn]] void fail(const std::string& file, const std::string& ptr, const std::string& what);

}  // namespace shadowlab::gltf
