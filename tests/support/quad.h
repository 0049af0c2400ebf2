#pragma once
// A flat quad as a scene object (two triangles, material 0): the hand-built scenes of the raster
// unit tests (a floor and a roof, a ground and a blocker).
#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "shadowlab/scenes/scene.h"

namespace shadowlab::testing {

// The quad corner, corner + u, corner + u + v, corner + v, named "quad<id>".
inline void addQuad(Scene& s, uint32_t id, glm::vec3 corner, glm::vec3 u, glm::vec3 v) {
  Object o;
  o.name = "quad" + std::to_string(id);
  o.id = id;
  o.positions = {corner, corner + u, corner + u + v, corner + v};
  o.triangles = {{0, 1, 2}, {0, 2, 3}};
  o.triangleMaterial = {0, 0};
  s.objects.push_back(o);
}

}  // namespace shadowlab::testing
