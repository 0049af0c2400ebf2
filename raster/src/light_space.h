#pragma once
// Where each map layer looks from: the light's (or projector's) projective texture matrix.
// One convention for every layer, the same as Projector::texFromWorld:
//   texFromWorld * (p, 1) = (u*w, v*w, depth*w, w), u, v in [0,1] across the map (v = 0 on
//   the map's top row), depth in [0,1] from near to far (Vulkan), w > 0 in front.
// The shadow pass renders layer i with clipFromTex() * texFromWorld, so texel (x, y) of the map
// covers u in [x, x+1) / size, v in [y, y+1) / size exactly.
// A layer with MapLayer::lightDepth (fit=tsm) takes its depth from depthFromWorld instead
// (resolve_params.h): the light's own, unwarped.
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/raster/resolve_params.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab::raster {

// MapLayer: resolve_params.h.

struct LightSpace {
  // directional: 1, or one per cascade (fit=cascades, fit=sdsm); spot: 1; point: 6 cube faces (+X -X +Y -Y +Z -Z)
  std::vector<MapLayer> layers;
  bool depthClamp = false;  // directional: casters outside [near, far] still write the map
  // fit=cascades, fit=sdsm: the split distances C_0..C_N (view depth, world units); empty otherwise.
  std::vector<float> cascadeSplitsView;
};

// Directional: orthographic. Fit::Sphere: the bounding sphere of the scene's box. Fit::Tight:
// the camera's view frustum (its [near, far] clipped to the scene box, cascadeDepthRange)
// intersected with the scene box, in light space: x/y the box of the frustum's 8 corners clipped
// to the scene box's light-space x/y. Fit::Cascades: the same per slice [C_i, C_(i+1)] of the
// practical split scheme (stabilized: a square of the slice's bounding-sphere diameter, snapped to
// whole texels). Fit::Lispsm: the light-space perspective warp of lispsm.h of the view
// frustum's part of the scene (in a basis rotated about the light so that y follows the view
// direction), one perspective layer; where the warp is negligible (view nearly along the light)
// exactly Fit::Tight. Fit::Psm: the perspective shadow map of psm.h, one projective layer in the
// post-perspective space of the fit camera slid back behind every caster; where its map is
// (nearly) orthographic (the view along the light) exactly Fit::Tight. Fit::Tsm: the trapezoidal
// warp of tsm.h (Martin & Tan) of the same part of the scene, one perspective layer; with no
// center line or no eta for the 80 % rule, exactly Fit::Tight. The depth range is always the
// scene box's in light space: casters between the light and the slice still cast. Spot:
// perspective with fov = cone angle, near = light.nearPlane, far = the farthest corner of the
// scene's box. Point: six 90-degree faces. `fitCamera` is the camera the tight and cascaded fits
// (and their splits) follow; normally scene.camera, another one to measure shimmer with a fixed
// evaluation view (raster.h). Fit::Sdsm: the cascades' splits over the view-depth range of
// `visiblePoints` (the world points the fit camera's pixels see: the camera pass's samples),
// each crop the box of the samples in its slice (sdsm.h); without samples (none given, or the
// camera sees nothing) exactly Fit::Cascades.
LightSpace fitLight(const Scene& scene, const Light& light, const Method& method, const Camera& fitCamera,
                    const std::vector<glm::vec3>* visiblePoints = nullptr);
MapLayer projectorLayer(const Projector& projector, int mapSize);

// (u, v, depth, w) -> Vulkan clip space (x = 2u - 1, y = 2v - 1: v = 0 is the framebuffer's top).
glm::mat4 clipFromTex();

// Which cube face (index into LightSpace::layers) a direction from a point light falls in.
int cubeFace(glm::vec3 fromLight);

}  // namespace shadowlab::raster
