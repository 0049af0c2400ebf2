// --set key=value arguments of `shadowlab run`, `raster`, `reference` and `stability`
// (set_arguments.h).
#include "shadowlab/compare/set_arguments.h"

#include <map>

#include "shadowlab/compare/config_name.h"
#include "shadowlab/compare/sweep.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {

SetArguments applySetArguments(const std::string& methodFile, const std::vector<std::string>& sets) {
  SetArguments a;
  if (!methodFile.empty()) a.method = loadMethodFile(methodFile);
  std::map<std::string, std::string> given;  // key -> the argument that set it
  for (const auto& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--set " + s + ": error: got \"" + s + "\"; expected key=value (e.g. map.size=4096)");
    const std::string key = s.substr(0, eq), value = s.substr(eq + 1);
    const std::string origin = "--set " + s;
    // The same key twice would silently keep one of them: refuse it, naming both.
    const auto [first, fresh] = given.emplace(key, origin);
    if (!fresh)
      throw InputError(formatError(
          origin, "", "\"" + key + "\" is set again (first by " + first->second + "); expected each key once"));
    if (key.rfind(kSceneKeyPrefix, 0) == 0)
      a.sceneOverrides.push_back({key.substr(std::string(kSceneKeyPrefix).size()), sceneValueFromText(value), origin});
    else applyMethodSetting(a.method, key, value, origin);
  }
  validateMethod(a.method, methodFile.empty() ? "--set" : methodFile);
  a.config = configName(a.method, a.sceneOverrides);
  return a;
}

}  // namespace shadowlab
