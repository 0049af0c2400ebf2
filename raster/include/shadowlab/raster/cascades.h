#pragma once
// Cascaded shadow maps: where the camera's view depth range is split (pure functions, no GPU).
// View depth = distance along the camera's forward axis, normalize(lookAt - position), in world
// units (the -z of the camera's view space).
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/scenes/scene.h"

namespace shadowlab::raster {

struct ViewDepthRange {
  float nearView = 0;  // n, world units along the camera's forward axis, > 0
  float farView = 0;   // f, > n
};

// The camera's [near, far] clipped to the view-depth range of the 8 corners of the box
// [boundsMin, boundsMax]: n = max(near, smallest corner depth), f = min(far, largest corner depth),
// so no cascade is spent on depths where the scene has nothing. Always well defined: n >= 1e-4
// (the logarithmic split needs n > 0), and where the clipped range is empty or inverted (the scene
// lies wholly behind the camera or beyond far) the camera's own [near, far] is used; f > n.
ViewDepthRange cascadeDepthRange(const Camera& camera, glm::vec3 boundsMin, glm::vec3 boundsMax);
// The camera's own [near, far] with the same guards (n >= 1e-4, f > n), not clipped: what
// stabilized cascades split, because the clipped range moves with the camera.
ViewDepthRange cameraDepthRange(const Camera& camera);

// The practical split scheme (Zhang et al., parallel-split shadow maps), count + 1 distances:
//   C_i = lambda n (f/n)^(i/N) + (1 - lambda)(n + (f - n) i/N),  i = 0..N
// lambda 1 is logarithmic, 0 uniform. Computed in double; C_0 = n and C_N = f exactly.
// Requires 0 < n < f, count >= 1, lambda in [0, 1].
std::vector<double> cascadeSplits(double nearView, double farView, int count, double lambda);

// The x/y crop of the light's orthographic map for the slice [nearView, farView] of the camera's
// frustum, in the light's view space (lightFromWorld: world -> light view, the light looking down
// -z; x, y in world units).
// - not stabilized: the box of the slice's 8 corners, intersected with the scene's light-space
//   x/y box [sceneMinLight, sceneMaxLight] (a slice missing the scene keeps its own box), padded
//   by a hair so extreme vertices land inside the map; texelWorld = the larger side / mapSize.
// - stabilized: a square of side mapSize * texelWorld, texelWorld = 2 r / (mapSize - 2), r the
//   radius of the slice's bounding sphere about its centroid, computed in camera space so it does
//   not depend on where the camera stands or looks; the square's center is the centroid snapped
//   down to whole texels (multiples of texelWorld) of the light-space grid, so moving the camera
//   moves the crop by whole texels. The two texels of slack keep the sphere inside after the snap.
struct CascadeCrop {
  glm::vec2 minLight{0}, maxLight{0};  // light view space x/y, world units
  float texelWorld = 0;                // world size of one map texel
};
CascadeCrop cascadeCrop(const Camera& camera, const glm::mat4& lightFromWorld, double nearView, double farView,
                        int mapSize, bool stabilize, glm::vec2 sceneMinLight, glm::vec2 sceneMaxLight);

}  // namespace shadowlab::raster
