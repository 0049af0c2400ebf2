#pragma once
// Private helpers shared by the files of reference/src.
#include <string>

#include "shadowlab/scenes/scene.h"

namespace shadowlab::reference_detail {

// The frame metadata's "camera_hash": hashHex(fnv1a64) over the packed little-endian bytes of
// position.xyz, lookAt.xyz, up.xyz, vfovDeg (10 float32) then width, height (2 int32): exactly
// the camera fields that decide which ray each pixel casts. The rasterizer must use the same
// definition (see reference/README.md).
std::string cameraHash(const Camera& camera);

}  // namespace shadowlab::reference_detail
