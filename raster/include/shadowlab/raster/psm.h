#pragma once
// Perspective shadow maps (fit=psm): the fit's pieces as pure functions, no GPU.
// Stamminger, Drettakis, "Perspective Shadow Maps", SIGGRAPH 2002; the virtual camera slide-back
// for casters behind the viewer as in Kozlov, "Perspective Shadow Maps: Care and Feeding", GPU
// Gems 1, ch. 14.
//
// The map is rendered in the post-perspective space (PPS) of a virtual camera: the fit camera
// slid back along its view axis. The camera's projection turns the directional light into the
// homogeneous point C = clipFromWorld * (towardLight, 0): a point light at c = C.xyz / C.w on the
// camera's infinity plane when C.w != 0, a directional light (along -C.xyz) when C.w = 0 (light
// perpendicular to the view direction). The map is a perspective projection from c of the body in
// PPS. The composition (map projection) x (camera projection) is one projective 4x4, so it fits
// light_space.h's contract texFromWorld * (p, 1) = (u w, v w, depth w, w).
//
// Source and sink. C.w > 0 (the light ahead of the viewer): the light rays leave c, depth grows
// with the distance from c. C.w < 0 (the light behind the viewer; in PPS "beyond infinity"): the
// rays converge on c (the vanishing point of the light's direction of travel) and depth must
// shrink with the distance from c: the projection is inverted, near and far swapped (Kozlov's
// inverse projection). Both are one formula, with sigma = sign(C.w), in psmTexFromClip.
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/scenes/scene.h"

namespace shadowlab::raster {

// The light in post-perspective space.
enum class PsmLight {
  Directional,  // C.w = 0: the light perpendicular to the view direction stays directional
  Source,       // C.w > 0: a point light ahead of the viewer, rays leave it
  Sink,         // C.w < 0: the light behind the viewer, rays converge on it (inverted projection)
};
const char* toString(PsmLight kind);

// The virtual camera: the fit camera moved back by `slide` (world units) along its view axis,
// its projection (OpenGL-style: x, y in [-1, 1] at the frustum's sides, z in [-1, 1] from nearView
// to farView, w = view depth) with nearView, farView the caster body's depth range seen from it.
// The projection center (the slide) shapes the warp; near and far only scale PPS's z (and so the
// direction of the map's axis below).
struct PsmCamera {
  glm::dmat4 clipFromWorld{1.0};
  double slide = 0;     // world units behind the fit camera
  double nearView = 0;  // the nearest caster's view depth from the virtual camera, > 0
  double farView = 0;   // the farthest caster's
};

// The slide-back. zNear, zFar: the view-depth range of the visible body (from the fit camera);
// zCasterMin, zCasterMax: that of the caster body (the visible body extended towards the light;
// zCasterMin may be <= 0: casters behind the viewer). The virtual camera moves back by
//   slide = max(0, zNear - zCasterMin) + slideBack * (zFar - zNear)
// so that every caster lies at least zNear in front of it: the camera's near plane pushed to the
// nearest visible point (Stamminger and Drettakis), and no caster behind the projection center,
// where w would change sign (Kozlov's virtual camera shift). slideBack (psm.slide_back) weakens the
// warp further: the larger, the closer to the orthographic fit.
PsmCamera psmVirtualCamera(const Camera& camera, double zNear, double zFar, double zCasterMin, double zCasterMax,
                           double slideBack);

// The map from clip space of the virtual camera: clip (x, y, z, w) -> (u w, v w, depth w, w), for
// C (the light, clipFromWorld * (towardLight, 0)), the visible body's vertices and the caster
// body's (both in clip coordinates, w > 0). In PPS (q = clip.xyz / clip.w), with a the unit axis
// from c towards `center`, the view axis at the visible body's middle PPS depth (the paper's cube
// center; -z where that cone would not hold every caster: the map is then orthographic)
// and e1, e2 across it:
//   z'(q)  = |C.w| a.q - sigma a.C.xyz         (> 0 over the casters: the distance from c along a, times |C.w|)
//   w(q)   = z'(q) / z'_min = 1 + rho (a.q - t0),  rho = |C.w| / z'_min
//   X_i    = (e_i.q - e_i.c) / w(q)            (e_i.c = e_i.center when a points at the center: finite as C.w -> 0)
//   u, v   = X_1, X_2 over their ranges on the visible body's vertices
//   source: depth w = (a.q - t0) w(t1) / (t1 - t0);  sink: depth w = (t1 - a.q) w(t0) / (t1 - t0)
// [t0, t1] the range of a.q over the casters (padded by a hair). Each row is affine in q, so times
// clip.w it is linear in clip: one 4x4. As C.w -> 0 it tends to the orthographic projection of PPS
// along -C.xyz (rho -> 0): in world space the camera's own perspective warp, PSM's strongest. With a = -z (the axis
// normal to the infinity plane c lies on) it is orthographic in world space whatever c: w times clip w is constant. ok
// = false where no axis holds the casters.
struct PsmMap {
  bool ok = false;
  glm::dmat4 texFromClip{1.0};
  PsmLight light = PsmLight::Directional;
};
PsmMap psmTexFromClip(glm::dvec4 lightClip, const std::vector<glm::dvec4>& visibleClip,
                      const std::vector<glm::dvec4>& casterClip);

// How a layer's texels vary over the visible body, from its texFromWorld and the light's
// direction: |det J| of (u, v) against world displacements across the light (u, v are constant
// along a light ray, so J does not depend on where along the ray it is taken), at each point.
// warp = cbrt(max |det J| / min |det J|) - 1: 0 for an orthographic map, d/n for fit=lispsm's
// (whose 2D denominator 1 + (y - y0)/n enters det J cubed), the measure of the fallback.
// texelWorldPerW = the largest over the points of (the texel's larger world side) / w: the
// layer's texelWorldPerW for bias.normal (exact at those points, not a bound between them).
struct PsmTexels {
  double warp = 0;
  double texelWorldPerW = 0;
};
PsmTexels psmTexels(const glm::dmat4& texFromWorld, glm::dvec3 towardLight, const std::vector<glm::dvec3>& points,
                    int mapSize);

// Everything together for a directional light: the virtual camera from the fit camera and the
// bodies (world vertices: the visible body, the caster body including it), the light in its PPS,
// the map. texFromWorld = texFromClip * camera.clipFromWorld.
struct PsmFit {
  bool ok = false;
  glm::dmat4 texFromWorld{1.0};
  PsmCamera camera;
  PsmLight light = PsmLight::Directional;
  PsmTexels texels;
};
PsmFit psmFit(const Camera& camera, glm::dvec3 towardLight, const std::vector<glm::dvec3>& visible,
              const std::vector<glm::dvec3>& casters, double slideBack, int mapSize);

}  // namespace shadowlab::raster
