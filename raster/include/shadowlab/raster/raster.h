#pragma once
// Vulkan 1.3 headless shadow-mapping rasterizer (lavapipe by default).
// No Vulkan header leaks through this interface.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "shadowlab/raster/device_memory.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

struct RasterDeviceOptions {
  std::string device;       // substring of the device name; empty = lavapipe ("llvmpipe"), else first
  bool validation = false;  // enable VK_LAYER_KHRONOS_validation when installed
  // Keep the shadow maps while everything the shadow pass reads stays the same (a sweep's filter
  // axis): render() then skips the pass and reports the time it took when drawn. false: every
  // render draws them (bench/raster_bare_bench: a configuration's whole cost, every iteration).
  bool keepShadowMaps = true;
  // Every wait for the GPU ends after this many seconds with a DriverError (exit 3): a hung device,
  // or a technique file that never returns. The device is then left as it is (Context::hung).
  // 0: $SHADOWLAB_GPU_TIMEOUT_S when set (a number > 0), else 120.
  double gpuTimeoutS = 0;
};

struct RasterTimings {
  // shadow_gpu_ms: GPU timestamps of the shadow pass (all maps). While everything the pass reads
  // stays the same the rasterizer keeps the maps (RasterDeviceOptions::keepShadowMaps) and reports
  // the time they took when drawn (plus this frame's moments pass): the method's cost either way.
  double shadowGpuMs = 0;
  bool shadowMapsKept = false;  // this frame reused the last frame's maps (shadowGpuMs carried over)
  // GPU timestamps of the camera pass: the visibility buffer + the resolve. The visibility buffer
  // does not depend on the method: while the scene and the camera stay the same, the rasterizer
  // keeps it and adds the time it took when it was drawn (visibilityGpuMs). camera_gpu_ms.
  double cameraGpuMs = 0;
  double visibilityGpuMs = 0;  // visibility_gpu_ms: the camera pass's first part, the visibility buffer
  // lookup_gpu_ms: GPU timestamps of the lookup pass, the method's visibility (and filter) alone
  // per pixel into 1 byte, what an engine pays beside the shadow pass (0 without a light).
  // method_gpu_ms = shadowGpuMs + lookupGpuMs + sdsmGpuMs (compare/TIMINGS.md).
  double lookupGpuMs = 0;
  // sdsm_gpu_ms: fit=sdsm's sample pass (the fit camera's visibility buffer, read back), what an
  // engine pays for its depth samples before the shadow pass; timed when the samples were taken
  // (they are kept per scene and fit camera), 0 for the other fits. sdsm_reduce_ms: the readback
  // and the reduction on the CPU, not in method_gpu_ms.
  bool sdsmSampled = false;  // the fit read the samples (fit=sdsm, a directional light)
  double sdsmGpuMs = 0;
  double sdsmReduceMs = 0;
  double methodGpuMs() const { return shadowGpuMs + lookupGpuMs + sdsmGpuMs; }
  // moments_gpu_ms: the filterable maps' moments pass, the part of shadowGpuMs after the map
  // layers are drawn (0 for the other filters).
  double momentsGpuMs = 0;
  // evidence_gpu_ms: GPU timestamps of the evidence resolve, the part of cameraGpuMs after the
  // visibility buffer: the full-screen resolve, or with evidence on demand the resolve of the
  // listed pixels only (evidencePixels of them; the full path: every pixel).
  double evidenceGpuMs = 0;
  uint64_t evidencePixels = 0;
  bool partialEvidence = false;  // the frame's evidence planes hold the listed pixels only
  double readbackMs = 0;         // readback_ms: CPU wall time to copy the outputs back into the Frame
  double renderWallMs = 0;       // render_wall_ms: CPU wall time of render() (names: compare/TIMINGS.md)
};

// What an EvidenceSelector asks for: pixel indices (y * width + x), in any order, repeats allowed.
struct EvidenceRequest {
  // Every evidence channel (the full resolve of these pixels).
  std::vector<uint32_t> full;
  // The map texel's evidence only: in_map, occluder_id and occluder_prim (beside the exact vis
  // that every listed pixel gets); their depth, bias and moment channels stay 0. The lookup pass
  // over these pixels alone, a fraction of the full resolve's cost. A pixel in both lists gets
  // everything.
  std::vector<uint32_t> occluder;
};

// Evidence on demand (raster/METHODS.md): given the lookup pass's bytes (`vis8`, row-major,
// width x height; 255 only where the visibility is exactly 1, 0 only where it is exactly 0, 128..255
// exactly where it is >= 0.5), appends to `request` the pixels whose evidence channels the caller
// will read; the rasterizer lists every fractional pixel (a byte other than 0 and 255) itself, for
// its exact vis. The study layer passes one that lists where the lit decision disagrees with the
// reference's (where the reference is lit, the map texel's evidence decides the class); raster
// does not know why a pixel is listed.
using EvidenceSelector = std::function<void(const uint8_t* vis8, int width, int height, EvidenceRequest& request)>;

class Rasterizer {
 public:
  explicit Rasterizer(const RasterDeviceOptions& options = {});
  ~Rasterizer();
  Rasterizer(Rasterizer&&) noexcept;
  Rasterizer& operator=(Rasterizer&&) noexcept;

  std::string deviceName() const;
  int maxMapSize() const;  // the device's largest 2D image size
  // What the device can hold (raster/device_memory.h), and the images a render of this request
  // allocates there, with the device's sizes (validates the request first, as render() does).
  DeviceMemoryLimits memoryLimits() const;
  std::vector<DeviceImage> plannedImages(const Scene& scene, const Method& method, const std::string& light = "") const;
  // Throws what render() would throw for this request before any GPU work (InputError: a method
  // the device cannot render, an unknown light, images that do not fit; device_memory.h), so a
  // command refuses it before it traces a reference or writes anything.
  void check(const Scene& scene, const Method& method, const std::string& light = "") const;
  // Number of validation-layer messages (warnings and errors) seen so far (validation only).
  int validationMessages() const;
  // Hands a finished frame's channel planes back for the next render() to fill: a frame of the
  // same size then needs no fresh (zero-filled) memory. Optional; a sweep calls it per row. The
  // planes must be as render() returned them: an evidence-on-demand frame's planes are reused
  // knowing their values (zeros and the lookup's bytes, rewritten only where they change).
  void recycle(Frame&& frame);
  // One timed run of the method's passes (retimeMethod), GPU timestamps in ms.
  struct MethodTiming {
    double shadowGpuMs = 0;   // the shadow pass: every map layer drawn, then the moments pass
    double lookupGpuMs = 0;   // the lookup pass (0 without a light)
    double momentsGpuMs = 0;  // the moments pass's part of shadowGpuMs (0 for the other filters)
    double sdsmGpuMs = 0;     // fit=sdsm: the kept samples' pass, as taken (not run again)
    double methodGpuMs() const { return shadowGpuMs + lookupGpuMs + sdsmGpuMs; }
  };
  // Runs the last render()'s method passes again `repeats` times, each submitted and timed on its
  // own: the shadow pass (every map layer drawn, never the kept maps; then the moments pass) and
  // the lookup pass, none of the harness's passes. Their inputs are the last frame's, so the maps
  // and the lookup's bytes come out the same (lookupVisibility() is unchanged). A sweep times each
  // configuration so, its render() serving as the warm-up (compare/TIMINGS.md: the median and the
  // range of these runs). Empty before the first render.
  std::vector<MethodTiming> retimeMethod(int repeats);
  // The last render()'s lookup pass output: the light's visibility, one byte (UNORM, 255 = lit)
  // per pixel, row-major; empty before the first render, stale after a render without a light.
  // It equals the frame's vis channel converted to 8 bits, 255 only where vis is exactly 1 and 0
  // only where it is exactly 0, 128..255 exactly where vis >= 0.5 (tests/raster_lookup_test.cpp).
  std::vector<uint8_t> lookupVisibility() const;
  // The last render()'s light layers (a cascade, a cube face +X -X +Y -Y +Z -Z; one for a plain
  // directional or spot map; none without a light): clip space from world space as the shadow pass
  // drew them, Vulkan's (x/w, y/w in [-1, 1] across the map, y = -1 on its top row, depth 0..1).
  // What a renderer declares beside an outside frame (compare/classify declared_renderer.h).
  std::vector<glm::mat4> lastLightClipFromWorld() const;

  // Renders `scene` with `method` for the light named `light` (empty: the scene's first light)
  // and all projectors. The GPU copy of the scene is kept and reused while the scene hash is the
  // same, so a sweep uploads geometry once. A warm-up frame runs before the timed one the first
  // time a pipeline is used. Throws InputError for an impossible method (map larger than the
  // device allows, unknown light) and DriverError for Vulkan failures.
  // `fitCamera` (null: scene.camera) is the camera the light's frustum fit follows: the tight and
  // cascaded crops and the cascade splits (picked by the pixel's view depth along this camera's
  // forward axis). The image is always rendered from scene.camera, so a fixed scene.camera with a
  // moving fit camera shows the same surface point in every pixel of every frame (shimmer).
  // `select` (optional): evidence on demand. When the scene has a light and no projectors, the
  // planes that do not depend on bias or filter (hit, object_id, prim_id, m, cascade) are kept per
  // group (the same scene, camera and light layers: map size, fit, light; the group's first render
  // with `select` draws them in a planes pass, the next ones reuse them), the frame is made from the lookup pass (vis
  // exact at every byte 0 or 255), those kept planes and one resolve of the listed pixels only: the
  // other evidence channels (receiver_depth, map_depth, bias_depth, bias_world, occluder_id,
  // occluder_prim, in_map, the moment channels) are 0 except at the listed pixels (at those listed
  // for the occluder alone and the fractional ones: vis, in_map, occluder_id and occluder_prim),
  // and meta "evidence" is "partial" ("evidence_pixels": how many). Such a frame's shadow pass
  // writes the occluder's object into the map's stencil rather than its triangle into an id
  // attachment (up to 255 objects, where the device has the format): occluder_id is exact and
  // occluder_prim stays 0 (meta "occluder_prim": "unresolved"). compareFrames gives the same
  // metrics as on the full frame when `select` lists every disagreement. Otherwise (no selector,
  // projectors) the full frame, as without it.
  Frame render(const Scene& scene, const Method& method, const std::string& light = "",
               RasterTimings* timings = nullptr, const Camera* fitCamera = nullptr,
               const EvidenceSelector* select = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Compiles the method's technique file (method key technique; nothing without one), as render()
// would, so a command can refuse a file that does not compile (InputError, file:line:column) before
// it creates any output. Cached by content: render() does not compile it again.
void precompileTechnique(const Method& method);

// The GPU time limit as every command takes it (--gpu-timeout-s, a sweep file's gpu_timeout_s):
// seconds 0..1e6, 0 for the default (RasterDeviceOptions::gpuTimeoutS). Throws InputError
// "origin: pointer: error: got X; expected ..." otherwise (NaN included).
void checkGpuTimeout(double seconds, const std::string& origin, const std::string& pointer = "");

// Whether a device of this process stopped answering (a wait ran past gpuTimeoutS: a hung GPU, a
// technique that never returns). Its threads may still run the shader: the Rasterizer then leaks
// the device rather than wait for it, and the process must end with _exit (app/main.cpp), since
// the driver's exit handlers would wait for those threads forever.
bool rasterDeviceHung();
void markRasterDeviceHung();

// A readable picture of a raster frame (same look as referencePicture).
std::vector<uint8_t> rasterPicture(const Scene& scene, const Frame& frame);

}  // namespace shadowlab
