// The timing glossary in code: the one name of each timing quantity a result row (metrics.json,
// results.json/csv, stability.json), raster.json or a sweep's bookkeeping carries, and the names
// older builds wrote for them. compare/TIMINGS.md says what each includes and where it is measured.
#pragma once

#include <string>

namespace shadowlab {
namespace timing {

// Per frame / per configuration, milliseconds (the `timings` object of a result row).
constexpr const char* kShadowGpuMs = "shadow_gpu_ms";          // GPU timestamps around the shadow pass
constexpr const char* kCameraGpuMs = "camera_gpu_ms";          // GPU timestamps: visibility buffer + resolve
constexpr const char* kVisibilityGpuMs = "visibility_gpu_ms";  // the visibility-buffer part of camera_gpu_ms
constexpr const char* kLookupGpuMs = "lookup_gpu_ms";    // GPU timestamps: the method's visibility alone, 1 byte/pixel
constexpr const char* kMethodGpuMs = "method_gpu_ms";  // shadow + lookup (+ sdsm) _gpu_ms: what an engine pays
constexpr const char* kMethodGpuMsMin = "method_gpu_ms_min";  // the fastest of a sweep row's timed repetitions
constexpr const char* kMethodGpuMsMax = "method_gpu_ms_max";  // the slowest of them (method_gpu_ms: their median)
constexpr const char* kMomentsGpuMs = "moments_gpu_ms";  // the moments pass's part of shadow_gpu_ms (filterable maps)
constexpr const char* kSdsmGpuMs = "sdsm_gpu_ms";        // fit=sdsm: the sample pass, part of method_gpu_ms
constexpr const char* kSdsmReduceMs = "sdsm_reduce_ms";  // fit=sdsm: CPU wall of the samples' readback and reduction
constexpr const char* kEvidenceGpuMs = "evidence_gpu_ms";  // camera_gpu_ms - visibility: the evidence resolve
constexpr const char* kReadbackMs = "readback_ms";         // CPU wall: outputs copied into the Frame
constexpr const char* kRenderWallMs = "render_wall_ms";    // CPU wall of Rasterizer::render
constexpr const char* kCompareMs = "compare_ms";           // CPU wall of compareFrames
constexpr const char* kReferenceMs = "reference_ms";       // CPU wall: reference traced or read from the cache
constexpr const char* kConfigWallMs = "config_wall_ms";    // one configuration end to end
constexpr const char* kCommandWallMs = "command_wall_ms";  // the whole command (stability.json)
// An outside renderer's own time for its frame, as its renderer JSON declares it (frame_ms).
constexpr const char* kRendererFrameMs = "renderer_frame_ms";
// An adapter's batch (adapters/README.md): its command's wall time per frame, start-up included,
// and shadowlab's time reading and checking one frame's files.
constexpr const char* kAdapterMs = "adapter_ms";
constexpr const char* kAdapterDecodeMs = "adapter_decode_ms";

// True for a current per-row timing name above.
inline bool isTimingName(const std::string& key) {
  for (const char* name : {kShadowGpuMs, kCameraGpuMs, kVisibilityGpuMs, kLookupGpuMs, kMethodGpuMs, kMethodGpuMsMin,
                           kMethodGpuMsMax, kMomentsGpuMs, kSdsmGpuMs, kSdsmReduceMs, kEvidenceGpuMs, kReadbackMs, kRenderWallMs, kCompareMs,
                           kReferenceMs, kConfigWallMs, kCommandWallMs, kRendererFrameMs, kAdapterMs, kAdapterDecodeMs})
    if (key == name) return true;
  return false;
}

// Which file a retired name was read from: `total_ms` meant a different quantity in each.
enum class TimingSource { ResultRow, StabilityRow, RasterJson };

// The current name of a timing key that older builds wrote, or nullptr when `key` is not retired.
// Retired names are refused, never mapped silently: a baseline written with `total_ms` holds a
// different quantity than any one new name, so comparing it against a new run would mislead.
inline const char* renamedTiming(const std::string& key, TimingSource source) {
  if (key == "shadow_ms") return kShadowGpuMs;
  if (key == "camera_ms") return kCameraGpuMs;
  if (key == "camera_visibility_ms" || key == "visibility_ms") return kVisibilityGpuMs;
  if (key == "raster_ms") return kRenderWallMs;
  if (key == "total_ms") {
    switch (source) {
      case TimingSource::StabilityRow: return kCommandWallMs;
      case TimingSource::RasterJson: return kRenderWallMs;
      case TimingSource::ResultRow: return kConfigWallMs;
    }
  }
  return nullptr;
}

// "error: "total_ms" was renamed; use "config_wall_ms" (...)": the text after `file: /pointer: error: `.
inline std::string renamedTimingMessage(const std::string& key, const char* newName) {
  return "\"" + key + "\" was renamed; use \"" + newName + "\" (timing names: compare/TIMINGS.md)";
}

}  // namespace timing
}  // namespace shadowlab
