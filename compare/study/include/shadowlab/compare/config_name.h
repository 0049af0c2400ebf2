#pragma once
// The one name of a configuration: ResultRow::config in metrics.json, results.json/csv,
// stability.json, tune.json and a sweep journal, and the folder of its pictures. `shadowlab gate`
// matches rows by (scene, config, light), so every command that writes a row names it here, from
// what the configuration is (its resolved method and its scene: values), never from which keys a
// command was given: a run can then be gated against the sweep or tune row of the same
// configuration however either was spelled (compare/SWEEPS.md, "Rows and configuration names").
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab {

// The canonical text of one value: strings as they are, booleans true/false, integers plainly,
// other numbers as the shortest text that reads back to the same double (0.0005, 1.5, 1e-06; an
// integral one without a fraction: 2.0 -> "2"), so "0.50", 0.5 and 5e-1 are the same value;
// arrays and objects as compact JSON of canonical elements ([4,10,6]).
std::string canonicalValueText(const nlohmann::json& value);

// "key=value,..." sorted by key, of every method key whose resolved value differs from its default
// (Method{}, raster/METHODS.md) and of every scene: value ("scene:/camera/width=320", named even
// when it equals the file's own value); "default" when there is none. The method's "name" is not
// part of it. `methodJson` is methodToJson's object (a key it lacks counts as the default), read
// through the method parser (applyMethodJson), so a float widened to a double by an older build
// (0.10000000149011612) is named as the float's shortest text (0.1).
std::string configName(const nlohmann::json& methodJson, const std::vector<SceneOverride>& sceneOverrides);
std::string configName(const Method& method, const std::vector<SceneOverride>& sceneOverrides);

}  // namespace shadowlab
