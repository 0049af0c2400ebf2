#pragma once
// Trapezoidal shadow maps (fit=tsm): the fit's pieces as pure functions, no GPU.
// Martin, Tan, "Anti-aliasing and Continuity with Trapezoidal Shadow Maps", EGSR 2004.
//
// For a directional light the light's post-projective space is its (orthographic) view space:
// x, y the image plane, z towards the light. The part of the camera's view frustum that holds the
// scene, projected onto the image plane, is enclosed in a trapezoid whose top and base are
// perpendicular to the center line (through the projected centers of the near and far faces),
// the top on the camera's side. N_T, the 2D perspective that maps the trapezoid onto the square,
// gives the map's u, v and w: near the camera the map gets more texels, far away fewer. N_T acts
// on x and y alone, so w is constant along every light ray (a ray is a line of constant x, y):
// the order of depths along a ray is the world's.
#include <array>
#include <vector>

#include <glm/glm.hpp>

namespace shadowlab::raster {

// The 80 % rule (Martin & Tan, section 6): the distance eta of the projection point q before the
// top line such that the point a distance deltaPrime behind the top line (the end of the focus
// region, on the center line) maps to the line xi = 1 - 2 focusLine of the map (top +1, base -1;
// focusLine = 0.8: the paper's xi = -0.6, the focus region gets 80 % of the map), lambda the
// distance between top and base:
//   eta = lambda deltaPrime (1 + xi) / (lambda (1 - xi) - 2 deltaPrime)
// derived from the 1D perspective y(s) = a - b / s (s the distance from q) with y(eta) = +1 and
// y(eta + lambda) = -1. Infinite where no eta > 0 exists: deltaPrime >= focusLine * lambda (the
// uniform map already gives the focus region that share) or non-finite input; 0 for
// deltaPrime <= 0 (q on the top line: a singular warp; the caller falls back).
double tsmEta(double lambda, double deltaPrime, double focusLine);

// N_T in 2D homogeneous coordinates: (x, y, 1) in the image plane -> (X w, Y w, w), mapping the
// trapezoid's corners to the square's: t0 -> (-1, -1), t1 -> (+1, -1), t2 -> (+1, +1),
// t3 -> (-1, +1); t0 t1 the base, t3 t2 the top (parallel to the base, the shorter of the two),
// t0 t3 and t1 t2 the sides, which meet in q behind the top. Built as the paper's sequence:
// the top's center to the origin and the top along x (T1, R), q to the origin (T2), the shear H
// that centers the trapezoid on the y axis, the scale S1 that puts its sides at 45 degrees, the
// perspective N that makes them parallel, and T3, S2 that fit the result to [-1, 1]^2 (here y is
// the distance s from q along the axis, w = s; normalized so that w = 1 on the top).
glm::dmat3 tsmTrapezoidToSquare(const std::array<glm::dvec2, 4>& t);

// The whole fit in the image plane. `hull`: the points whose convex hull is the projected body
// (only x, y are read); nearCenter, farCenter: the projected centers of the body's near and far
// view-depth faces (the center line); focusPoint: the projected end of the focus region on the
// view axis; depth over [zMin, zMax] (light view z, zMax nearest the light).
struct TsmMap {
  // false (fall back): an empty hull, no center line (the centers closer than 1e-4 of the hull's
  // extent from nearCenter: the view along the light), or no eta.
  bool valid = false;
  std::array<glm::dvec2, 4> trapezoid{};  // t0, t1 (base), t2, t3 (top), as tsmTrapezoidToSquare
  glm::dvec2 q{0.0};                      // where the sides meet
  double lambda = 0, deltaPrime = 0, eta = 0;
  // light view -> (u*w, v*w, depth*w, w), as light_space.h: u, v from N_T (v = 0 on the top
  // line, v = focusLine at the focus point), w = s / eta (1 on the top, 1 + lambda/eta on the
  // base), depth*w = (zMax - z) / (zMax - zMin): depth = that / w, the order along a light ray kept.
  glm::dmat4 texFromLight{1.0};
  // The light's own depth, unwarped: depth = dot(depthFromLight, (p, 1)) = (zMax - z) / (zMax - zMin).
  // fit=tsm's map holds this one (MapLayer::lightDepth), as the paper does: texFromLight's z / w
  // only places the vertices for the clipper.
  glm::dvec4 depthFromLight{0.0};
  // An upper bound of a texel's larger side per unit of w (world units): max(top width,
  // lambda sqrt(1 + slope^2)) / mapSize, slope the steeper side's against the center line.
  double texelWorldPerW = 0;
};
TsmMap tsmFit(const std::vector<glm::dvec3>& hull, glm::dvec2 nearCenter, glm::dvec2 farCenter, glm::dvec2 focusPoint,
              double focusLine, double zMin, double zMax, int mapSize);

}  // namespace shadowlab::raster
