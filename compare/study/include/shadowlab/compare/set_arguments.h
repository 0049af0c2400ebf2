#pragma once
#include <string>
#include <vector>

#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab {

// The --set key=value arguments of `shadowlab run` and `shadowlab stability`, over an optional
// method file: method keys set the method (then validated), scene:/pointer keys become scene
// overrides, as in sweeps (sweep.h; the last --set of a key wins). `config` names the row like a
// sweep row of the same configuration: the canonical "key=value" of the given keys sorted by key (method keys
// with the resolved method's value); with no --set, the method's name, else "default".
// InputError for a malformed argument or value.
struct SetArguments {
  Method method;
  std::vector<SceneOverride> sceneOverrides;
  std::string config;
};
SetArguments applySetArguments(const std::string& methodFile, const std::vector<std::string>& sets);

}  // namespace shadowlab
