// --set key=value arguments of `shadowlab run` and `shadowlab stability` (set_arguments.h).
#include "shadowlab/compare/set_arguments.h"

#include <map>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {

SetArguments applySetArguments(const std::string& methodFile, const std::vector<std::string>& sets) {
  SetArguments a;
  if (!methodFile.empty()) a.method = loadMethodFile(methodFile);
  std::map<std::string, std::string> given;  // key -> canonical value, sorted
  for (const auto& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--set " + s + ": error: got \"" + s + "\"; expected key=value (e.g. map.size=4096)");
    const std::string key = s.substr(0, eq), value = s.substr(eq + 1);
    if (key.rfind(kSceneKeyPrefix, 0) == 0) {
      const nlohmann::json v = sceneValueFromText(value);
      a.sceneOverrides.push_back({key.substr(std::string(kSceneKeyPrefix).size()), v});  // in order: the last wins
      given[key] = canonicalValueText(v);
    } else {
      applyMethodSetting(a.method, key, value, "--set " + s);
      given[key] = "";  // the resolved method's value, below
    }
  }
  validateMethod(a.method, methodFile.empty() ? "--set" : methodFile);
  const nlohmann::json resolved = methodToJson(a.method);
  for (auto& [key, text] : given) {
    if (key.rfind(kSceneKeyPrefix, 0) != 0) text = canonicalValueText(resolved.at(key));
    a.config += (a.config.empty() ? "" : ",") + key + "=" + text;
  }
  if (a.config.empty()) a.config = a.method.name.empty() ? "default" : a.method.name;
  return a;
}

}  // namespace shadowlab
