// The one name of a configuration (config_name.h).
#include "shadowlab/compare/config_name.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "shadowlab/scenes/adapter_manifest.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab {

std::string canonicalValueText(const nlohmann::json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number_integer()) return std::to_string(value.get<int64_t>());
  if (value.is_number_unsigned()) return std::to_string(value.get<uint64_t>());
  if (value.is_number_float()) {
    const double d = value.get<double>();
    if (d == 0.0) return "0";  // also folds -0
    // An integral value as an integer (2.0 and 2 are one value); below 1e15 every such double is
    // exactly an int64.
    if (std::isfinite(d) && std::floor(d) == d && std::fabs(d) < 1e15) return std::to_string(int64_t(d));
    // nlohmann writes the shortest digits that read back to the same double, in fixed notation
    // from 1e-4 up to 1e15 and with an exponent beyond (as Python's repr does).
    return dumpJson(value);
  }
  if (value.is_array()) {
    std::string out = "[";
    for (size_t i = 0; i < value.size(); ++i) {
      const nlohmann::json& v = value[i];
      out += (i ? "," : "") + (v.is_string() ? dumpJson(v) : canonicalValueText(v));
    }
    return out + "]";
  }
  if (value.is_object()) {
    std::string out = "{";
    bool first = true;
    for (auto it = value.begin(); it != value.end(); ++it) {
      out += (first ? "" : ",") + dumpJson(it.key()) + ":" +
             (it.value().is_string() ? dumpJson(it.value()) : canonicalValueText(it.value()));
      first = false;
    }
    return out + "}";
  }
  return dumpJson(value);  // null
}

std::string configName(const nlohmann::json& methodJson, const std::vector<SceneOverride>& sceneOverrides) {
  // Through the method parser: a value is then the method's own (a float written by an older build
  // as its widened double, 0.10000000149011612, names 0.1 as methodToJson writes it today).
  Method method;
  for (const std::string& key : methodKeys())
    if (auto it = methodJson.find(key); it != methodJson.end()) applyMethodJson(method, key, *it, "method");
  // A technique file's own keys (technique.<name>); its hash is checked where rows meet, not named.
  for (auto it = methodJson.begin(); it != methodJson.end(); ++it)
    if (it.key().rfind("technique.", 0) == 0 && it.key() != "technique.hash")
      applyMethodJson(method, it.key(), it.value(), "method");
  // An outside renderer's keys (NAME.KEY of its manifest): every other dotted key the method names.
  if (!method.renderer.empty())
    for (auto it = methodJson.begin(); it != methodJson.end(); ++it)
      if (it.key().find('.') != std::string::npos && it.key().rfind("technique.", 0) != 0 &&
          std::find(methodKeys().begin(), methodKeys().end(), it.key()) == methodKeys().end())
        applyMethodJson(method, it.key(), it.value(), "method");
  return configName(method, sceneOverrides);
}

std::string configName(const Method& method, const std::vector<SceneOverride>& sceneOverrides) {
  static const nlohmann::json defaults = methodToJson(Method{});
  const nlohmann::json resolved = methodToJson(method);
  std::vector<std::pair<std::string, std::string>> parts;
  for (const std::string& key : methodKeys()) {
    const auto value = resolved.find(key), byDefault = defaults.find(key);
    if (value == resolved.end()) continue;  // a key written only when set (technique)
    const std::string text = canonicalValueText(*value);
    if (byDefault == defaults.end() || text != canonicalValueText(*byDefault)) parts.emplace_back(key, text);
  }
  // The technique file's declared keys, every one (their defaults are the file's, not Method's); the
  // hash is not part of the name, so an edited file meets its old rows and is refused naming both.
  for (auto it = resolved.begin(); it != resolved.end(); ++it)
    if (it.key().rfind("technique.", 0) == 0 && it.key() != "technique.hash")
      parts.emplace_back(it.key(), canonicalValueText(it.value()));
  // An outside renderer's keys where they differ from its manifest's defaults.
  if (const AdapterManifest* a = rendererManifest(method)) {
    const nlohmann::json values = adapterKeyValues(method);
    for (const AdapterKey& k : a->keys)
      if (canonicalValueText(values[k.name]) != canonicalValueText(k.defaultValue))
        parts.emplace_back(a->name + "." + k.name, canonicalValueText(values[k.name]));
  }
  for (const SceneOverride& o : sceneOverrides) parts.emplace_back("scene:" + o.pointer, canonicalValueText(o.value));
  std::stable_sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::string name;
  for (const auto& [key, text] : parts) name += (name.empty() ? "" : ",") + key + "=" + text;
  return name.empty() ? "default" : name;
}

}  // namespace shadowlab
