#pragma once
// How compare's file readers (results, gate tolerances, sweep files) name JSON values and places
// in their error messages. Private to compare/src.
#include <string>

#include <nlohmann/json.hpp>

namespace shadowlab::json_text {

// "a number", "a string", ... for "got X; expected Y" messages.
inline std::string typeName(const nlohmann::json& v) {
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_boolean()) return "a boolean";
  if (v.is_null()) return "null";
  if (v.is_array()) return "an array";
  return "an object";
}

// Escapes one reference token for a JSON pointer (RFC 6901): keys like "scene:/a/b" hold slashes.
inline std::string pointerToken(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}

}  // namespace shadowlab::json_text
