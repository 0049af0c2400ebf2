#pragma once
#include <string>
#include <vector>

#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab {

// The --set key=value arguments of `shadowlab run`, `raster`, `reference` and `stability`, over an
// optional method file: method keys set the method (then validated), scene:/pointer keys become
// scene overrides (any JSON value: --set scene:/camera/look_at=[4,10,6]) that carry their argument
// as origin, so the scene's errors name it. A key given twice is an InputError naming both
// arguments. `config` is configName(method, sceneOverrides) (config_name.h): the name every command
// gives the configuration, so a run's row matches the sweep or tune row of the same configuration.
// InputError for a malformed argument or value.
struct SetArguments {
  Method method;
  std::vector<SceneOverride> sceneOverrides;
  std::string config;
};
SetArguments applySetArguments(const std::string& methodFile, const std::vector<std::string>& sets);

}  // namespace shadowlab
