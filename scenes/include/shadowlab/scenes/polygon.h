#pragma once
// Polygon faces (an OBJ "f" line with more than three corners) -> triangles.
//
// A face that is convex seen along its normal is cut the simple way: a quad along its shorter
// diagonal (tinyobjloader's own rule, in its float arithmetic, so meshes of triangles and convex
// quads load bit for bit as they did through it), five or more corners fanned from the first.
// Any other face is ear-clipped (the rules of mapbox/earcut) in the plane it lies in: a simple
// polygon of n corners gives n - 2 triangles covering exactly its area, including the "keyhole"
// polygons exporters write for a face with a hole (the outer loop, a bridge edge, the inner loop
// and the same bridge back). A non-convex face that is not flat (a corner farther than
// kPolygonPlanarTolerance of its size from its plane) or whose edges cross is refused: no
// triangulation of it is the surface its author meant.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace shadowlab {

// A corner of a non-convex face may lie at most this fraction of the face's size (its bounding
// box diagonal) from the face's plane.
constexpr double kPolygonPlanarTolerance = 0.01;
// Corners of a non-convex face at most (ear clipping is quadratic in them, at least).
constexpr size_t kMaxConcavePolygonCorners = 4096;

struct PolygonTriangles {
  // Corner indices (into the face's corner list), wound the way the face is.
  std::vector<std::array<uint32_t, 3>> triangles;
  // Empty when the face was triangulated; else why not, as "what; expected ..." for an error message.
  std::string error;
};

// `corners`: the face's corner positions in order. Three corners give the face itself.
PolygonTriangles triangulatePolygon(const std::vector<glm::vec3>& corners);

}  // namespace shadowlab
