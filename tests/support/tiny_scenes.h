#pragma once
// Scenes of the evidence-on-demand tests (compare_on_demand_test, compare_context_test): a bundled
// scene at 160x90, and its first light made a spot or a point light.
#include <string>

#include <glm/glm.hpp>

#include "shadowlab/scenes/loader.h"

namespace shadowlab::testing {

inline Scene tinyScene(const std::string& name) {
  Scene s = loadScene(resolveScenePath(name));
  s.camera.width = 160;
  s.camera.height = 90;
  return s;
}

// The scene's first light made a spot (kind 1) or a point light (kind 2), placed back along its
// direction from the scene's centre, so it lights what the directional light lit; kind 0: as is.
inline Scene withLight(Scene s, int kind) {
  if (kind == 0) return s;
  Light& l = s.lights.front();
  const glm::vec3 lo = s.boundsMin(), hi = s.boundsMax();
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = 0.5f * glm::length(hi - lo);
  l.position = centre - l.direction * (kind == 1 ? 1.6f : 1.2f) * radius;
  l.type = kind == 1 ? LightType::Spot : LightType::Point;
  l.coneDeg = 90.0f;
  l.nearPlane = 0.02f * radius;
  return s;
}

}  // namespace shadowlab::testing
