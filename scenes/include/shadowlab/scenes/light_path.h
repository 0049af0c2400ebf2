#pragma once
// Light paths: a directional light's motion for temporal stability (`shadowlab stability
// --light-path`, compare/METRICS.md "Temporal stability"), beside the camera paths
// (camera_path.h). Each frame is the scene loaded with the overrides of that frame.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// One moving angle of a directional light: `--light-path elevation_deg=60:10:11` moves the sun's
// elevation from 60 to 10 degrees in 11 frames (both ends included, equal steps).
struct LightPathAxis {
  std::string key;  // "elevation_deg" or "azimuth_deg" (scenes/FORMAT.md, lights)
  double from = 0, to = 0;
  int frames = 0;  // 2..kMaxPathFrames
  double value(int k) const { return from + (to - from) * double(k) / double(frames - 1); }
};
// Parses "KEY=FROM:TO:FRAMES". InputError "--light-path TEXT: error: ..." on anything else: an
// unknown key, a non-finite number, an elevation outside -90..90, frames outside 2..kMaxPathFrames.
LightPathAxis parseLightPath(const std::string& text);

// The scene overrides that put light `lightName` of `scene` at frame k of the axes (one or two
// axes with distinct keys and the same frames; InputError otherwise, or when the light is not
// directional). A light declared with elevation_deg in the file gets elevation_deg/azimuth_deg
// overrides; one declared with a direction gets a direction override computed from its angles
// (the angle not moved keeps its value). `sceneDocument`: the scene file as parsed (to see how
// the light is declared).
std::vector<SceneOverride> lightPathOverrides(const nlohmann::json& sceneDocument, const Scene& scene,
                                              const std::string& lightName, const std::vector<LightPathAxis>& axes,
                                              int k);

}  // namespace shadowlab
