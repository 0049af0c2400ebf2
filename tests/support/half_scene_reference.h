#pragma once
// The bundled scenes at half their pixels (480x270 for the 960x540 ones) and their Embree
// reference, traced once per (scene, width) and executable: what the raster-against-reference
// tests compare against.
#include <map>
#include <string>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"

namespace shadowlab::testing {

inline Scene halfScene(const std::string& name) {
  Scene s = loadScene(resolveScenePath(name));
  s.camera.width /= 2;
  s.camera.height /= 2;
  return s;
}

inline const Frame& cachedReference(const Scene& s) {
  static std::map<std::string, Frame> cache;
  const std::string key = s.name + "/" + std::to_string(s.camera.width);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  return cache.emplace(key, renderReference(s, ReferenceOptions{})).first->second;
}

}  // namespace shadowlab::testing
