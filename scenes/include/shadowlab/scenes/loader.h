#pragma once
// Scene files: JSON (comments allowed), documented in scenes/FORMAT.md.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// A value to put at a JSON pointer of the scene document before it is resolved
// (sweeps use it: --grid scene:/lights/0/elevation_deg=60,30).
struct SceneOverride {
  std::string pointer;  // e.g. "/lights/0/elevation_deg"
  nlohmann::json value;
  // Where the value came from ("--set scene:/camera/width=0", "sweep.json: /grid/..."): an error
  // at or below `pointer` then names it first, the scene file and place after. Empty: the file.
  std::string origin = {};
};

// Loads, validates and resolves a scene file. Relative paths inside it (OBJ, textures, images)
// are relative to the scene file's folder; the token "${SHARED}" at the start of a path means the
// shared assets folder (SHADOWLAB_SHARED_DIR env var, else ../shared beside the source tree).
// Throws InputError with a GCC-style message naming the file and place (line:col for syntax
// errors, JSON pointer otherwise).
Scene loadScene(const std::string& path, const std::vector<SceneOverride>& overrides = {});

// Where the bundled scenes live (<home>/scenes/data: <home> is $SHADOWLAB_HOME when set, e.g. by an
// unpacked bundle's launcher, else the source tree this binary was built from) and the shared
// assets folder.
std::string bundledScenesDir();
std::string sharedAssetsDir();
// The bundled scene names in a stable order.
std::vector<std::string> bundledSceneNames();
// "sphere_on_plane" -> "<source>/scenes/data/sphere_on_plane.json"; a path with a '/' or ending
// in .json is returned unchanged.
std::string resolveScenePath(const std::string& nameOrPath);

}  // namespace shadowlab
