// `shadowlab methods [--json]`: every method key with its type, default, range and one line of
// help, from the method parser's own table (methodKeyTable(), scenes/src/method.cpp): the keys
// files, --set and --grid accept, the defaults a method starts from, the ranges they are checked
// against, in the parser's words. raster/METHODS.md explains them at length.
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "command.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/method_keys.h"

namespace {

using namespace shadowlab;

int run(bool json) {
  const std::vector<MethodKeyInfo>& table = methodKeyTable();
  if (json) {
    nlohmann::json rows = nlohmann::json::array();
    for (const MethodKeyInfo& k : table)
      rows.push_back({{"key", k.key},
                      {"type", k.type},
                      {"default", k.defaultValue},
                      {"range", k.range},
                      {"help", k.help}});
    std::printf("%s\n", nlohmann::json{{"schema", "shadowlab.methods/1"}, {"keys", rows}}.dump(2).c_str());
    return 0;
  }
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
                                auto* sub = app.add_subcommand(
                                    "methods",
                                    "List every method key (--set, --grid, method files): type, default, range, help");
                                sub->add_flag("--json", *json, "Print the keys as JSON (schema shadowlab.methods/1)");
                                return std::function<int()>([json] { return run(*json); });
                              }};

}  // namespace
