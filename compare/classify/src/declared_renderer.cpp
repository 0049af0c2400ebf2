// The renderer JSON (scenes/FRAME-CONTRACT.md "The renderer JSON"): what an outside renderer says
// it used for a frame, read into DeclaredRenderer (declared_renderer.h).
#include <cmath>
#include <string>

#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab {
namespace {

constexpr size_t kMaxLayers = 64;       // cascades and cube faces: far more than any renderer draws
constexpr size_t kMaxSettings = 64;     // keys of "settings"
constexpr size_t kMaxTextLength = 200;  // name, filter, a setting's string
constexpr int kMaxMapSize = 65536;      // texels per side

}  // namespace

DeclaredRenderer readDeclaredRenderer(const std::string& path) {
  const nlohmann::json j = readJsonFile(path);
  auto fail = [&](const std::string& pointer, const std::string& what) {
    throw InputError(formatError(path, pointer, what));
  };
  if (!j.is_object()) fail("", "got " + describeJson(j) + "; expected an object (the renderer JSON)");
  DeclaredRenderer d;
  auto text = [&](const nlohmann::json& v, const std::string& pointer, std::string& out) {
    if (!v.is_string() || v.get<std::string>().size() > kMaxTextLength)
      fail(pointer, "got " + describeJson(v) + "; expected a string of at most 200 bytes");
    out = v.get<std::string>();
  };
  auto finite = [&](const nlohmann::json& v, const std::string& pointer, const char* expected) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      fail(pointer, "got " + describeJson(v) + "; expected " + expected);
    return v.get<double>();
  };
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    const std::string pointer = "/" + jsonPointerToken(key);
    const nlohmann::json& v = it.value();
    if (key == "name") {
      text(v, pointer, d.name);
    } else if (key == "filter") {
      text(v, pointer, d.filter);
    } else if (key == "light_clip_from_world") {
      if (!v.is_array() || v.empty() || v.size() > kMaxLayers)
        fail(pointer, "got " + describeJson(v) +
                          "; expected an array of 1..64 map layers, each 16 numbers (column-major clip from world)");
      for (size_t layer = 0; layer < v.size(); ++layer) {
        const nlohmann::json& m = v[layer];
        const std::string place = pointer + "/" + std::to_string(layer);
        if (!m.is_array() || m.size() != 16)
          fail(place, "got " + describeJson(m) + "; expected 16 numbers (a 4x4 matrix, column-major)");
        glm::mat4 matrix(0.0f);
        bool zero = true;
        for (int k = 0; k < 16; ++k) {
          const double e = finite(m[size_t(k)], place + "/" + std::to_string(k), "a finite number");
          matrix[k / 4][k % 4] = float(e);
          zero = zero && e == 0.0;
        }
        if (zero) fail(place, "got a matrix of zeros; expected the light's clip-from-world matrix");
        d.lightClipFromWorld.push_back(matrix);
      }
    } else if (key == "map_size") {
      if (!v.is_number_integer() || v.get<long long>() < 1 || v.get<long long>() > kMaxMapSize)
        fail(pointer, "got " + describeJson(v) + "; expected an integer 1..65536 (texels per side of a map layer)");
      d.mapSize = v.get<int>();
    } else if (key == "normal_bias_world") {
      d.normalBiasWorld = finite(v, pointer, "a finite number (world units along the normal)");
    } else if (key == "depth_bias") {
      d.depthBias = finite(v, pointer, "a finite number (the renderer's own depth-bias units)");
    } else if (key == "frame_ms") {
      const double ms = finite(v, pointer, "a finite number >= 0 (milliseconds)");
      if (ms < 0) fail(pointer, "got " + describeJson(v) + "; expected a finite number >= 0 (milliseconds)");
      d.frameMs = ms;
    } else if (key == "settings") {
      if (!v.is_object() || v.size() > kMaxSettings)
        fail(pointer, "got " + describeJson(v) + "; expected an object of at most 64 settings");
      for (auto s = v.begin(); s != v.end(); ++s) {
        const std::string place = pointer + "/" + jsonPointerToken(s.key());
        const nlohmann::json& value = s.value();
        if (s.key().empty() || s.key().size() > kMaxTextLength)
          fail(place, "got a key of " + std::to_string(s.key().size()) + " bytes; expected a name of 1..200 bytes");
        const bool scalar = value.is_boolean() || (value.is_number() && std::isfinite(value.get<double>())) ||
                            (value.is_string() && value.get<std::string>().size() <= kMaxTextLength);
        if (!scalar) fail(place, "got " + describeJson(value) + "; expected a number, a string or a boolean");
      }
      d.settings = v;
    } else {
      fail(pointer,
           "unknown key; expected one of name, light_clip_from_world, map_size, normal_bias_world, "
           "depth_bias, filter, frame_ms, settings");
    }
  }
  if (!d.lightClipFromWorld.empty() && d.mapSize == 0)
    fail("/map_size", "missing; expected the map size beside light_clip_from_world");
  return d;
}

}  // namespace shadowlab
