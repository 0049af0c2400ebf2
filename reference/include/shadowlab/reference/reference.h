#pragma once
// Embree 3 ground truth. No Embree header leaks through this interface.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// Which channels renderReference writes (reference/README.md, "Channels"). Every channel has the same
// values in both sets; Compare leaves out those no later stage reads.
enum class ReferenceChannels {
  // What compare, stability and the pictures of compare read: hit, object_id, light.L.vis,
  // light.L.occluder_dist, light.L.vis_sigma (sized lights only), proj.P.coverage and
  // proj.P.R/G/B. The reference cache holds this set.
  Compare,
  // Compare's plus prim_id, P.x/y/z, N.x/y/z and proj.P.u/v: for people, tests and referencePicture.
  All,
};

// Which compilation of the trace runs (reference/README.md, "Speed"): the same source compiled for
// x86-64's baseline (SSE2) and, on x86-64, a second time for AVX2 (no FMA, no contraction), chosen
// at run time. Both give the same bits (tested on every bundled scene); Auto takes AVX2 where the
// CPU and the build have it. Not part of the cache key (referenceHash).
enum class ReferenceSimd {
  Auto,
  Baseline,
  Avx2,  // DriverError where referenceHasAvx2() is false
};

// True where this build has the AVX2 trace and the CPU runs it.
bool referenceHasAvx2();

// Reference samples per pixel: the one range every reader checks (`reference`, `run`, `sweep`,
// `tune` and sweep files), before anything is traced or written.
constexpr int kMinSpp = 1;
constexpr int kMaxSpp = 1024;
// InputError "FILE: PLACE: error: got N; expected an integer 1..1024 (reference samples per
// pixel)" (formatError) unless kMinSpp <= spp <= kMaxSpp; FILE names the option ("--spp") or the
// file, PLACE its JSON pointer ("/spp") or "".
void checkSpp(long long spp, const std::string& file, const std::string& place = "");

// Light samples per pixel sample of a sized light (Light::sized(), reference/README.md "Sized
// lights"): the one range every reader checks (`--light-samples`, the sweep file's
// `light_samples`). Hard lights take none.
constexpr int kMinLightSamples = 1;
constexpr int kMaxLightSamples = 4096;
constexpr int kDefaultLightSamples = 64;
// InputError "FILE: PLACE: error: got N; expected an integer 1..4096 (light samples per pixel
// sample of a sized light)" unless kMinLightSamples <= samples <= kMaxLightSamples; FILE names the
// option ("--light-samples") or the file, PLACE its JSON pointer ("/light_samples") or "".
void checkLightSamples(long long samples, const std::string& file, const std::string& place = "");

struct ReferenceOptions {
  int spp = 1;  // stratified samples per pixel, kMinSpp..kMaxSpp (1 = the pixel center); visibility becomes fractional
  // Stratified samples of each sized light's solid angle per pixel sample, kMinLightSamples..
  // kMaxLightSamples. Part of the cache key (referenceHash) only where the scene has a sized light.
  int lightSamples = kDefaultLightSamples;
  int threads = 0;  // 0 = all hardware threads; results are bit-identical for any value
  // Not part of the cache key (referenceHash): the values are the same, the cache always holds Compare.
  ReferenceChannels channels = ReferenceChannels::All;
  ReferenceSimd simd = ReferenceSimd::Auto;  // not part of the result or its hash: the same bits
  // Added to every camera sample point, pixels (the center ray of pixel (i, j) passes through
  // (i + 0.5 + x, j + 0.5 + y)): a frame traced as a renderer whose pixel centers are elsewhere
  // would see it (compare's alignment check of outside frames, scenes/FRAME-CONTRACT.md). Part of
  // the cache key (referenceHash) when not zero; each component in [-1, 1].
  glm::vec2 pixelOffset{0.0f, 0.0f};
  // Called with the fraction of tiles traced (0..1], at most once per percent, from one thread
  // at a time (the caller's terminal progress line). Not part of the result or its hash.
  std::function<void(double)> progress;
};

// The channel names of a reference of this scene, in the frame's order ("channels" in the frame's
// metadata names the set: "compare" or "all").
std::vector<std::string> referenceChannelNames(const Scene& scene, ReferenceChannels channels);
const char* referenceChannelsKey(ReferenceChannels channels);

// Bytes a reference frame of this scene takes in memory: one float per pixel per channel
// (All: 9 per frame, 2 per light, 6 per projector; Compare: 2, 2, 4).
double referenceFrameBytes(const Scene& scene, ReferenceChannels channels = ReferenceChannels::All);

struct ReferenceStats {
  uint64_t primaryRays = 0;
  uint64_t shadowRays = 0;    // occlusion rays to lights and projectors
  double traceSeconds = 0.0;  // trace_seconds: wall time of the trace (scene build excluded)
  // Process CPU time (user + system, all threads) during the trace: on a machine other work shares,
  // much steadier than the wall time (bench/reference_rays_bench compares it with bare loops).
  double traceCpuSeconds = 0.0;
  double buildSeconds = 0.0;  // build_seconds: Embree device + BVH
  double mraysPerS() const { return traceSeconds > 0 ? (primaryRays + shadowRays) / traceSeconds * 1e-6 : 0.0; }
};

// Traces every light and projector of the scene. Channels: see scenes/frame.h.
// With `picture`, also draws referencePicture's picture (the same bytes) during the trace, from the
// values it computes, so a Compare frame suffices. Throws DriverError when Embree reports an error.
Frame renderReference(const Scene& scene, const ReferenceOptions& options, ReferenceStats* stats = nullptr,
                      std::vector<uint8_t>* picture = nullptr);

// The shadow-ray origin rule (reference/README.md, "Shadow-ray origins"): a shadow ray from the hit
// point `position` on the triangle (p0, p1, p2) starts at position + N * shadowOriginOffset(...),
// N the camera-facing unit normal. 2^-17 times the largest coordinate magnitude among the four.
float shadowOriginOffset(const glm::vec3& position, const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2);

// A hash of everything the reference depends on (scene hash, camera, spp, and lightSamples where the
// scene has a sized light): the cache key. The channel set is left out (the values are the same; the
// cache holds Compare).
std::string referenceHash(const Scene& scene, const ReferenceOptions& options);

// A readable picture: grey shading times the first light's visibility (plus a little ambient),
// projector colors added where covered; background dark blue. width*height*3 bytes. Needs the All set
// (prim_id, P, N).
std::vector<uint8_t> referencePicture(const Scene& scene, const Frame& frame);

}  // namespace shadowlab
