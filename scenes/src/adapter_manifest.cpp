// adapter.json: read, checked and cached (adapter_manifest.h, adapters/README.md).
#include "shadowlab/scenes/adapter_manifest.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/number_text.h"

#ifndef SHADOWLAB_SOURCE_DIR
#error "SHADOWLAB_SOURCE_DIR must be defined by the build"
#endif

namespace shadowlab {
namespace {

namespace fs = std::filesystem;

std::string adaptersHome() {
  const char* home = std::getenv("SHADOWLAB_HOME");
  return std::string(home && *home ? home : SHADOWLAB_SOURCE_DIR) + "/adapters";
}

bool nameChars(const std::string& s, const char* extra) {
  if (s.empty() || s.size() > 64) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || std::string(extra).find(c) != std::string::npos;
    if (!ok) return false;
  }
  return true;
}

struct Reader {
  const std::string& file;
  [[noreturn]] void fail(const std::string& place, const nlohmann::json& got, const std::string& expected) const {
    throw InputError(formatError(file, place, "got " + describeJson(got) + "; expected " + expected));
  }
  [[noreturn]] void missing(const std::string& place, const std::string& expected) const {
    throw InputError(formatError(file, place, "missing; expected " + expected));
  }
  std::string text(const nlohmann::json& obj, const std::string& key, const std::string& place,
                   const std::string& expected, bool required = true) const {
    auto it = obj.find(key);
    if (it == obj.end()) {
      if (required) missing(place + "/" + key, expected);
      return "";
    }
    if (!it->is_string()) fail(place + "/" + key, *it, expected);
    return it->get<std::string>();
  }
  double number(const nlohmann::json& v, const std::string& place, const std::string& expected) const {
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(place, v, expected);
    return v.get<double>();
  }
  void onlyKeys(const nlohmann::json& obj, const std::string& place, std::initializer_list<const char*> keys) const {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      bool known = false;
      std::string list;
      for (const char* k : keys) {
        known = known || it.key() == k;
        list += (list.empty() ? "" : ", ") + std::string(k);
      }
      if (!known)
        throw InputError(formatError(file, place + "/" + jsonPointerToken(it.key()),
                                     "unknown field \"" + it.key() + "\"; expected one of " + list));
    }
  }
};

AdapterKey readKey(const Reader& r, const nlohmann::json& j, const std::string& place) {
  if (!j.is_object()) r.fail(place, j, "an object {name, type, default, help, ...}");
  r.onlyKeys(j, place, {"name", "type", "default", "min", "max", "values", "help"});
  AdapterKey k;
  k.name = r.text(j, "name", place, "a key name");
  if (!nameChars(k.name, "_.") || k.name.front() == '.' || k.name.back() == '.')
    r.fail(place + "/name", j["name"], "a key name of 1..64 lower-case letters, digits, '_' and '.'");
  const std::string type = r.text(j, "type", place, "int, number, bool or enum");
  k.help = r.text(j, "help", place, "one line of help");
  if (k.help.size() > 200 || k.help.find('\n') != std::string::npos)
    r.fail(place + "/help", j["help"], "one line of at most 200 characters");
  if (type == "int" || type == "number") {
    k.type = type == "int" ? AdapterKey::Type::Int : AdapterKey::Type::Number;
    if (!j.contains("min")) r.missing(place + "/min", "the smallest value");
    if (!j.contains("max")) r.missing(place + "/max", "the largest value");
    k.lo = r.number(j["min"], place + "/min", "a finite number");
    k.hi = r.number(j["max"], place + "/max", "a finite number");
    if (!(k.lo <= k.hi)) r.fail(place + "/max", j["max"], "a number >= min (" + numberText(k.lo) + ")");
    if (k.type == AdapterKey::Type::Int &&
        (std::floor(k.lo) != k.lo || std::floor(k.hi) != k.hi || std::fabs(k.lo) > 1e15 || std::fabs(k.hi) > 1e15))
      r.fail(place + "/min", j["min"], "whole numbers for min and max of an int key (at most 1e15)");
    if (j.contains("values")) r.fail(place + "/values", j["values"], "no values beside an int or number key");
  } else if (type == "bool") {
    k.type = AdapterKey::Type::Bool;
    for (const char* f : {"min", "max", "values"})
      if (j.contains(f)) r.fail(place + "/" + f, j[f], std::string("no ") + f + " beside a bool key");
  } else if (type == "enum") {
    k.type = AdapterKey::Type::Enum;
    if (!j.contains("values")) r.missing(place + "/values", "the enum's values, an array of strings");
    const nlohmann::json& values = j["values"];
    if (!values.is_array() || values.empty() || values.size() > 64)
      r.fail(place + "/values", values, "an array of 1..64 strings");
    for (size_t i = 0; i < values.size(); ++i) {
      const std::string at = place + "/values/" + std::to_string(i);
      if (!values[i].is_string() || !nameChars(values[i].get<std::string>(), "_-ABCDEFGHIJKLMNOPQRSTUVWXYZ"))
        r.fail(at, values[i], "a value of 1..64 letters, digits, '_' and '-'");
      for (const std::string& v : k.values)
        if (v == values[i].get<std::string>()) r.fail(at, values[i], "each value once");
      k.values.push_back(values[i].get<std::string>());
    }
    for (const char* f : {"min", "max"})
      if (j.contains(f)) r.fail(place + "/" + f, j[f], std::string("no ") + f + " beside an enum key");
  } else {
    r.fail(place + "/type", j["type"], "int, number, bool or enum");
  }
  if (!j.contains("default")) r.missing(place + "/default", "the value the renderer uses when a method sets none");
  k.defaultValue = k.accept(j["default"], false);
  if (k.defaultValue.is_null()) r.fail(place + "/default", j["default"], k.expected());
  return k;
}

}  // namespace

std::string AdapterKey::expected() const {
  switch (type) {
    case Type::Int: return "an integer " + numberText(lo) + ".." + numberText(hi);
    case Type::Number: return "a number " + numberText(lo) + ".." + numberText(hi);
    case Type::Bool: return "true or false";
    case Type::Enum: {
      std::string s = "one of ";
      for (size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + values[i];
      return s;
    }
  }
  return "";
}

nlohmann::json AdapterKey::accept(const nlohmann::json& value, bool fromText) const {
  if (type == Type::Enum) {
    if (!value.is_string()) return nullptr;
    for (const std::string& v : values)
      if (v == value.get<std::string>()) return v;
    return nullptr;
  }
  if (type == Type::Bool) {
    if (value.is_boolean()) return value;
    if (fromText && value.is_string()) {
      const std::string& t = value.get_ref<const std::string&>();
      if (t == "true" || t == "1") return true;
      if (t == "false" || t == "0") return false;
    }
    return nullptr;
  }
  double x = 0;
  if (value.is_number()) {
    x = value.get<double>();
  } else if (fromText && value.is_string()) {
    const std::string& t = value.get_ref<const std::string&>();
    if (t.empty() || t.size() > 40) return nullptr;
    for (char c : t)
      if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'))
        return nullptr;
    char* end = nullptr;
    x = std::strtod(t.c_str(), &end);
    if (end != t.c_str() + t.size()) return nullptr;
  } else {
    return nullptr;
  }
  if (!std::isfinite(x) || x < lo || x > hi) return nullptr;
  if (type == Type::Int) {
    if (std::floor(x) != x) return nullptr;
    return static_cast<long long>(x);
  }
  return x;
}

const AdapterKey* AdapterManifest::find(const std::string& key) const {
  for (const AdapterKey& k : keys)
    if (k.name == key) return &k;
  return nullptr;
}

std::string resolveAdapterPath(const std::string& value) {
  const bool isPath =
      value.find('/') != std::string::npos || (value.size() > 5 && value.compare(value.size() - 5, 5, ".json") == 0);
  if (isPath) return value;
  return adaptersHome() + "/" + value + "/adapter.json";
}

std::vector<std::string> bundledAdapterNames() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(adaptersHome(), ec))
    if (e.is_directory(ec) && fs::is_regular_file(e.path() / "adapter.json", ec))
      names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

const AdapterManifest& loadAdapterManifest(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw InputError(
        formatError(path, "", "no such file; expected an adapter manifest (adapter.json, adapters/README.md)"));
  const std::string bytes = readFileAtMost(path, kAdapterManifestMaxBytes, "an adapter manifest");
  const std::string hash = hashHex(fnv1a64(bytes.data(), bytes.size()));
  static std::mutex mutex;
  // Never erased: references stay valid, and an edited file is a new entry (a new hash).
  static std::map<std::string, std::unique_ptr<AdapterManifest>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[path + '\n' + hash];
  if (slot) return *slot;

  const nlohmann::json j = parseJsonText(bytes, path);
  const Reader r{path};
  if (!j.is_object()) r.fail("", j, "a JSON object (adapters/README.md)");
  r.onlyKeys(j, "", {"shadowlab_adapter", "name", "description", "command", "timeout_s", "frame", "keys"});
  auto m = std::make_unique<AdapterManifest>();
  m->path = path;
  m->dir = fs::absolute(fs::path(path).parent_path(), ec).lexically_normal().string();
  m->hash = hash;
  if (!j.contains("shadowlab_adapter")) r.missing("/shadowlab_adapter", "the protocol version, 1");
  if (j["shadowlab_adapter"] != kAdapterProtocol) r.fail("/shadowlab_adapter", j["shadowlab_adapter"], "1");
  m->name = r.text(j, "name", "", "the adapter's name");
  if (!nameChars(m->name, "-_"))
    r.fail("/name", j["name"], "a name of 1..64 lower-case letters, digits, '-' and '_' (the prefix of its keys)");
  m->description = r.text(j, "description", "", "one line", false);
  if (m->description.size() > 200 || m->description.find('\n') != std::string::npos)
    r.fail("/description", j["description"], "one line of at most 200 characters");
  if (!j.contains("command")) r.missing("/command", "the program and its arguments, an array of strings");
  const nlohmann::json& command = j["command"];
  if (!command.is_array() || command.empty() || command.size() > kAdapterMaxArgs)
    r.fail("/command", command, "an array of 1.." + std::to_string(kAdapterMaxArgs) + " strings");
  bool takesRequest = false;
  for (size_t i = 0; i < command.size(); ++i) {
    const std::string at = "/command/" + std::to_string(i);
    if (!command[i].is_string() || command[i].get<std::string>().empty() ||
        command[i].get<std::string>().find('\0') != std::string::npos)
      r.fail(at, command[i], "a non-empty string");
    takesRequest = takesRequest || command[i].get<std::string>().find("{request}") != std::string::npos;
    m->command.push_back(command[i].get<std::string>());
  }
  if (!takesRequest) r.fail("/command", command, "an argument holding {request} (the request file's path)");
  if (j.contains("timeout_s")) {
    const nlohmann::json& t = j["timeout_s"];
    if (!t.is_object()) r.fail("/timeout_s", t, "an object {start, per_frame} of seconds");
    r.onlyKeys(t, "/timeout_s", {"start", "per_frame"});
    const std::string range = "a number of seconds > 0 and <= " + numberText(kAdapterMaxTimeoutS);
    auto seconds = [&](const char* key, double& out) {
      if (!t.contains(key)) return;
      out = r.number(t[key], std::string("/timeout_s/") + key, range);
      if (!(out > 0 && out <= kAdapterMaxTimeoutS)) r.fail(std::string("/timeout_s/") + key, t[key], range);
    };
    seconds("start", m->startTimeoutS);
    seconds("per_frame", m->perFrameTimeoutS);
  }
  const std::string frame = r.text(j, "frame", "", "png or shadowlab");
  if (frame == "png") m->frame = AdapterManifest::FrameKind::Png;
  else if (frame == "shadowlab") m->frame = AdapterManifest::FrameKind::Shadowlab;
  else r.fail("/frame", j["frame"], "png (vis.png, coverage.png, renderer.json) or shadowlab (raster.exr)");
  if (!j.contains("keys")) r.missing("/keys", "an array of the keys the renderer takes (may be empty)");
  const nlohmann::json& keys = j["keys"];
  if (!keys.is_array() || keys.size() > kAdapterMaxKeys)
    r.fail("/keys", keys, "an array of at most " + std::to_string(kAdapterMaxKeys) + " keys");
  for (size_t i = 0; i < keys.size(); ++i) {
    const std::string at = "/keys/" + std::to_string(i);
    AdapterKey k = readKey(r, keys[i], at);
    if (m->find(k.name)) r.fail(at + "/name", keys[i]["name"], "each key once");
    m->keys.push_back(std::move(k));
  }
  slot = std::move(m);
  return *slot;
}

}  // namespace shadowlab
