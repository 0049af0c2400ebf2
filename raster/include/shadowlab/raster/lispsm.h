#pragma once
// Light-space perspective shadow maps (fit=lispsm): the warp's pieces as pure functions, no GPU.
// Wimmer, Scherzer, Purgathofer, "Light Space Perspective Shadow Maps", EGSR 2004.
//
// In light space (the light looking down -z), a perspective frustum P whose axis is the camera's
// view direction projected perpendicular to the light, its projection center a distance n before
// the near face of the body B, is applied before the orthographic fit of the map; near the camera
// the map gets more texels, far away fewer. P's axis is perpendicular to the light, so its w is
// constant along every light ray and the order of depths along a ray is kept: the shadow test
// stays a depth comparison.
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/scenes/scene.h"

namespace shadowlab::raster {

// The vertices (world space) of the convex body V n S: the camera's view frustum (its own
// [near, far] with cascades.h's guards) intersected with the box [boxMin, boxMax] (the scene's).
// Each vertex is where three of the twelve bounding planes meet inside all the others, so the
// extremes of any linear function over the body (the view depth, light-space x and y) are among
// them. Empty when frustum and box do not intersect. fit=lispsm takes its depth range [z_n, z_f]
// and its body B from these points over every object's box: fit=tight's clip (the scene box's
// corners) leaves z_n at the camera's near plane whenever the camera stands inside the box's
// depth range, and with z_n = 0.01 n_opt degenerates to a warp that spends the map on the empty
// space before the scene (measured: sphere_on_plane, 1024, m_p95 4.2 with tight, 64.6 so, 4.0
// with the body).
std::vector<glm::dvec3> viewBoxIntersection(const Camera& camera, glm::vec3 boxMin, glm::vec3 boxMax);

// The light space the warp works in: the light's view space (lightViewFromWorld, the light
// looking down -z) rotated about z so that +y is the camera's view direction (viewForwardWorld,
// unit) projected perpendicular to the light. sinGamma = sin of the angle gamma between the view
// direction and the light's direction (0..1; the same for a light from behind and from ahead).
// Where the projection is zero (view exactly along the light: no axis), the rotation is the
// identity and sinGamma is 0.
struct LispsmBasis {
  glm::dmat4 lightFromWorld{1.0};
  double sinGamma = 0;
};
LispsmBasis lispsmBasis(const glm::mat4& lightViewFromWorld, glm::vec3 viewForwardWorld);

// 1 / n, n the distance of P's projection center from B's near face (world units):
//   n = nScale * n_opt,  n_opt = (z_n + sqrt(z_n z_f)) / sin(gamma)   (Wimmer et al., section 5)
// with [z_n, z_f] the camera's view depth range (clipped to the scene as fit=tight does). Returned
// as the inverse so that the view along the light (sinGamma -> 0, n -> infinity) is 0 and
// continuous: no warp, the orthographic fit. 0 for sinGamma <= 0 or non-finite input.
double lispsmInverseNear(double zNear, double zFar, double sinGamma, double nScale);

// The map of the body B = [bodyMin, bodyMax] in the warp's light space (x lateral, y the warp
// axis, z towards the light: bodyMax.z is the face nearest the light), the projection center at
// x = eyeX (the camera's), y = bodyMin.y - n, inverseNear = 1 / n. With t = (y - y0) / (y1 - y0):
//   w           = 1 + (y - y0) / n            (1 on B's near face, 1 + d/n on its far face)
//   u * w       = (x - eyeX) - Xmin * w, over (Xmax - Xmin); X = (x - eyeX) / w over B's corners
//   v * w       = 1 - t                       (v = 0 on the far face, 1 on the near face)
//   depth * w   = (z1 - z) / (z1 - z0)        (0 at the face nearest the light)
// so u, v, depth lie in [0, 1] over B and each is affine in P's post-perspective coordinates
// (x / w, 1 / w, z / w): an orthographic fit after the perspective. inverseNear = 0 is exactly the
// orthographic box fit of fit=tight (u = (x - x0) / Wx, v = (y1 - y) / d, depth as above).
// texelWorldPerW: max(Xmax - Xmin, y1 - y0) / mapSize. A texel at w is (Xmax - Xmin) w / mapSize
// wide across the axis and d w^2 / ((1 + d/n) mapSize) long along it, so texelWorldPerW * w is an
// upper bound of the texel's larger side everywhere in B, exact on the far face (w = 1 + d/n),
// and at inverseNear = 0 it is fit=tight's texelWorld (the larger side / mapSize).
struct LispsmMap {
  glm::dmat4 texFromLight{1.0};  // light (warp basis) -> (u*w, v*w, depth*w, w), as light_space.h
  double texelWorldPerW = 0;
};
LispsmMap lispsmTexFromLight(glm::dvec3 bodyMin, glm::dvec3 bodyMax, double eyeX, double inverseNear, int mapSize);

}  // namespace shadowlab::raster
