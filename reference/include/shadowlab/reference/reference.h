#pragma once
// Embree 3 ground truth. No Embree header leaks through this interface.
#include <cstdint>
#include <string>

#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

struct ReferenceOptions {
  int spp = 1;      // stratified samples per pixel (1 = the pixel center); visibility becomes fractional
  int threads = 0;  // 0 = all hardware threads; results are bit-identical for any value
};

struct ReferenceStats {
  uint64_t primaryRays = 0;
  uint64_t shadowRays = 0;  // occlusion rays to lights and projectors
  double traceSeconds = 0.0;  // trace_seconds: wall time of the trace (scene build excluded)
  double buildSeconds = 0.0;  // build_seconds: Embree device + BVH
  double mraysPerS() const { return traceSeconds > 0 ? (primaryRays + shadowRays) / traceSeconds * 1e-6 : 0.0; }
};

// Traces every light and projector of the scene. Channels: see scenes/frame.h.
// Throws DriverError when Embree reports an error.
Frame renderReference(const Scene& scene, const ReferenceOptions& options, ReferenceStats* stats = nullptr);

// A hash of everything the reference depends on (scene hash, camera, spp): the cache key.
std::string referenceHash(const Scene& scene, const ReferenceOptions& options);

// A readable picture: grey shading times the first light's visibility (plus a little ambient),
// projector colors added where covered; background dark blue. width*height*3 bytes.
std::vector<uint8_t> referencePicture(const Scene& scene, const Frame& frame);

}  // namespace shadowlab
