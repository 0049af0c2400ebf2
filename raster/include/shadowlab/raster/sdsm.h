#pragma once
// Sample distribution shadow maps (fit=sdsm): the fit's pieces as pure functions, no GPU.
// Lauritzen, Salvi, Lefohn, "Sample Distribution Shadow Maps", I3D 2011; the steps follow MJP's
// Shadows sample (DepthReduction.hlsl, AutoComputeDepthBounds):
//   1. depth reduction: the min and max view depth of the samples the camera sees (the pixels of
//      its visibility buffer that hit geometry);
//   2. the practical split scheme (cascades.h's cascadeSplits) over that range, not over the
//      camera's [near, far];
//   3. bounds reduction: per partition, the light-space x/y box of the samples that fall in it;
//   4. the crop: that box with a texel of margin, optionally snapped to whole texels of a
//      power-of-two texel size (sdsm.snap), the depth range the scene's (casters between the light
//      and the partition still cast, as for fit=cascades).
// A pixel then picks its partition by view depth exactly as fit=cascades does (resolve.frag's
// pickCascade): the splits are data.
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/raster/cascades.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab::raster {

// One visible sample as the reductions read it.
struct SdsmSample {
  float viewDepth = 0;    // along the fit camera's forward axis from its position, world units
  glm::vec2 light{0.0f};  // x/y in the light's view space (lightFromWorld), world units
};

// The world point a visibility-buffer pixel sees: where the ray through the pixel's center
// (rays.direction(x + 0.5, y + 0.5) from `origin`) meets the plane of the triangle (v0, v1, v2),
// in double, as resolve.frag's visibleSurface computes it in float. false where the ray runs
// along the plane (no finite point in front of the camera).
bool visiblePoint(const CameraRays& rays, glm::vec3 origin, int x, int y, glm::vec3 v0, glm::vec3 v1, glm::vec3 v2,
                  glm::vec3& point);

// The samples of world points for a fit camera and a light: view depth = dot(p - camera.position,
// normalize(lookAt - position)) (the depth resolve.frag picks a cascade by), light = the x/y of
// lightFromWorld * p.
std::vector<SdsmSample> sdsmSamples(const std::vector<glm::vec3>& worldPoints, const Camera& camera,
                                    const glm::mat4& lightFromWorld);

// Step 1: [min, max] of the samples' view depths, with cascades.h's guards (n >= 1e-4, f > n:
// f >= 1.001 n + 1e-4, so that a wall seen square on still has a range to split). false (range
// untouched) without samples.
bool sdsmDepthRange(const std::vector<SdsmSample>& samples, ViewDepthRange& range);

// Step 3: per partition k = 0..N-1 of `splits` (C_0..C_N), the light-space box of the samples
// whose lookups read it. resolve.frag gives partition k the view depths (C_k, C_(k+1)] (the first
// also everything below C_1, the last everything above C_(N-1)); in the blend band at the far end
// of partition k-1 (the last `blend` share of its range, cascades.blend) a pixel reads partition k
// too. A sample within a rounding tolerance of a split (1e-5 of the far split, the shader measures
// depth in float) counts for both sides. `samples` = 0 marks a partition no sample reads.
// At most 32 partitions (fit=sdsm has cascades.count, 1..8).
struct SdsmBounds {
  glm::vec2 minLight{0.0f}, maxLight{0.0f};
  size_t samples = 0;
};
std::vector<SdsmBounds> sdsmPartitionBounds(const std::vector<SdsmSample>& samples, const std::vector<double>& splits,
                                            double blend);

// Step 4: the map crop of a partition's box, mapSize texels per side (>= 8).
// - not snapped: per axis the box's extent e over mapSize - 2 texels, t = e / (mapSize - 2), and
//   one texel of margin on each side: [min - t, max + t] (the lookups of the box's edge samples and
//   the hardware's 2x2 footprint stay inside the map, whatever float rounding the shader adds);
// - snapped: per axis t = the smallest power of two (world units) with e <= (mapSize - 4) t, the
//   crop [floor((min - t) / t) t, that + mapSize t]: while the box moves by less than a power-of-two
//   step in size, the texel grid stays put in light space (shadow edges do not crawl), and a moving
//   box moves the crop by whole texels. It costs up to half the resolution per axis.
// An extent below 1e-4 of the other axis' (or 1e-5 world units) is raised to it: a partition of
// one sample, or of samples on a line, still gets an invertible map.
// texelWorld = the larger of the two axes' t.
CascadeCrop sdsmCrop(const SdsmBounds& bounds, int mapSize, bool snap);

}  // namespace shadowlab::raster
