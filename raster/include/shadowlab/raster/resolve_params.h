#pragma once
// The steps of Rasterizer::render that need no GPU, as pure functions: the fit (light and
// projector layers), the resolve pass's parameter block and its specialization constants.
// render() calls them in this order; tests call them directly.
#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/raster/resolve_abi.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab::raster {

// One map layer: texFromWorld * (p, 1) = (u*w, v*w, depth*w, w), u, v in [0,1] across the map
// (v = 0 on the map's top row), depth in [0,1] from near to far, w > 0 in front; with lightDepth,
// depth = dot(depthFromWorld, (p, 1)) instead.
struct MapLayer {
  glm::mat4 texFromWorld{1.0f};
  // World size of one texel at w = 1 (orthographic: everywhere; fit=lispsm, fit=tsm: an upper bound
  // of the texel's larger side per unit of w, see lispsm.h, tsm.h; fit=psm: the largest of that
  // ratio over the visible body's vertices, see psm.h).
  float texelWorldPerW = 0;
  // fit=tsm (tsm.h): the map's depth is the light's own, depth = dot(depthFromWorld, (p, 1)), not
  // texFromWorld's z / w (u, v and w still come from texFromWorld): the shadow pass writes it as
  // the fragment's depth and the resolve compares against it (kSpecLightDepth).
  bool lightDepth = false;
  glm::vec4 depthFromWorld{0.0f};
};

// The fit step's result: every map layer of a frame, the light's first, then one per projector.
struct FrameLayers {
  std::vector<MapLayer> layers;
  int lightLayers = 0;                   // layers[0 .. lightLayers) are the light's
  bool depthClamp = false;               // the light's pass clamps depth (directional lights)
  std::vector<float> cascadeSplitsView;  // fit=cascades, sdsm: C_0..C_N (fit-camera view depth); else empty
};

// The light's layers (none without a light) fitted to `fitCamera`, then the projectors'.
// `visiblePoints`: the world points the fit camera's pixels see (fit=sdsm reads them; without
// them it fits as fit=cascades).
FrameLayers fitFrameLayers(const Scene& scene, const Light* light, const Method& method, const Camera& fitCamera,
                           const std::vector<glm::vec3>* visiblePoints = nullptr);
// Whether the fit reads the fit camera's visible points (fit=sdsm with a directional light).
bool fitReadsVisiblePoints(const Light* light, const Method& method);

// Where a projector's image starts in the projector texel table, and its size.
struct ProjectorTexels {
  int32_t firstTexel = 0;
  int32_t width = 0;
  int32_t height = 0;
};

// The kPoissonTaps-point disc of filter=poisson (fixed, progressive: every prefix is well spread).
const std::vector<glm::vec2>& poissonDisc();

// Smallest resolvable depth difference r of a UNORM format (Vulkan: 2^-n); 0 marks the float
// format, whose r depends on the depth's exponent and is computed per pixel in the shader.
float depthResolution(DepthFormat format);

// The resolve pass's parameter block for the scene's camera, `light` (nullptr: projectors only),
// the method and the fitted layers. `projectorTexels` has one entry per scene projector.
abi::Params packResolveParams(const Scene& scene, const Light* light, const Method& method, const Camera& fitCamera,
                              const FrameLayers& layers, const std::vector<ProjectorTexels>& projectorTexels);

// resolve.frag's specialization constants, indexed by abi::kSpec*.
using ResolveSpecialization = std::array<uint32_t, abi::kSpecCount>;
ResolveSpecialization resolveSpecialization(const Scene& scene, const Light* light, const Method& method,
                                            const FrameLayers& layers);

// The light's size in a light layer's units (abi::Params::lightSize, raster/METHODS.md "Soft
// filters"): xy the penumbra radius in texels (u, v) per unit of the depth term, zw a perspective
// map's depth linearization (z_lin = w / (d - z)); orthographic layers (a directional light's
// plain crops) have zw = 0. Zero for a hard light (radius and angular diameter 0).
glm::vec4 lightSizeInMap(const Light& light, const MapLayer& layer, int mapSize);

// The shader's light type code (abi::kLightNone without a light).
uint32_t lightTypeCode(const Light* light);

// The point the camera rays' parameters and the triangle planes (scene_gpu.h) are relative to:
// the camera position (perspective), or for an orthographic camera the image plane's point at
// image position (0, 0) (its rays start on that plane: origin(x, y) = it + rayX x + rayY y), both
// from the inverse of the matrix that rasterizes the visibility buffer.
glm::dvec3 cameraRaysOrigin(const Camera& camera);

}  // namespace shadowlab::raster
