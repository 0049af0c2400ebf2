#pragma once
// An outside renderer's manifest, `adapter.json` (adapters/README.md): the command that starts it,
// the keys it takes (the same table form as a technique file's keys) and what it returns. A method
// names it with renderer= and sets its keys as NAME.KEY (method.h).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace shadowlab {

constexpr int kAdapterProtocol = 1;
// Bounds on what a manifest may ask for: its size, its keys, its command.
constexpr size_t kAdapterManifestMaxBytes = 256 * 1024;
constexpr size_t kAdapterMaxKeys = 256;
constexpr size_t kAdapterMaxArgs = 64;
constexpr double kAdapterMaxTimeoutS = 24 * 3600.0;

struct AdapterKey {
  enum class Type { Int, Number, Bool, Enum };
  std::string name;  // letters, digits, '_' and '.'
  Type type = Type::Number;
  nlohmann::json defaultValue;
  double lo = 0, hi = 0;            // int, number
  std::vector<std::string> values;  // enum
  std::string help;
  // What a value of this key must be, in the words of "got X; expected Y".
  std::string expected() const;
  // `value` as this key's typed JSON value, or null when it is not one (wrong type, out of range).
  // `fromText`: the value came from the command line as text ("0.05", "true", "PCF").
  nlohmann::json accept(const nlohmann::json& value, bool fromText) const;
};

struct AdapterManifest {
  std::string path;  // the manifest file, as resolved
  std::string dir;   // its folder: the command runs there
  std::string name;  // the prefix of its keys in a method
  std::string description;
  std::vector<std::string> command;  // {request} and {shadowlab} are replaced when it runs
  double startTimeoutS = 60, perFrameTimeoutS = 30;
  enum class FrameKind { Png, Shadowlab } frame = FrameKind::Png;
  std::vector<AdapterKey> keys;
  std::string hash;  // of the manifest's bytes: a row records it, an edited manifest is another renderer
  const AdapterKey* find(const std::string& key) const;
};

// renderer=VALUE: a bundled adapter's name (adapters/NAME/adapter.json under $SHADOWLAB_HOME, else
// the source tree) when VALUE has no '/' and does not end in .json; otherwise the path as given.
std::string resolveAdapterPath(const std::string& value);
// The bundled adapters' names (folders of adapters/ holding an adapter.json), sorted.
std::vector<std::string> bundledAdapterNames();

// Reads and checks a manifest (InputError naming the file and the JSON place). Cached by path and
// content: the reference stays valid for the process.
const AdapterManifest& loadAdapterManifest(const std::string& path);

}  // namespace shadowlab
