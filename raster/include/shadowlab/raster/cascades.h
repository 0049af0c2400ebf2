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

// The practical split scheme (Zhang et al., parallel-split shadow maps), count + 1 distances:
//   C_i = lambda n (f/n)^(i/N) + (1 - lambda)(n + (f - n) i/N),  i = 0..N
// lambda 1 is logarithmic, 0 uniform. Computed in double; C_0 = n and C_N = f exactly.
// Requires 0 < n < f, count >= 1, lambda in [0, 1].
std::vector<double> cascadeSplits(double nearView, double farView, int count, double lambda);

}  // namespace shadowlab::raster
