// `shadowlab methods [--json]`: every method key with its type, default, range and one line of
// help, from the method parser's own table (methodKeyTable(), scenes/src/method.cpp): the keys
// files, --set and --grid accept, the defaults a method starts from, the ranges they are checked
// against, in the parser's words. raster/METHODS.md explains them at length.
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "command.h"
#include "shadowlab/scenes/adapter_manifest.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/method_keys.h"

namespace cmd_methods {
namespace {

using namespace shadowlab;

// An outside renderer's keys (its manifest's table, adapters/README.md), each as NAME.KEY.
std::vector<MethodKeyInfo> rendererKeyTable(const AdapterManifest& a) {
  std::vector<MethodKeyInfo> rows;
  for (const AdapterKey& k : a.keys) {
    const char* type = k.type == AdapterKey::Type::Int      ? "integer"
                       : k.type == AdapterKey::Type::Number ? "number"
                       : k.type == AdapterKey::Type::Bool   ? "boolean"
                                                            : "choice";
    rows.push_back({a.name + "." + k.name, type, k.defaultValue, k.expected(), k.help});
  }
  return rows;
}

int run(bool json, const std::string& renderer) {
  const AdapterManifest* adapter = renderer.empty() ? nullptr : &loadAdapterManifest(resolveAdapterPath(renderer));
  const std::vector<MethodKeyInfo> table = adapter ? rendererKeyTable(*adapter) : methodKeyTable();
  if (json) {
    nlohmann::json rows = nlohmann::json::array();
    for (const MethodKeyInfo& k : table)
      rows.push_back({{"key", k.key},
                      {"type", k.type},
                      {"default", k.defaultValue},
                      {"range", k.range},
                      {"help", k.help}});
    nlohmann::json doc = {{"schema", "shadowlab.methods/1"}, {"keys", rows}};
    if (adapter)
      doc["renderer"] = {{"name", adapter->name}, {"path", adapter->path}, {"description", adapter->description}};
    std::printf("%s\n", doc.dump(2).c_str());
    return 0;
  }
  if (adapter)
    std::printf("renderer=%s: %s (%s)\n", renderer.c_str(), adapter->description.c_str(), adapter->path.c_str());
  size_t keyWidth = 0;
  for (const MethodKeyInfo& k : table) keyWidth = std::max(keyWidth, k.key.size());
  for (const MethodKeyInfo& k : table) {
    // methodToJson wrote each float default as its shortest text (jsonFloat): "0.0005".
    const nlohmann::json& d = k.defaultValue;
    const std::string defaultText = d.is_null() ? "none" : d.is_string() ? d.get<std::string>() : d.dump();
    std::printf("%-*s  %s, default %s: %s\n%-*s  expected %s\n", int(keyWidth), k.key.c_str(), k.type.c_str(),
                defaultText.c_str(), k.help.c_str(), int(keyWidth), "", k.range.c_str());
  }
  return 0;
}

shadowlab::app::Registrar reg{"methods", [](CLI::App& app) {
                                auto json = std::make_shared<bool>(false);
                                auto renderer = std::make_shared<std::string>();
                                auto* sub = app.add_subcommand(
                                    "methods",
                                    "List every method key (--set, --grid, method files): type, default, range, help");
                                sub->add_flag("--json", *json, "Print the keys as JSON (schema shadowlab.methods/1)");
                                sub->add_option("--renderer", *renderer,
                                                "List an outside renderer's keys instead: a bundled adapter's name "
                                                "or its adapter.json (adapters/README.md)");
                                return std::function<int()>([json, renderer] { return run(*json, *renderer); });
                              }};

}  // namespace
}  // namespace cmd_methods
