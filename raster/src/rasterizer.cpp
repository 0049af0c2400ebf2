// The rasterizer, pass by pass:
//   Pass 1 (shadow): depth + ids (global triangle + 1) from the light into one layer per map
//                    (cube faces for point lights), then one layer per projector.
//   Pass 1b (moments, filterable maps only): per light layer, the moments of the map depths
//                    blurred along rows, then along columns (a separable Gaussian), into a
//                    moments map sampled with linear filtering (moments_rows/cols.frag).
//   Pass 2 (camera): the camera's visibility buffer: depth + id (global triangle + 1) per pixel,
//                    kept while the scene and the camera stay the same.
//   Pass 3a (planes, a group's first frame): resolve.frag specialized to kSpecPlanesOnly: m and
//                    2 * cascade + in_map (evidence on demand keeps them per group) and the group's
//                    surface (kSurfaceFormat: the camera ray's t at the visible point, whether the
//                    light reaches it), kept for up to kKeptFootprints groups (surfaceFor).
//   Pass 3 (resolve, a full-screen fragment pass): per pixel, the visible point, the map lookup with the method's
//                    bias and filter, the evidence channels into two color attachments
//                    (kResolveFormats), the projectors into a storage buffer (one plane per channel),
//                    with a light the group's surface into one more attachment (pass 4 reads it).
//   Pass 4 (lookup, with a light): resolve.frag specialized to the method's lookup alone
//                    (kSpecLookupOnly): the visibility as 1 byte per pixel (kLookupFormat; 0 and
//                    255 only for exactly 0 and 1, the 0.5 threshold exact), the evidence
//                    compiled out; timed on its own (lookup_gpu_ms, what an engine pays for the
//                    method besides its shadow pass). A method that needs no normal reads the
//                    visible point from the group's surface (kSpecSurface), one fetch per pixel.
// Evidence on demand (render() with an EvidenceSelector, a light, no projectors, and the group's
// planes kept): pass 3 is skipped and pass 1 writes the stencil ids (each draw's object index + 1
// in the map's stencil aspect, no id attachment: a depth-only pass's cost; up to 255 objects, where
// the device has the depth+stencil format). After passes 1, 2 and 4 the CPU reads the bytes back, lists the
// fractional pixels and those the selector asks for (where the decision disagrees with the
// reference), and
//   Pass 5 (evidence): resolve.frag specialized to kSpecCompact draws a kCompactWidth-wide target
//                    with one fragment per listed pixel (evidencePixels[k] instead of
//                    gl_FragCoord), the same channels as pass 3 for those pixels only; the pixels
//                    listed for the map texel's evidence alone (EvidenceRequest::occluder, and the
//                    fractional ones) go through the lookup's specialization made compact instead
//                    (kSpecLookupOnly + kSpecCompact: vis, occluder, in_map; about half the cost
//                    per pixel on lavapipe);
// the frame is then the bytes (0/1 exactly), the kept planes of the group (hit, object_id,
// prim_id from the visibility buffer; m and cascade per footprintKey: the light's layers, the
// camera, the cascade splits) and the listed pixels' evidence, zeros elsewhere. A group's first
// frame draws those planes first (pass 3a).
// The visibility buffer and the resolve attachments are linear images in host memory: the CPU
// splits them into the Frame's channel planes in place, without a copy to a buffer first.
#include "shadowlab/raster/raster.h"

#include <algorithm>
#include <atomic>
#include <functional>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <list>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>
#include <tuple>

#include <glm/gtc/matrix_inverse.hpp>

#include "light_space.h"
#include "shadowlab/raster/device_memory.h"
#include "shadowlab/raster/sdsm.h"
#include "shadowlab/raster/resolve_abi.h"
#include "shadowlab/raster/resolve_params.h"
#include "scene_gpu.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/technique.h"
#include "technique_compiler.h"
#include "vk/buffer.h"
#include "vk/check.h"
#include "vk/commands.h"
#include "vk/context.h"
#include "vk/image.h"
#include "vk/pipeline.h"

#include "id_frag.h"
#include "id_vert.h"
#include "fullscreen_vert.h"
#include "id_light_depth_frag.h"
#include "id_light_depth_vert.h"
#include "id_plain_frag.h"
#include "id_plain_vert.h"
#include "moments_cols_frag.h"
#include "moments_rows_frag.h"
#include "resolve_frag.h"

namespace shadowlab {

namespace {

namespace abi = raster::abi;
constexpr int kProjectorChannels = abi::kProjectorChannels;
// The resolve pass's color attachments (resolve.frag's outA, outB, and outC for filterable maps).
constexpr int kResolveAttachments = 3;
constexpr VkFormat kResolveFormats[kResolveAttachments] = {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                           VK_FORMAT_R32G32B32A32_SFLOAT};
// The attachments a frame of `filter` writes: outC (the moments' evidence) for filterable maps only.
int resolveAttachments(Filter filter) { return isMomentFilter(filter) ? 3 : 2; }
// A colour attachment that a full-screen pass overwrites entirely (its old contents are not loaded).
VkRenderingAttachmentInfo overwrittenColor(VkImageView view, VkImageLayout layout) {
  VkRenderingAttachmentInfo color{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  color.imageView = view;
  color.imageLayout = layout;
  color.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;  // every pixel is written
  color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  return color;
}
// Makes the writes of `srcStage` (`srcAccess`) visible to the host's reads after the submit.
void barrierToHost(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess) {
  VkMemoryBarrier2 toHost{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  toHost.srcStageMask = srcStage;
  toHost.srcAccessMask = srcAccess;
  toHost.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT;
  toHost.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT;
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.memoryBarrierCount = 1;
  dep.pMemoryBarriers = &toHost;
  vkCmdPipelineBarrier2(cmd, &dep);
}
// Sorted pixel indices (y * width + x) as x | y << 16 into `out` (images are at most 65535 wide).
void packPixels(const std::vector<uint32_t>& sorted, uint32_t width, uint32_t* out) {
  uint32_t y = 0, rowStart = 0;
  for (uint32_t i : sorted) {
    while (i - rowStart >= width) {
      rowStart += width;
      ++y;
    }
    *out++ = (i - rowStart) | (y << 16);
  }
}
// Row y of a host-readable image, as T.
template <class T>
const T* mappedRow(const vk::Image& img, size_t y) {
  return reinterpret_cast<const T*>(static_cast<const char*>(img.mapped()) + y * img.rowPitch());
}
// A full-screen pass (the moments, the resolve, the lookup): one triangle drawn with `pipeline`
// over width x height into `count` colour attachments; `beforeDraw` (optional) runs after the
// pipeline is bound, e.g. for push constants.
// warmup: a scissor of one pixel (a pipeline's untimed first use, compiling its shaders: submit()).
void drawFullscreen(VkCommandBuffer cmd, const VkRenderingAttachmentInfo* colors, uint32_t count, uint32_t width,
                    uint32_t height, VkPipeline pipeline, const std::function<void()>& beforeDraw = {},
                    bool warmup = false) {
  VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
  info.renderArea = {{0, 0}, {width, height}};
  info.layerCount = 1;
  info.colorAttachmentCount = count;
  info.pColorAttachments = colors;
  vkCmdBeginRendering(cmd, &info);
  VkViewport viewport{0, 0, float(width), float(height), 0.0f, 1.0f};
  VkRect2D scissor{{0, 0}, {warmup ? 1u : width, warmup ? 1u : height}};
  vkCmdSetViewport(cmd, 0, 1, &viewport);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
  vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
  if (beforeDraw) beforeDraw();
  vkCmdDraw(cmd, 3, 1, 0, 0);
  vkCmdEndRendering(cmd);
}
// The lookup pass's one attachment: the visibility, 1 byte per pixel.
constexpr VkFormat kLookupFormat = VK_FORMAT_R8_UNORM;
// Listed pixels from which partialFrame scatters the evidence on two threads (a thread's start
// costs ~50 us; 64k pixels' scatter ~1.5 ms).
constexpr size_t kParallelScatter = 65536;

// f(begin, end) over [0, n) in two halves, the second on a helper thread: the frame's CPU copies
// (the halves write disjoint pixels; this machine has 2 cores).
template <class F>
void inTwoHalves(size_t n, const F& f) {
  std::thread helper(f, n / 2, n);
  f(size_t(0), n / 2);
  helper.join();
}
// GPU timestamps per frame: 0 start, 5 after the map layers (before the moments pass), 1 after
// the shadow pass (moments included), 3 after the visibility buffer, 4 after the resolve, 2 after
// the lookup (the end).
constexpr uint32_t kTimestamps = 6;
// The evidence pass's compact targets: listed pixel k at (k % width, k / width).
constexpr int kCompactWidth = 256;
// How many groups' planes (m, cascade) evidence on demand keeps: a sweep whose fastest axis is a
// bias or a filter needs one; a grid with map.size fastest, one per size.
constexpr size_t kKeptFootprints = 4;
// The filterable maps' moment images kept across frames (Impl::momentsSpare): every vsm and msm
// pair of a 2048^2 sweep (3 sizes x 2 formats, 252 MB) fits.
constexpr size_t kMomentsKeptBytes = size_t(384) << 20;
// A group's surface (resolve.frag's kSpecSurface), the planes pass's second attachment and the full
// resolve's last: the camera ray's t at the visible point, and 1 where the light reaches it (-1
// where it does not, 0 where no triangle covers the pixel). Kept
// per group, as many as the footprints (8 bytes per pixel: 17 MB at 1080p each).
constexpr VkFormat kSurfaceFormat = VK_FORMAT_R32G32_SFLOAT;

// Whether the full resolve of a specialization writes the group's surface: with a light (the lookup
// after it reads it), not in the evidence pass (kSpecCompact).
bool resolveWritesSurface(const raster::ResolveSpecialization& spec) {
  return spec[abi::kSpecLightType] != uint32_t(abi::kLightNone) && !spec[abi::kSpecCompact];
}

// Whether the lookup pass of a specialization reads the group's surface: it needs no normal (no
// normal offset, no receiver plane, no adaptive bias), the surface image holds the visible point.
bool lookupReadsSurface(const raster::ResolveSpecialization& spec) {
  return spec[abi::kSpecLightType] != uint32_t(abi::kLightNone) && !spec[abi::kSpecNormalOffset] &&
         !spec[abi::kSpecReceiverPlane] && !spec[abi::kSpecAdaptive] && !spec[abi::kSpecTechniqueNormal];
}

// A filterable map's moments format: RG32F for 2 moments, RGBA32F for 4 (raster/METHODS.md).
VkFormat momentsFormat(Filter filter) {
  return momentCount(filter) == 4 ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R32G32_SFLOAT;
}
constexpr VkFormat kIdFormat = VK_FORMAT_R32_UINT;  // global triangle + 1, 0: nothing
constexpr VkFormat kCameraDepthFormat = VK_FORMAT_D32_SFLOAT;

struct DrawPush {
  glm::mat4 clipFromWorld;
  uint32_t objectIndex, triangleBase, pad0, pad1;
  // id_light_depth.vert/.frag only (layers with MapLayer::lightDepth): the light's depth row and the
  // depth bias the fragment shader applies: x bias.constant * r (a float format: w = 1 and x the
  // constant factor alone, r from the depth's exponent in the shader), y bias.slope, z bias.clamp.
  glm::vec4 depthRow{0.0f}, depthBias{0.0f};
};

// One shadow-pass layer: its clip matrix and, for a light-depth layer, the depth row.
struct LayerDraw {
  glm::mat4 clip;
  bool lightDepth = false;
  glm::vec4 depthRow{0.0f};
};

VkFormat vkDepthFormat(DepthFormat f) {
  switch (f) {
    case DepthFormat::D16: return VK_FORMAT_D16_UNORM;
    case DepthFormat::D24: return VK_FORMAT_X8_D24_UNORM_PACK32;
    case DepthFormat::D32F: return VK_FORMAT_D32_SFLOAT;
  }
  return VK_FORMAT_D32_SFLOAT;
}

// The map format with a stencil aspect beside the same depth bits: evidence on demand writes the
// occluder's object (index + 1) there instead of an id attachment (a depth-only pass's cost).
VkFormat vkDepthStencilFormat(DepthFormat f) {
  switch (f) {
    case DepthFormat::D16: return VK_FORMAT_D16_UNORM_S8_UINT;
    case DepthFormat::D24: return VK_FORMAT_D24_UNORM_S8_UINT;
    case DepthFormat::D32F: return VK_FORMAT_D32_SFLOAT_S8_UINT;
  }
  return VK_FORMAT_D32_SFLOAT_S8_UINT;
}
// Objects the stencil ids can tell apart: 8 bits, 0 for no occluder.
constexpr size_t kMaxStencilObjects = 255;
bool isDepthStencil(VkFormat f) {
  return f == VK_FORMAT_D16_UNORM_S8_UINT || f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D32_SFLOAT_S8_UINT;
}

VkCullModeFlags vkCull(CullMode c) {
  switch (c) {
    case CullMode::Back: return VK_CULL_MODE_BACK_BIT;
    case CullMode::Front: return VK_CULL_MODE_FRONT_BIT;
    case CullMode::None: return VK_CULL_MODE_NONE;
  }
  return VK_CULL_MODE_NONE;
}

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Evidence on demand: the lookup's bytes into the frame's vis plane (1 at 255, 0 elsewhere; the
// fractional pixels get their floats from the evidence pass afterwards) and the sorted list of the
// fractional bytes (1..254), in one pass over the bytes, 8 at a time. `held` holds the bytes that
// `plane` already encodes (a plane recycle() handed back): only the words that differ are
// written; `full` (no such plane) writes every pixel. `held` then holds `bytes`.
void visFromBytes(const uint8_t* bytes, size_t n, bool full, uint8_t* held, float* plane,
                  std::vector<uint32_t>& fractional) {
  constexpr uint64_t kLow = 0x0101010101010101ull;
  auto encode = [&](size_t i, size_t count) {
    for (size_t j = 0; j < count; ++j) plane[i + j] = bytes[i + j] == 255 ? 1.0f : 0.0f;
  };
  fractional.clear();
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t w, h;
    std::memcpy(&w, bytes + i, 8);
    std::memcpy(&h, held + i, 8);
    if (full || w != h) {
      encode(i, 8);
      std::memcpy(held + i, &w, 8);
    }
    // A byte is 0 or 255 exactly where it equals its top bit spread over the byte.
    uint64_t frac = w ^ (((w >> 7) & kLow) * 0xFF);
    while (frac) {
      const int byte = __builtin_ctzll(frac) / 8;
      fractional.push_back(uint32_t(i) + uint32_t(byte));
      frac &= ~(uint64_t(0xFF) << (8 * byte));
    }
  }
  for (; i < n; ++i) {
    if (full || bytes[i] != held[i]) encode(i, 1), held[i] = bytes[i];
    if (bytes[i] != 0 && bytes[i] != 255) fractional.push_back(uint32_t(i));
  }
}

// The descriptor set's bindings, from resolve_abi.h's table.
enum class DescriptorKind { StorageBuffer, UniformBuffer, CombinedImageSampler, UniformTexelBuffer };

VkDescriptorType vkDescriptorType(DescriptorKind kind) {
  switch (kind) {
    case DescriptorKind::StorageBuffer: return VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    case DescriptorKind::UniformBuffer: return VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    case DescriptorKind::CombinedImageSampler: return VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    case DescriptorKind::UniformTexelBuffer: return VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
  }
  return VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}

struct BindingRow {
  uint32_t binding;
  VkDescriptorType type;
};
#define SHADOWLAB_BINDING_ROW(name, binding, kind) {binding, vkDescriptorType(DescriptorKind::kind)},
const BindingRow kBindings[] = {SHADOWLAB_RESOLVE_BINDINGS(SHADOWLAB_BINDING_ROW)};
#undef SHADOWLAB_BINDING_ROW
constexpr uint32_t kBindingCount = uint32_t(std::size(kBindings));
// Every binding is read by the fragment shaders (id.frag: 0..2, resolve.frag: all).
constexpr VkShaderStageFlags kBindingStages = VK_SHADER_STAGE_FRAGMENT_BIT;

}  // namespace

// The id-writing pipelines of one frame: the plain writer and the one with material tests
// (alpha cutoff, one-sided back faces), for the shadow pass and for the camera pass.
struct IdPipelines {
  VkPipeline shadowPlain, shadowTested, cameraPlain, cameraTested;
  // Light-depth layers (fit=tsm): the same two, with id_light_depth.vert/.frag.
  VkPipeline shadowLightDepthPlain = VK_NULL_HANDLE, shadowLightDepthTested = VK_NULL_HANDLE;
};

struct Rasterizer::Impl {
  std::unique_ptr<vk::Context> context;
  std::unique_ptr<vk::Commands> commands;
  vk::DescriptorSetLayout setLayout;
  vk::PipelineLayout pipelineLayout;
  vk::DescriptorPool descriptorPool;
  VkDescriptorSet descriptorSet = VK_NULL_HANDLE;
  vk::Sampler nearestSampler, compareSampler, linearSampler;
  vk::ShaderModule idVert, idFrag, idPlainVert, idPlainFrag, idLightDepthVert, idLightDepthFrag, fullscreenVert,
      resolveFrag, momentsRowsFrag, momentsColsFrag;
  vk::QueryPool queries;
  // Keyed by what needs a new pipeline: (depth format, depth clamp, material tests, depth bias,
  // light depth); a depth+stencil format: the stencil ids, no id attachment.
  std::map<std::tuple<VkFormat, bool, bool, bool, bool>, vk::PipelineHandle> idPipelines;
  std::map<DepthFormat, bool> stencilFormatOk;  // whether the device renders and samples it
  // Keyed by resolve.frag's specialization constants (resolve_abi.h's kSpec*).
  // and the technique's key (techniqueKey; empty: the built-in resolve.frag).
  using ResolveKey = raster::ResolveSpecialization;
  std::map<std::pair<ResolveKey, std::string>, vk::PipelineHandle> resolvePipelines;
  // The method's technique (method key technique): resolve.frag compiled with the file, one module
  // per content hash; the current render's module, key (id and constants) and constants (the
  // declared keys' values, specialization constants kSpecCount + i). useTechnique sets them.
  std::map<std::string, vk::ShaderModule> techniqueModules;
  VkShaderModule techniqueModule = VK_NULL_HANDLE;
  std::string techniqueKey;
  std::vector<uint32_t> techniqueConstants;
  void useTechnique(const Method& method);
  // Keyed by (filter, cols pass): the moments pass's two pipelines per filterable filter.
  std::map<std::pair<Filter, bool>, vk::PipelineHandle> momentsPipelines;
  std::set<std::string> warmed;

  std::unique_ptr<raster::SceneGpu> scene;
  vk::Image mapDepth, mapIds, cameraDepth, cameraIds;
  // Filterable maps: the rows-blurred moments and the moments map, one layer per light layer
  // (1x1 placeholders, never read, until a filterable map needs them: every binding needs an
  // image; the other filters leave whatever pair is there).
  vk::Image momentsRows, moments;
  // Pairs of other sizes, layer counts or formats, kept for when a sweep comes back to them (its
  // rows alternate vsm and msm, and map sizes): a new pair is fresh memory, whose first touch the
  // moments pass would pay inside its timestamps (~15 % of the main job's moments_gpu_ms).
  // At most kMomentsKeptBytes in all, with the pair in use; the least recently used goes first,
  // and a pair over the budget on its own is made alone, as before.
  struct MomentsPair {
    vk::Image rows, map;
    uint64_t lastUse = 0;
  };
  std::vector<MomentsPair> momentsSpare;
  uint64_t momentsUses = 0;
  // resolveOut[2] (the moment channels) is allocated at the first filterable map only.
  vk::Image resolveOut[kResolveAttachments];
  vk::Image lookupOut;        // pass 4's visibility (R8), host-readable
  vk::Buffer params, output;  // output: the projector channels
  // Evidence on demand (pass 5): the listed pixels, the compact targets (kCompactWidth wide, as
  // many rows as the list needs; [2] for filterable maps only), their two timestamps.
  vk::Buffer evidencePixels;
  vk::Image evidenceOut[kResolveAttachments];
  vk::Image occluderOut;  // the pixels listed for the occluder's evidence alone: vis, occluder, in_map
  vk::QueryPool evidenceQueries;
  std::set<std::pair<raster::ResolveSpecialization, std::string>> evidenceWarmed;
  // The planes that depend on the scene and the camera only (hit, object_id, prim_id, as the last
  // full frame read them back) and, per group, on the light's layers too (m, cascade): what
  // evidence on demand copies instead of resolving (render()'s `select`).
  struct CameraPlanes {
    std::string key;  // the visibility key they were read with
    std::vector<float> hit, objectId, primId;
  } cameraPlanes;
  struct Footprint {
    std::string key;  // footprintKey
    std::vector<float> m, cascade;
  };
  std::list<Footprint> footprints;  // most recently used first, at most kKeptFootprints
  // The groups' surfaces (kSurfaceFormat), keyed like the footprints (footprintKey), most recently
  // used first, at most kKeptFootprints: the planes pass draws one on demand, a full frame's resolve
  // writes its group's. `surfaceBound` is the frame's (kBindingSurface: the lookup reads it), else
  // the 1x1 placeholder (never read: every binding needs an image).
  struct SurfaceImage {
    std::string key;  // empty until the planes pass has drawn it
    vk::Image image;
  };
  std::list<SurfaceImage> surfaces;
  vk::Image surfacePlaceholder;
  vk::Image* surfaceBound = nullptr;
  // The kept planes are lent (moved, not copied) to the last partial frame; recycle() moves them
  // back and re-zeroes that frame's evidence planes at its listed pixels only, for the next one.
  // A frame not handed back leaves its group without planes: its next frame is a full one.
  struct Lent {
    std::string footprintKey;
    const float* kept[5] = {};         // hit, object_id, prim_id, m, cascade
    std::vector<const float*> zeroed;  // evidence planes: 0 except at `listed`
    const float* vis = nullptr;        // the vis plane: the bytes' values except at `listed`
    std::vector<uint32_t> listed;
  } lent;
  std::vector<std::vector<float>> zeroSpare;  // planes of zeros (recycled evidence planes)
  // The vis plane of the last partial frame, handed back by recycle() with its listed pixels set
  // back to what the bytes say, and the lookup bytes it encodes: the next partial frame rewrites
  // only the pixels whose byte changed. `plane` is empty while lent (or never handed back).
  struct VisPlane {
    std::vector<float> plane;
    std::vector<uint8_t> bytes;
  } visKept;
  std::vector<uint8_t> lookupRows;  // the lookup's bytes when its rows are padded (a copy without the padding)
  EvidenceRequest asked;
  std::vector<uint32_t> fractional;
  // partialFrame's lists beside `asked` (kept, so a frame with acne everywhere needs no fresh memory
  // for them): the occluder's list with the fractional pixels, and that less the full list.
  std::vector<uint32_t> occluderOrFractional, occluderListed;

  explicit Impl(const RasterDeviceOptions& options);
  // Work may still be in flight when a render throws (a failed call after a submission): wait for
  // the device before the members release what it reads and writes. Not after a timeout, where
  // the wait could last forever; a lost device answers at once.
  ~Impl() {
    if (context && context->device() && !context->hung()) vkDeviceWaitIdle(context->device());
  }

  // render()'s steps (defined beside render(), in its order).
  struct FramePipelines {
    IdPipelines ids;
    VkPipeline planes = VK_NULL_HANDLE;    // pass 3a: the group's planes and surface (none: both kept)
    VkPipeline resolve = VK_NULL_HANDLE;   // pass 3 (none on demand)
    bool resolveSurface = false;           // pass 3 writes the group's surface too (a light)
    VkPipeline lookup = VK_NULL_HANDLE;    // pass 4; none without a light
    VkPipeline evidence = VK_NULL_HANDLE;  // pass 5 (evidence on demand)
    VkPipeline evidenceOccluder = VK_NULL_HANDLE;  // pass 5, the pixels listed for the occluder alone
    bool evidenceFirstUse = false;
    bool firstUse = false;  // lavapipe compiles at first use: run once untimed (warmupRun)
  };
  struct PassTimes {
    double shadowGpuMs = 0;   // pass 1
    double resolveGpuMs = 0;  // pass 3 (pass 2's time is visibilityGpuMs)
    double lookupGpuMs = 0;   // pass 4
    double momentsGpuMs = 0;  // pass 1b (part of shadowGpuMs)
  };
  const Light* validate(const Scene& scene, const Method& method, const std::string& lightName) const;
  int maxMapSize() const;
  DeviceMemoryLimits memoryLimits() const;
  // The images a frame of this request allocates, with the device's sizes; checkDeviceMemory
  // refuses it before any is allocated.
  std::vector<DeviceImage> plannedImages(const Scene& scene, const Method& method,
                                         const raster::FrameLayers& layers) const;
  mutable std::string plannedKey;  // plannedImages' last request and answer
  mutable std::vector<DeviceImage> planned;
  void upload(const Scene& scene);
  void prepareTargets(const Scene& scene, const Method& method, const raster::FrameLayers& layers, bool stencilIds);
  bool stencilIdsApply(const Method& method);
  std::vector<raster::ProjectorTexels> projectorTexels() const;
  FramePipelines pipelinesFor(const Method& method, const raster::FrameLayers& layers,
                              const raster::ResolveSpecialization& spec, bool partial, bool planes);
  std::string cameraKey(const Scene& scene) const;
  std::string cameraKey(const Camera& camera) const;
  const std::vector<glm::vec3>& visiblePoints(const Scene& scene, const Light* light, const Method& method,
                                              const Camera& fitCamera, bool stencilIds);
  std::string footprintKey(const Scene& scene, const abi::Params& params,
                           const raster::ResolveSpecialization& spec) const;
  Footprint* findFootprint(const std::string& key);
  Footprint& keepPlanes(const std::string& key, const std::string& camera, int width, int height);
  SurfaceImage& surfaceFor(const std::string& key, int width, int height, bool& kept);
  void idsOf(uint32_t id, float& objectId, float& prim) const;
  void cameraRow(int y, float* hit, float* objectId, float* primId) const;
  Frame partialFrame(const Scene& scene, const Light& light, const Method& method, const EvidenceSelector& select,
                     Footprint& footprint, const FramePipelines& pipes, RasterTimings& t);
  struct Drawn {
    bool visibility = false, shadow = false;
  };
  Drawn submit(const Scene& scene, const Method& method, const raster::FrameLayers& layers,
               const FramePipelines& pipes);  // what it drew (the rest was kept)
  PassTimes readTimestamps(Drawn drawn);

  void createLayouts();
  VkPipeline idPipeline(VkFormat format, bool depthClamp, bool materialTests, bool depthBias, bool lightDepth = false);
  VkPipeline resolvePipeline(const ResolveKey& key);
  void ensureImages(int mapSize, VkFormat mapFormat, int layers, int width, int height, bool momentChannels);
  void writeDescriptors();
  void ensureMoments(Filter filter, int mapSize, int lightLayers);
  VkPipeline momentsPipeline(Filter filter, bool cols);
  Frame readback(const Scene& scene, const Light* light, const Method& method, int width, int height);
  void record(VkCommandBuffer cmd, const std::vector<LayerDraw>& layerDraws, int lightLayers,
              const FramePipelines& frame, const Method& method, const glm::mat4& cameraClip, int width, int height,
              bool drawVisibility, bool drawShadow, bool visibilityOnly = false);
  std::string shadowPassKey(const std::vector<LayerDraw>& layerDraws, const IdPipelines& pipes,
                            const Method& method) const;

  // The camera's visibility buffer depends on the scene and the camera only, not on the method:
  // while both stay the same (a sweep over methods, a stability run with a fixed evaluation
  // camera) it is kept and not drawn again. Its GPU time, measured when it was drawn, stays part
  // of every frame's camera_gpu_ms.
  std::string visibilityKey;  // empty: cameraIds holds nothing reusable
  // The same for the map layers (pass 1, not the moments): kept while everything pass 1 reads is
  // the same (shadowPassKey; a sweep's filter axis, or a stability run's fixed light and camera),
  // its time (the layers' part of shadow_gpu_ms) carried over. RasterDeviceOptions::keepShadowMaps.
  std::string shadowKey;  // empty: mapDepth (and mapIds) hold nothing reusable
  double shadowLayersGpuMs = 0;
  bool keepShadowMaps = true;
  // The untimed first run of a pipeline combination (lavapipe compiles its shaders at the first
  // draw): every pass scissored to one pixel, then the timed run draws the frame.
  bool warmupRun = false;
  // retimeMethod's runs: pass 1 (every layer), 1b and 4 only; the visibility buffer, the planes and
  // the resolve are skipped (their outputs stay as the last frame left them).
  bool methodOnly = false;
  // What the last submit recorded, for retimeMethod.
  struct LastSubmit {
    bool valid = false;
    std::vector<LayerDraw> layerDraws;
    int lightLayers = 0;
    FramePipelines pipes;
    Method method;
    glm::mat4 cameraClip{1.0f};
    int width = 0, height = 0;
    bool light = false;
  } last;
  std::vector<std::vector<float>> spare;  // recycled channel planes (Rasterizer::recycle)
  double visibilityGpuMs = 0;
  // fit=sdsm's samples (visiblePoints) and the key of the scene and fit camera they are of.
  std::vector<glm::vec3> samplePoints;
  std::string samplesKey;  // empty: none kept
};

Rasterizer::Impl::Impl(const RasterDeviceOptions& options) {
  vk::ContextOptions co;
  co.device = options.device;
  co.validation = options.validation;
  context = std::make_unique<vk::Context>(co);
  keepShadowMaps = options.keepShadowMaps;
  double timeoutS = options.gpuTimeoutS;
  if (!(timeoutS > 0)) {
    timeoutS = 120;
    if (const char* env = std::getenv("SHADOWLAB_GPU_TIMEOUT_S"); env && *env) {
      char* end = nullptr;
      timeoutS = std::strtod(env, &end);
      if (*end || !(timeoutS > 0 && timeoutS <= 1e6))
        throw InputError(std::string("SHADOWLAB_GPU_TIMEOUT_S: error: got \"") + env +
                         "\"; expected seconds, a number > 0 and <= 1e6");
    }
  }
  commands = std::make_unique<vk::Commands>(*context, uint64_t(timeoutS * 1e9));
  createLayouts();
  idVert = vk::createShaderModule(*context, kSpv_id_vert, sizeof(kSpv_id_vert));
  idFrag = vk::createShaderModule(*context, kSpv_id_frag, sizeof(kSpv_id_frag));
  idPlainVert = vk::createShaderModule(*context, kSpv_id_plain_vert, sizeof(kSpv_id_plain_vert));
  idPlainFrag = vk::createShaderModule(*context, kSpv_id_plain_frag, sizeof(kSpv_id_plain_frag));
  idLightDepthVert = vk::createShaderModule(*context, kSpv_id_light_depth_vert, sizeof(kSpv_id_light_depth_vert));
  idLightDepthFrag = vk::createShaderModule(*context, kSpv_id_light_depth_frag, sizeof(kSpv_id_light_depth_frag));
  fullscreenVert = vk::createShaderModule(*context, kSpv_fullscreen_vert, sizeof(kSpv_fullscreen_vert));
  resolveFrag = vk::createShaderModule(*context, kSpv_resolve_frag, sizeof(kSpv_resolve_frag));
  momentsRowsFrag = vk::createShaderModule(*context, kSpv_moments_rows_frag, sizeof(kSpv_moments_rows_frag));
  momentsColsFrag = vk::createShaderModule(*context, kSpv_moments_cols_frag, sizeof(kSpv_moments_cols_frag));

  VkDevice device = context->device();
  auto makeSampler = [&](bool compare, bool linear) {
    VkSamplerCreateInfo s{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    // Depths are point-sampled; the comparison sampler filters its 0/1 results, the moments
    // sampler the moments.
    s.magFilter = s.minFilter = linear ? VK_FILTER_LINEAR : VK_FILTER_NEAREST;
    s.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    s.addressModeU = s.addressModeV = s.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    s.compareEnable = compare;
    s.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;  // lit when reference <= stored depth
    s.maxLod = 0.0f;
    VkSampler sampler;
    VK_CHECK(vkCreateSampler(device, &s, nullptr, &sampler));
    return vk::Sampler(device, sampler);
  };
  nearestSampler = makeSampler(false, false);
  compareSampler = makeSampler(true, true);
  linearSampler = makeSampler(false, true);

  VkQueryPoolCreateInfo q{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  q.queryType = VK_QUERY_TYPE_TIMESTAMP;
  q.queryCount = kTimestamps;
  VkQueryPool pool;
  VK_CHECK(vkCreateQueryPool(device, &q, nullptr, &pool));
  queries = vk::QueryPool(device, pool);
  params = vk::Buffer(*context, sizeof(abi::Params),
                      VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);  // ParamsLoops too
  evidencePixels = vk::Buffer(*context, 4096 * sizeof(uint32_t), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  q.queryCount = 2;
  VK_CHECK(vkCreateQueryPool(device, &q, nullptr, &pool));
  evidenceQueries = vk::QueryPool(device, pool);
}

void Rasterizer::Impl::createLayouts() {
  VkDevice device = context->device();
  std::vector<VkDescriptorSetLayoutBinding> bindings;
  std::map<VkDescriptorType, uint32_t> typeCounts;  // the pool holds exactly the set's descriptors
  for (const BindingRow& row : kBindings) {
    bindings.push_back({row.binding, row.type, 1, kBindingStages, nullptr});
    ++typeCounts[row.type];
  }
  VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  info.bindingCount = uint32_t(bindings.size());
  info.pBindings = bindings.data();
  VkDescriptorSetLayout layout;
  VK_CHECK(vkCreateDescriptorSetLayout(device, &info, nullptr, &layout));
  setLayout = vk::DescriptorSetLayout(device, layout);

  VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(DrawPush)};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &layout;
  pl.pushConstantRangeCount = 1;
  pl.pPushConstantRanges = &push;
  VkPipelineLayout pipeLayout;
  VK_CHECK(vkCreatePipelineLayout(device, &pl, nullptr, &pipeLayout));
  pipelineLayout = vk::PipelineLayout(device, pipeLayout);

  std::vector<VkDescriptorPoolSize> sizes;
  for (const auto& [type, count] : typeCounts) sizes.push_back({type, count});
  VkDescriptorPoolCreateInfo dp{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dp.maxSets = 1;
  dp.poolSizeCount = uint32_t(sizes.size());
  dp.pPoolSizes = sizes.data();
  VkDescriptorPool pool;
  VK_CHECK(vkCreateDescriptorPool(device, &dp, nullptr, &pool));
  descriptorPool = vk::DescriptorPool(device, pool);
  VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  alloc.descriptorPool = pool;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &layout;
  VK_CHECK(vkAllocateDescriptorSets(device, &alloc, &descriptorSet));
}

VkPipeline Rasterizer::Impl::idPipeline(VkFormat format, bool depthClamp, bool materialTests, bool depthBias,
                                        bool lightDepth) {
  auto key = std::make_tuple(format, depthClamp, materialTests, depthBias, lightDepth);
  auto it = idPipelines.find(key);
  if (it != idPipelines.end()) return it->second.get();
  vk::GraphicsPipelineDesc d;
  // Without material tests, the plain shaders: no uv varying to set up per triangle.
  d.vertex = lightDepth ? idLightDepthVert.get() : materialTests ? idVert.get() : idPlainVert.get();
  d.fragment = lightDepth ? idLightDepthFrag.get() : materialTests ? idFrag.get() : idPlainFrag.get();
  d.layout = pipelineLayout.get();
  d.bindings = {{0, 5 * sizeof(float), VK_VERTEX_INPUT_RATE_VERTEX}};
  d.attributes = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0}};
  if (materialTests || lightDepth) d.attributes.push_back({1, 0, VK_FORMAT_R32G32_SFLOAT, 3 * sizeof(float)});
  if (isDepthStencil(format)) {
    // The stencil ids: no id attachment; the object comes from the stencil reference, and a draw
    // without material tests or light depth needs no fragment shader at all (a depth-only pass).
    d.stencilFormat = format;
    if (!materialTests && !lightDepth) d.fragment = VK_NULL_HANDLE;
  } else {
    d.colorFormats = {kIdFormat};
  }
  d.depthFormat = format;
  d.depthClamp = depthClamp;
  d.depthBias = depthBias;
  if (materialTests || lightDepth) d.fragmentSpecialization = {materialTests ? 1u : 0u};
  return idPipelines.emplace(key, vk::createGraphicsPipeline(*context, d)).first->second.get();
}

void Rasterizer::Impl::useTechnique(const Method& method) {
  techniqueModule = VK_NULL_HANDLE;
  techniqueKey.clear();
  techniqueConstants.clear();
  if (method.technique.empty()) return;
  const TechniqueFile& t = loadTechniqueFile(method.technique);
  auto it = techniqueModules.find(t.hash);
  if (it == techniqueModules.end()) {
    auto compiled = raster::compileTechnique(t);
    it = techniqueModules
             .emplace(t.hash, vk::createShaderModule(*context, compiled->spirv.data(), compiled->spirv.size() * 4))
             .first;
  }
  techniqueModule = it->second.get();
  techniqueKey = t.hash;
  for (const TechniqueParam& p : t.params) {
    auto v = method.techniqueParams.find(p.name);
    techniqueConstants.push_back(techniqueParamBits(p, v == method.techniqueParams.end() ? p.defaultValue : v->second));
    techniqueKey += "/" + std::to_string(techniqueConstants.back());
  }
}

VkPipeline Rasterizer::Impl::resolvePipeline(const ResolveKey& key) {
  // The technique replaces the filter where one runs: not in the planes pass, not without a light.
  const bool technique =
      techniqueModule && !key[abi::kSpecPlanesOnly] && key[abi::kSpecLightType] != uint32_t(abi::kLightNone);
  const std::pair<ResolveKey, std::string> mapKey(key, technique ? techniqueKey : std::string());
  auto it = resolvePipelines.find(mapKey);
  if (it != resolvePipelines.end()) return it->second.get();
  vk::GraphicsPipelineDesc d;
  d.vertex = fullscreenVert.get();
  d.fragment = technique ? techniqueModule : resolveFrag.get();
  d.layout = pipelineLayout.get();
  d.depthTest = false;
  if (key[abi::kSpecLookupOnly]) d.colorFormats = {key[abi::kSpecCompact] ? kResolveFormats[0] : kLookupFormat};
  else if (key[abi::kSpecPlanesOnly]) d.colorFormats = {kResolveFormats[0], kSurfaceFormat};
  else {
    d.colorFormats.assign(kResolveFormats, kResolveFormats + resolveAttachments(Filter(key[abi::kSpecFilter])));
    if (resolveWritesSurface(key))
      d.colorFormats.push_back(kSurfaceFormat);  // the group's surface, for the lookup after it
  }
  d.fragmentSpecialization.assign(key.begin(), key.end());  // straight-line code per case
  if (technique)
    d.fragmentSpecialization.insert(d.fragmentSpecialization.end(), techniqueConstants.begin(),
                                    techniqueConstants.end());
  return resolvePipelines.emplace(mapKey, vk::createGraphicsPipeline(*context, d)).first->second.get();
}

VkPipeline Rasterizer::Impl::momentsPipeline(Filter filter, bool cols) {
  auto key = std::make_pair(filter, cols);
  auto it = momentsPipelines.find(key);
  if (it != momentsPipelines.end()) return it->second.get();
  vk::GraphicsPipelineDesc d;
  d.vertex = fullscreenVert.get();
  d.fragment = cols ? momentsColsFrag.get() : momentsRowsFrag.get();
  d.layout = pipelineLayout.get();
  d.depthTest = false;
  d.colorFormats = {momentsFormat(filter)};
  if (!cols) d.fragmentSpecialization = {uint32_t(filter)};  // kSpecFilter: which moments
  return momentsPipelines.emplace(key, vk::createGraphicsPipeline(*context, d)).first->second.get();
}

void Rasterizer::Impl::ensureMoments(Filter filter, int mapSize, int lightLayers) {
  const VkImageUsageFlags usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  const VkFormat format = momentsFormat(filter);
  if (!isMomentFilter(filter)) {  // never read: any pair will do, the placeholders until there is one
    if (moments.width() == 0) {
      momentsRows = vk::Image(*context, 1, 1, 1, format, usage, VK_IMAGE_ASPECT_COLOR_BIT);
      moments = vk::Image(*context, 1, 1, 1, format, usage, VK_IMAGE_ASPECT_COLOR_BIT);
    }
    return;
  }
  const int size = mapSize, layers = std::max(1, lightLayers);
  auto fits = [&](const vk::Image& image) {
    return image.width() == size && image.layers() == layers && image.format() == format;
  };
  if (fits(moments)) return;
  ++momentsUses;
  // Both images of a pair: size^2 texels per layer, RG32F or RGBA32F.
  auto pairBytes = [](int side, int count, VkFormat f) {
    return 2 * size_t(side) * size_t(side) * size_t(count) * (f == VK_FORMAT_R32G32B32A32_SFLOAT ? 16u : 8u);
  };
  if (moments.width() > 1) {  // the pair in use becomes a spare (a placeholder is dropped)
    MomentsPair spare;
    spare.lastUse = momentsUses;
    spare.rows = std::move(momentsRows);
    spare.map = std::move(moments);
    momentsSpare.push_back(std::move(spare));
  }
  momentsRows = vk::Image();
  moments = vk::Image();
  for (auto it = momentsSpare.begin(); it != momentsSpare.end(); ++it)
    if (fits(it->map)) {
      momentsRows = std::move(it->rows);
      moments = std::move(it->map);
      momentsSpare.erase(it);
      return;
    }
  // A new pair: spares go, least recently used first, until it fits the budget beside them (all
  // of them before a pair over the budget: two sets of 4096^2 RGBA32F layers would not fit).
  const size_t need = pairBytes(size, layers, format);
  auto spareBytes = [&] {
    size_t n = 0;
    for (const MomentsPair& p : momentsSpare) n += pairBytes(p.map.width(), p.map.layers(), p.map.format());
    return n;
  };
  while (!momentsSpare.empty() && spareBytes() + need > kMomentsKeptBytes)
    momentsSpare.erase(
        std::min_element(momentsSpare.begin(), momentsSpare.end(),
                         [](const MomentsPair& a, const MomentsPair& b) { return a.lastUse < b.lastUse; }));
  momentsRows =
      vk::Image(*context, size, size, layers, format, usage, VK_IMAGE_ASPECT_COLOR_BIT, false, "moments rows");
  moments = vk::Image(*context, size, size, layers, format, usage, VK_IMAGE_ASPECT_COLOR_BIT, false, "moments map");
}

void Rasterizer::Impl::ensureImages(int mapSize, VkFormat mapFormat, int layers, int width, int height,
                                    bool momentChannels) {
  const vk::Context& c = *context;
  if (mapDepth.width() != mapSize || mapDepth.format() != mapFormat || mapDepth.layers() != layers) {
    shadowKey.clear();
    mapDepth = vk::Image();  // released first: maps of 4096^2 and more
    mapDepth = vk::Image(
        c, mapSize, mapSize, layers, mapFormat,
        VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
        isDepthStencil(mapFormat) ? VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT : VK_IMAGE_ASPECT_DEPTH_BIT,
        false, "shadow map depth");
  }
  if (mapIds.width() != mapSize || mapIds.layers() != layers) {
    shadowKey.clear();
    mapIds = vk::Image(c, mapSize, mapSize, layers, kIdFormat,
                       VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                       false, "shadow map ids");
  }
  if (cameraIds.width() != width || cameraIds.height() != height) {
    cameraDepth = vk::Image(c, width, height, 1, kCameraDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                            VK_IMAGE_ASPECT_DEPTH_BIT, false, "camera depth");
    visibilityKey.clear();
    cameraIds =
        vk::Image(c, width, height, 1, kIdFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                  VK_IMAGE_ASPECT_COLOR_BIT, true, "camera ids");
    for (int i = 0; i < kResolveAttachments; ++i) {
      resolveOut[i] = vk::Image();
      if (i < 2)
        resolveOut[i] = vk::Image(c, width, height, 1, kResolveFormats[i], VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                                  VK_IMAGE_ASPECT_COLOR_BIT, true, "camera resolve target");
    }
    lookupOut = vk::Image(c, width, height, 1, kLookupFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                          VK_IMAGE_ASPECT_COLOR_BIT, true, "camera lookup target");
  }
  // The moment channels' target (33 MB at 1080p) only once a filterable map needs it; kept after.
  if (momentChannels && resolveOut[2].width() != width)
    resolveOut[2] = vk::Image(c, width, height, 1, kResolveFormats[2], VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                              VK_IMAGE_ASPECT_COLOR_BIT, true, "camera resolve target");
}

void Rasterizer::Impl::writeDescriptors() {
  const raster::SceneGpu& s = *scene;
  // What each binding of resolve_abi.h's table holds: a buffer, an image with its sampler, or a
  // texel buffer view (exactly one per binding, checked below).
  struct Resource {
    const vk::Buffer* buffer = nullptr;
    VkDescriptorImageInfo image{};
    VkBufferView texelView = VK_NULL_HANDLE;
  };
  Resource resources[kBindingCount];
  auto image = [](const vk::Sampler& sampler, VkImageView view, VkImageLayout layout) {
    return VkDescriptorImageInfo{sampler.get(), view, layout};
  };
  resources[abi::kBindingTriangleMaterials].buffer = &s.triangleMaterials;
  resources[abi::kBindingMaterials].buffer = &s.materials;
  resources[abi::kBindingAlphaTexels].buffer = &s.alphaTexels;
  resources[abi::kBindingParams].buffer = &params;
  resources[abi::kBindingParamsLoops].buffer = &params;
  resources[abi::kBindingMapDepth].image =
      image(nearestSampler, mapDepth.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  resources[abi::kBindingMapShadow].image =
      image(compareSampler, mapDepth.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  // With the stencil ids the map's stencil aspect (object + 1) stands in for the id attachment.
  resources[abi::kBindingMapIds].image =
      image(nearestSampler, mapDepth.hasStencil() ? mapDepth.stencilView() : mapIds.arrayView(),
            VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  resources[abi::kBindingCameraIds].image = image(nearestSampler, cameraIds.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
  resources[abi::kBindingSurface].image = image(nearestSampler, surfaceBound->layerView(0), VK_IMAGE_LAYOUT_GENERAL);
  resources[abi::kBindingTrianglePlanes].texelView = s.trianglePlanesView.get();
  resources[abi::kBindingProjectorTexels].buffer = &s.projectorTexels;
  resources[abi::kBindingOutPlanes].buffer = &output;
  resources[abi::kBindingEvidencePixels].buffer = &evidencePixels;
  resources[abi::kBindingMomentsRows].image =
      image(nearestSampler, momentsRows.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  resources[abi::kBindingMoments].image =
      image(linearSampler, moments.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);

  VkDescriptorBufferInfo bufferInfos[kBindingCount]{};
  std::vector<VkWriteDescriptorSet> writes;
  for (const BindingRow& row : kBindings) {
    Resource& r = resources[row.binding];
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = descriptorSet;
    w.dstBinding = row.binding;
    w.descriptorCount = 1;
    w.descriptorType = row.type;
    switch (row.type) {
      case VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: w.pImageInfo = &r.image; break;
      case VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER: w.pTexelBufferView = &r.texelView; break;
      default:
        if (!r.buffer) throw std::logic_error("resolve binding " + std::to_string(row.binding) + " has no buffer");
        bufferInfos[row.binding] = {r.buffer->get(), 0, VK_WHOLE_SIZE};
        w.pBufferInfo = &bufferInfos[row.binding];
    }
    writes.push_back(w);
  }
  vkUpdateDescriptorSets(context->device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
}

void Rasterizer::Impl::record(VkCommandBuffer cmd, const std::vector<LayerDraw>& layerDraws, int lightLayers,
                              const FramePipelines& frame, const Method& method, const glm::mat4& cameraClip, int width,
                              int height, bool drawVisibility, bool drawShadow, bool visibilityOnly) {
  const IdPipelines& pipes = frame.ids;
  const VkPipeline resolve = frame.resolve, lookup = frame.lookup;
  const raster::SceneGpu& s = *scene;
  VkQueryPool pool = queries.get();
  vkCmdResetQueryPool(cmd, pool, 0, kTimestamps);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, pool, 0);
  VkDescriptorSet set = descriptorSet;
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout.get(), 0, 1, &set, 0, nullptr);
  VkBuffer vb = s.vertices.get();
  VkDeviceSize zero = 0;
  vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &zero);
  vkCmdBindIndexBuffer(cmd, s.indices.get(), 0, VK_INDEX_TYPE_UINT32);

  // Plain draws first, then those that need the material tests (discard turns early depth
  // testing off, so only the draws that need it pay for it).
  // A light-depth layer draws with its own pipelines and the depth bias in the push constants (its
  // fragment shader writes the depth, which replaces the rasterizer's bias).
  glm::vec4 shaderBias(method.biasConstant * raster::depthResolution(method.mapFormat), method.biasSlope,
                       method.biasClamp, raster::depthResolution(method.mapFormat) > 0.0f ? 0.0f : 1.0f);
  if (shaderBias.w > 0.5f) shaderBias.x = method.biasConstant;
  // The stencil ids (evidence on demand): the shadow pass writes each draw's object index + 1
  // into the map's stencil where its fragment wins the depth test, the same fragment whose id the
  // id attachment would keep.
  const bool stencilIds = mapDepth.hasStencil();
  const VkImageLayout mapLayout =
      stencilIds ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  auto drawAll = [&](const glm::mat4& clip, bool shadowPass, const LayerDraw* lightDepth = nullptr) {
    VkPipeline bound = VK_NULL_HANDLE;
    for (int tested = 0; tested < 2; ++tested)
      for (const raster::Draw& d : s.draws) {
        if (shadowPass && !d.castsShadow) continue;
        VkCullModeFlags cull = shadowPass ? vkCull(method.cull) : VkCullModeFlags(VK_CULL_MODE_NONE);
        // One-sided back faces: the hardware cull removes them when the pass culls back faces
        // anyway (shadow pass with cull=back) or when every material of the object is one-sided.
        bool backCulled = cull == VK_CULL_MODE_BACK_BIT;
        if (!shadowPass && d.allOneSided) cull = VK_CULL_MODE_BACK_BIT, backCulled = true;
        bool needsTests = d.hasAlpha || (d.anyOneSided && !backCulled);
        if (needsTests != (tested == 1)) continue;
        VkPipeline p = lightDepth   ? (needsTests ? pipes.shadowLightDepthTested : pipes.shadowLightDepthPlain)
                       : shadowPass ? (needsTests ? pipes.shadowTested : pipes.shadowPlain)
                                    : (needsTests ? pipes.cameraTested : pipes.cameraPlain);
        if (p != bound) vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p), bound = p;
        vkCmdSetCullMode(cmd, cull);
        DrawPush push{clip, d.objectIndex, d.triangleBase, 0, 0};
        if (lightDepth) push.depthRow = lightDepth->depthRow, push.depthBias = shaderBias;
        if (shadowPass && stencilIds) vkCmdSetStencilReference(cmd, VK_STENCIL_FACE_FRONT_AND_BACK, d.objectIndex + 1);
        vkCmdPushConstants(cmd, pipelineLayout.get(), VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                           sizeof(push), &push);
        vkCmdDrawIndexed(cmd, d.indexCount, 1, d.firstIndex, d.vertexOffset, 0);
      }
  };
  // idView VK_NULL_HANDLE: no id attachment (the stencil ids: depthView holds both aspects).
  auto beginRendering = [&](VkImageView depthView, VkImageView idView, int w, int h,
                            VkImageLayout idLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL) {
    VkRenderingAttachmentInfo color{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    color.imageView = idView;
    color.imageLayout = idLayout;
    color.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    color.clearValue.color.uint32[0] = 0;  // id 0: nothing drawn here
    VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    depth.imageView = depthView;
    depth.imageLayout = idView ? VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL : mapLayout;
    depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    // An empty texel lies at the far plane (lights all) and holds stencil 0 (no object).
    depth.clearValue.depthStencil = {1.0f, 0};
    VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
    info.renderArea = {{0, 0}, {uint32_t(w), uint32_t(h)}};
    info.layerCount = 1;
    info.colorAttachmentCount = idView ? 1 : 0;
    info.pColorAttachments = idView ? &color : nullptr;
    info.pDepthAttachment = &depth;
    info.pStencilAttachment = idView ? nullptr : &depth;
    vkCmdBeginRendering(cmd, &info);
    VkViewport viewport{0, 0, float(w), float(h), 0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, {warmupRun ? 1u : uint32_t(w), warmupRun ? 1u : uint32_t(h)}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
  };

  // ---- Pass 1: depth (+ ids) from the light and from each projector ----
  // (skipped while the maps of the last frame still hold: they are left in their read layout)
  if (drawShadow) {
    vk::transition(cmd, mapDepth, VK_IMAGE_LAYOUT_UNDEFINED, mapLayout, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0,
                   VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    if (!stencilIds)
      vk::transition(cmd, mapIds, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                     VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    for (size_t layer = 0; layer < layerDraws.size(); ++layer) {
      beginRendering(mapDepth.layerView(int(layer)), stencilIds ? VK_NULL_HANDLE : mapIds.layerView(int(layer)),
                     method.mapSize, method.mapSize);
      vkCmdSetDepthBias(cmd, method.biasConstant, method.biasClamp, method.biasSlope);
      const LayerDraw& ld = layerDraws[layer];
      drawAll(ld.clip, true, ld.lightDepth ? &ld : nullptr);
      vkCmdEndRendering(cmd);
    }
    vk::transition(cmd, mapDepth, mapLayout, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                   VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
    if (!stencilIds)
      vk::transition(cmd, mapIds, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                     VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 5);
  // ---- Pass 1b: the moments of filterable maps (placeholders made readable otherwise) ----
  if (!visibilityOnly) {
    const bool used = isMomentFilter(method.filter);
    const int size = moments.width();
    auto fullscreen = [&](const vk::Image& target, int layer, VkPipeline pipeline) {
      const VkRenderingAttachmentInfo color =
          overwrittenColor(target.layerView(layer), VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
      drawFullscreen(
          cmd, &color, 1, uint32_t(size), uint32_t(size), pipeline,
          [&] {
            DrawPush push{glm::mat4(1.0f), uint32_t(layer), 0, 0, 0};
            vkCmdPushConstants(cmd, pipelineLayout.get(), VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                               sizeof(push), &push);
          },
          warmupRun);
    };
    for (const vk::Image* target : {&momentsRows, &moments}) {
      const bool cols = target == &moments;
      if (used) {
        vk::transition(cmd, *target, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                       VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                       VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
        for (int layer = 0; layer < lightLayers; ++layer)
          fullscreen(*target, layer, momentsPipeline(method.filter, cols));
        vk::transition(cmd, *target, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                       VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
      } else {
        vk::transition(cmd, *target, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                       VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                       VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
      }
    }
  }
  // After the barriers: a CPU driver may still be rasterizing the maps until they are flushed.
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);

  // ---- Pass 2: the camera's visibility buffer (skipped while the last one still holds) ----
  if (drawVisibility) {
    vk::transition(cmd, cameraDepth, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_NONE, 0,
                   VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    // GENERAL throughout: the camera ids are an attachment, then sampled, then read by the host.
    vk::transition(cmd, cameraIds, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_HOST_BIT, 0,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    beginRendering(cameraDepth.layerView(0), cameraIds.layerView(0), width, height, VK_IMAGE_LAYOUT_GENERAL);
    drawAll(cameraClip, false);
    vkCmdEndRendering(cmd);
  }
  vk::transition(cmd, cameraIds, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 3);
  if (visibilityOnly) {  // fit=sdsm's samples (visiblePoints): the host reads the ids next
    barrierToHost(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    return;
  }

  // ---- Pass 3a: a group's planes (m, cascade) and surface, where not kept ----
  vk::Image& surface = *surfaceBound;
  if (frame.planes != VK_NULL_HANDLE && !methodOnly) {
    VkRenderingAttachmentInfo colors[2];
    vk::transition(cmd, resolveOut[0], VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_HOST_BIT,
                   0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    colors[0] = overwrittenColor(resolveOut[0].layerView(0), VK_IMAGE_LAYOUT_GENERAL);
    colors[1] = overwrittenColor(surface.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
    drawFullscreen(cmd, colors, 2, uint32_t(width), uint32_t(height), frame.planes, {}, warmupRun);
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  } else if (&surface == &surfacePlaceholder && !methodOnly) {
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                   VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }

  // ---- Pass 3: resolve, one fragment per pixel, into the resolve attachments (evidence on
  // demand: none; pass 5 resolves the listed pixels after the readback of pass 4) ----
  if (resolve != VK_NULL_HANDLE && !methodOnly) {
    const int attachments = resolveAttachments(method.filter);
    VkRenderingAttachmentInfo colors[kResolveAttachments + 1];
    for (int i = 0; i < attachments; ++i) {
      // After the planes pass (pass 3a), which wrote resolveOut[0] too.
      vk::transition(cmd, resolveOut[i], VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                     VK_PIPELINE_STAGE_2_HOST_BIT | VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                     VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                     VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      colors[i] = overwrittenColor(resolveOut[i].layerView(0), VK_IMAGE_LAYOUT_GENERAL);
    }
    if (frame.resolveSurface)  // the group's surface, for the lookup (as the planes pass draws it on demand)
      vk::transition(cmd, surface, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                     VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    const int targets = attachments + (frame.resolveSurface ? 1 : 0);
    if (frame.resolveSurface) colors[attachments] = overwrittenColor(surface.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
    drawFullscreen(cmd, colors, uint32_t(targets), uint32_t(width), uint32_t(height), resolve, {}, warmupRun);
    if (frame.resolveSurface)
      vk::transition(cmd, surface, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
                     VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                     VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
  barrierToHost(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 4);

  // ---- Pass 4: the lookup, the method's visibility alone (1 byte per pixel), timed on its own ----
  if (lookup != VK_NULL_HANDLE) {
    vk::transition(cmd, lookupOut, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_HOST_BIT, 0,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    const VkRenderingAttachmentInfo color = overwrittenColor(lookupOut.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
    drawFullscreen(cmd, &color, 1, uint32_t(width), uint32_t(height), lookup, {}, warmupRun);
    barrierToHost(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                  VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  }
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 2);
}

// The frame's channels from the visibility buffer (hit, object_id, prim_id), the resolve
// attachments (the light's channels, see resolve.frag's outA/outB) and the projector planes.
// Each attachment is read once, row by row, its components scattered to their planes; the rows
// are split over two threads (the split is bound by memory bandwidth, which one core does not
// saturate). Ids arrive as global triangle index + 1 (0: none) and leave as the object's id and
// its own primitive index.
Frame Rasterizer::Impl::readback(const Scene& sc, const Light* light, const Method& method, int width, int height) {
  const bool momentChannels = light && isMomentFilter(method.filter);
  output.invalidate(*context);
  cameraIds.invalidate(*context);
  for (int i = 0; i < resolveAttachments(method.filter); ++i) resolveOut[i].invalidate(*context);
  Frame frame;
  frame.width = width;
  frame.height = height;
  const size_t n = size_t(width) * size_t(height);
  const bool hasLight = light != nullptr;
  const int projectorCount = int(sc.projectors.size());
  frame.names = {"hit", "object_id", "prim_id"};
  if (light) {
    const std::string p = "light." + light->name + ".";
    for (const char* name : {"vis", "receiver_depth", "map_depth", "m", "bias_depth", "bias_world", "occluder_id",
                             "occluder_prim", "in_map", "cascade"})
      frame.names.push_back(p + name);
    // Filterable maps: the moments' evidence at the lookup (resolve.frag's outC).
    if (momentChannels)
      for (const char* name : {"moment_mean", "moment_variance", "moment_bound"}) frame.names.push_back(p + name);
  }
  for (int j = 0; j < projectorCount; ++j) {
    const std::string p = "proj." + sc.projectors[size_t(j)].name + ".";
    for (const char* name : {"coverage", "R", "G", "B", "reverse"}) frame.names.push_back(p + name);
  }
  frame.data.resize(frame.names.size());
  // Recycled planes first (resized to this frame; every element is overwritten below).
  for (size_t c = 0; c < frame.data.size() && !spare.empty(); ++c) {
    frame.data[c] = std::move(spare.back());
    spare.pop_back();
  }
  spare.clear();
  auto allocate = [&](size_t first, size_t step) {
    for (size_t c = first; c < frame.data.size(); c += step) frame.data[c].resize(n);
  };
  {
    std::thread helper(allocate, 1, 2);
    allocate(0, 2);
    helper.join();
  }
  const float* planes = static_cast<const float*>(output.mapped());
  auto split = [&](size_t y0, size_t y1) {
    for (int y = int(y0); y < int(y1); ++y) {
      const size_t o = size_t(y) * size_t(width);
      cameraRow(y, frame.data[0].data() + o, frame.data[1].data() + o, frame.data[2].data() + o);
      if (hasLight) {
        float* out[10];
        for (int c = 0; c < 10; ++c) out[c] = frame.data[size_t(3 + c)].data() + o;
        const float* a = mappedRow<float>(resolveOut[0], size_t(y));
        const float* b = mappedRow<float>(resolveOut[1], size_t(y));
        for (int x = 0; x < width; ++x) {
          for (int k = 0; k < 4; ++k) out[k][x] = a[4 * x + k];
          out[4][x] = b[4 * x];
          out[5][x] = b[4 * x + 1];
          idsOf(uint32_t(b[4 * x + 2]), out[6][x], out[7][x]);  // exact up to 2^24
          const int packed = int(b[4 * x + 3]);                 // 2 * cascade + in_map
          out[8][x] = float(packed & 1);
          out[9][x] = float(packed >> 1);
        }
        if (momentChannels) {
          const float* c = mappedRow<float>(resolveOut[2], size_t(y));
          float* mean = frame.data[13].data() + o;
          float* variance = frame.data[14].data() + o;
          float* bound = frame.data[15].data() + o;
          for (int x = 0; x < width; ++x) {
            mean[x] = c[4 * x];
            variance[x] = c[4 * x + 1];
            bound[x] = c[4 * x + 2];
          }
        }
      }
      const size_t first = hasLight ? (momentChannels ? 16 : 13) : 3;
      for (int p = 0; p < kProjectorChannels * projectorCount; ++p) {
        const float* in = planes + size_t(p) * n + o;
        std::copy(in, in + width, frame.data[first + size_t(p)].data() + o);
      }
    }
  };
  inTwoHalves(size_t(height), split);
  return frame;
}

namespace {
// The method as the passes read it: a technique file's moments line (technique.h) makes its
// filterable map the filter whose moments pass, attachments and evidence channels the frame gets
// (the technique's shadowVisibility still gives vis: resolve.frag's kTechnique).
// Every fit but sphere follows the camera's view frustum (tight's and the cascades' corners from
// its field of view, lispsm's, psm's and tsm's eye point, sdsm's perspective samples): with an
// orthographic camera they are refused (exit 2) rather than fitted to a frustum it does not have.
void checkOrthographicFit(const Scene& scene, const Light* light, const Method& method, const Camera& camera) {
  if (!camera.orthographic() || !light || light->type != LightType::Directional || method.fit == Fit::Sphere) return;
  throw InputError(formatError("method", "fit",
                               "got " + toString(method.fit) + " with the orthographic camera of " +
                                   (scene.path.empty() ? scene.name : scene.path) + "; expected fit=sphere (fit=" +
                                   toString(method.fit) + " follows a perspective camera's frustum)"));
}

Method withEffectiveFilter(const Method& requested) {
  Method m = requested;
  m.filter = effectiveFilter(requested);
  return m;
}
}  // namespace

Rasterizer::Rasterizer(const RasterDeviceOptions& options) : impl_(std::make_unique<Impl>(options)) {}
Rasterizer::~Rasterizer() {
  // A device that stopped answering is still running what it was given: destroying what it reads
  // could crash it, waiting for it would never end. Left as it is; the process ends with _exit.
  if (impl_ && impl_->context && impl_->context->hung()) (void)impl_.release();
}

namespace {
std::atomic<bool> gDeviceHung{false};
}  // namespace
bool rasterDeviceHung() { return gDeviceHung.load(); }

void checkGpuTimeout(double seconds, const std::string& origin, const std::string& pointer) {
  if (seconds >= 0 && seconds <= 1e6) return;
  char got[32];
  std::snprintf(got, sizeof got, "%g", seconds);
  throw InputError(formatError(
      origin, pointer,
      std::string("got ") + got + "; expected seconds, a number 0..1e6 (0: $SHADOWLAB_GPU_TIMEOUT_S, else 120)"));
}
void markRasterDeviceHung() { gDeviceHung = true; }

void precompileTechnique(const Method& method) {
  if (!method.technique.empty()) raster::compileTechnique(loadTechniqueFile(method.technique));
}
Rasterizer::Rasterizer(Rasterizer&&) noexcept = default;
Rasterizer& Rasterizer::operator=(Rasterizer&&) noexcept = default;

std::string Rasterizer::deviceName() const { return impl_->context->deviceName(); }

int Rasterizer::maxMapSize() const { return impl_->maxMapSize(); }

DeviceMemoryLimits Rasterizer::memoryLimits() const { return impl_->memoryLimits(); }

std::vector<DeviceImage> Rasterizer::plannedImages(const Scene& scene, const Method& requested,
                                                   const std::string& light) const {
  const Method method = withEffectiveFilter(requested);
  const Light* l = impl_->validate(scene, method, light);
  return impl_->plannedImages(scene, method, raster::fitFrameLayers(scene, l, method, scene.camera));
}

void Rasterizer::check(const Scene& scene, const Method& method, const std::string& light) const {
  checkDeviceMemory(plannedImages(scene, method, light), memoryLimits());
}

int Rasterizer::validationMessages() const { return impl_->context->validationMessages(); }

std::vector<uint8_t> Rasterizer::lookupVisibility() const {
  const vk::Image& img = impl_->lookupOut;
  std::vector<uint8_t> out;
  if (!img.mapped()) return out;
  img.invalidate(*impl_->context);
  out.resize(size_t(img.width()) * size_t(img.height()));
  for (int y = 0; y < img.height(); ++y) {
    const uint8_t* row = mappedRow<uint8_t>(img, size_t(y));
    std::copy(row, row + img.width(), out.data() + size_t(y) * size_t(img.width()));
  }
  return out;
}

std::vector<Rasterizer::MethodTiming> Rasterizer::retimeMethod(int repeats) {
  Impl& im = *impl_;
  std::vector<MethodTiming> out;
  if (!im.last.valid) return out;
  const Impl::LastSubmit& l = im.last;
  for (int k = 0; k < repeats; ++k) {
    VkCommandBuffer cmd = im.commands->begin();
    im.methodOnly = true;
    try {
      im.record(cmd, l.layerDraws, l.lightLayers, l.pipes, l.method, l.cameraClip, l.width, l.height,
                /*drawVisibility=*/false, /*drawShadow=*/true);
    } catch (...) {
      im.methodOnly = false;
      throw;
    }
    im.methodOnly = false;
    im.commands->submitAndWait();
    // Drawn: the shadow layers (their time also becomes the one a next frame with kept maps reports).
    const Impl::PassTimes p = im.readTimestamps({false, true});
    MethodTiming m;
    m.shadowGpuMs = p.shadowGpuMs;
    m.lookupGpuMs = l.light ? p.lookupGpuMs : 0.0;
    m.momentsGpuMs = isMomentFilter(l.method.filter) ? p.momentsGpuMs : 0.0;
    out.push_back(m);
  }
  return out;
}

void Rasterizer::recycle(Frame&& frame) {
  Impl& im = *impl_;
  const size_t n = frame.pixelCount();
  Impl::Lent& lent = im.lent;
  Impl::Footprint* footprint = nullptr;
  for (Impl::Footprint& f : im.footprints)
    if (f.key == lent.footprintKey) footprint = &f;
  std::vector<float>* home[5] = {&im.cameraPlanes.hit, &im.cameraPlanes.objectId, &im.cameraPlanes.primId,
                                 footprint ? &footprint->m : nullptr, footprint ? &footprint->cascade : nullptr};
  for (std::vector<float>& plane : frame.data) {
    if (plane.size() != n || n == 0) continue;
    const float* data = plane.data();
    bool back = false;
    for (int k = 0; k < 5 && !back; ++k)
      if (data == lent.kept[k] && home[k] && home[k]->empty()) {
        *home[k] = std::move(plane);  // the kept plane, lent to this frame
        lent.kept[k] = nullptr;
        back = true;
      }
    if (back) continue;
    if (data == lent.vis && im.visKept.plane.empty() && im.visKept.bytes.size() == n) {
      for (uint32_t i : lent.listed) plane[i] = im.visKept.bytes[i] == 255 ? 1.0f : 0.0f;  // the evidence's floats
      im.visKept.plane = std::move(plane);
      lent.vis = nullptr;
      continue;
    }
    if (std::find(lent.zeroed.begin(), lent.zeroed.end(), data) != lent.zeroed.end() && im.zeroSpare.size() < 16) {
      for (uint32_t i : lent.listed) plane[i] = 0.0f;  // the only non-zero values
      im.zeroSpare.push_back(std::move(plane));
    } else {
      im.spare.push_back(std::move(plane));
    }
  }
  lent.zeroed.clear();
  frame = Frame();
}

// ---- render()'s steps, in the order it calls them ----

// Validation: everything that can be wrong with the request, before any GPU work. Returns the
// light to render (nullptr: the scene's projectors only).
const Light* Rasterizer::Impl::validate(const Scene& scene, const Method& method, const std::string& lightName) const {
  const std::string where = scene.path.empty() ? scene.name : scene.path;
  const int maxSize = maxMapSize();
  const std::string chosen = scene.lightOrDefault(lightName);
  const Light* light = chosen.empty() ? nullptr : scene.findLight(chosen);
  if (!chosen.empty()) {
    if (!light) {
      std::string names;
      for (auto& l : scene.lights) names += (names.empty() ? "" : ", ") + l.name;
      throw InputError(formatError(where, "",
                                   "no light named \"" + lightName + "\"; expected one of: " +
                                       (names.empty() ? "(the scene has no lights)" : names)));
    }
  }
  checkOrthographicFit(scene, light, method, scene.camera);
  if (method.mapSize < 16 || method.mapSize > maxSize)
    throw InputError(formatError("method", "map.size",
                                 "got " + std::to_string(method.mapSize) + "; expected 16.." + std::to_string(maxSize) +
                                     " (the device's largest image)"));
  if (method.filter == Filter::Pcf && (method.filterSize < 1 || method.filterSize % 2 == 0 || method.filterSize > 15))
    throw InputError(formatError("method", "filter.size",
                                 "got " + std::to_string(method.filterSize) + "; expected an odd number 3..15"));
  if (method.filter == Filter::Poisson && (method.filterTaps < 1 || method.filterTaps > abi::kMaxTaps))
    throw InputError(
        formatError("method", "filter.taps",
                    "got " + std::to_string(method.filterTaps) + "; expected 1.." + std::to_string(abi::kMaxTaps)));
  if (method.filter == Filter::Poisson && !(method.filterRadius > 0.0f && method.filterRadius <= 32.0f))
    throw InputError(formatError("method", "filter.radius",
                                 "got " + std::to_string(method.filterRadius) + "; expected > 0 and <= 32 texels"));
  // The soft filters take the light's size in map units from a layer that is a plain crop (an
  // orthographic one for a directional light): a warped map's texel and depth scales change
  // across it, so no one size per layer holds (raster/METHODS.md "Soft filters").
  const bool softFilter = method.filter == Filter::Pcss || method.filter == Filter::Dpcf;
  if (softFilter && light && light->type == LightType::Directional &&
      (method.fit == Fit::Lispsm || method.fit == Fit::Psm || method.fit == Fit::Tsm))
    throw InputError(formatError("method", "fit",
                                 "got " + toString(method.fit) + " with filter=" + toString(method.filter) +
                                     " and the directional light \"" + light->name +
                                     "\"; expected fit=sphere, tight, cascades or sdsm (a warped map has no one "
                                     "light size in texels)"));
  if (scene.projectors.size() > size_t(abi::kMaxProjectors))
    throw InputError(formatError(where, "/projectors",
                                 "got " + std::to_string(scene.projectors.size()) +
                                     " projectors; the rasterizer renders at most " +
                                     std::to_string(abi::kMaxProjectors)));
  const Camera& camera = scene.camera;
  if (camera.width < 1 || camera.height < 1 || camera.width > maxSize || camera.height > maxSize)
    throw InputError(formatError(
        where, "/camera",
        "image size " + std::to_string(camera.width) + "x" + std::to_string(camera.height) + " is not renderable"));
  VkFormatProperties fp;
  vkGetPhysicalDeviceFormatProperties(context->physical(), vkDepthFormat(method.mapFormat), &fp);
  VkFormatFeatureFlags need = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
  if ((fp.optimalTilingFeatures & need) != need)
    throw InputError(formatError("method", "map.format",
                                 "got " + toString(method.mapFormat) + ", which device " + context->deviceName() +
                                     " cannot render and sample; expected another format"));
  if (isMomentFilter(method.filter)) {
    // The moments map is rendered, then sampled with linear filtering.
    const VkFormat mf = momentsFormat(method.filter);
    vkGetPhysicalDeviceFormatProperties(context->physical(), mf, &fp);
    need = VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT |
           VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
    if ((fp.optimalTilingFeatures & need) != need)
      throw InputError(formatError("method", "filter",
                                   "got " + toString(method.filter) + ", whose moments map (" +
                                       (mf == VK_FORMAT_R32G32_SFLOAT ? "RG32F" : "RGBA32F") + ") device " +
                                       context->deviceName() +
                                       " cannot render and sample with linear filtering; expected another filter"));
  }
  return light;
}

int Rasterizer::Impl::maxMapSize() const {
  const VkPhysicalDeviceLimits& l = context->properties().limits;
  return int(std::min({l.maxImageDimension2D, l.maxFramebufferWidth, l.maxFramebufferHeight}));
}

DeviceMemoryLimits Rasterizer::Impl::memoryLimits() const {
  DeviceMemoryLimits out;
  out.deviceName = context->deviceName();
  out.cpuDevice = context->properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  const VkPhysicalDeviceMemoryProperties& memory = context->memoryProperties();
  for (uint32_t i = 0; i < memory.memoryHeapCount; ++i)
    if (memory.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      out.deviceLocalHeapBytes = std::max<uint64_t>(out.deviceLocalHeapBytes, memory.memoryHeaps[i].size);
  out.maxAllocationBytes = context->maxAllocationBytes();
  out.maxImageDimension2D = context->properties().limits.maxImageDimension2D;
  out.maxImageArrayLayers = context->properties().limits.maxImageArrayLayers;
  return out;
}

// What ensureImages and ensureMoments allocate for this frame (the map in the larger of its two
// formats: the depth+stencil twin serves evidence on demand), sized by the device itself
// (vkGetDeviceImageMemoryRequirements, Vulkan 1.3: no image is created).
std::vector<DeviceImage> Rasterizer::Impl::plannedImages(const Scene& scene, const Method& method,
                                                         const raster::FrameLayers& layers) const {
  auto bytesOf = [&](int width, int height, int count, VkFormat format, VkImageUsageFlags usage, bool linear) {
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {uint32_t(width), uint32_t(height), 1};
    info.mipLevels = 1;
    info.arrayLayers = uint32_t(count);
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = linear ? VK_IMAGE_TILING_LINEAR : VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    VkDeviceImageMemoryRequirements query{VK_STRUCTURE_TYPE_DEVICE_IMAGE_MEMORY_REQUIREMENTS};
    query.pCreateInfo = &info;
    VkMemoryRequirements2 req{VK_STRUCTURE_TYPE_MEMORY_REQUIREMENTS_2};
    vkGetDeviceImageMemoryRequirements(context->device(), &query, &req);
    return uint64_t(req.memoryRequirements.size);
  };
  const std::string scenePlace = scene.path.empty() ? scene.name : scene.path;
  // A sweep asks for the same images frame after frame: the device is asked once per shape.
  const std::string key = scenePlace + "|" + std::to_string(method.mapSize) + "|" + toString(method.mapFormat) + "|" +
                          toString(method.filter) + "|" + std::to_string(layers.layers.size()) + "|" +
                          std::to_string(layers.lightLayers) + "|" + std::to_string(scene.camera.width) + "x" +
                          std::to_string(scene.camera.height);
  if (key == plannedKey) return planned;
  std::vector<DeviceImage> out;
  auto add = [&](const char* what, bool map, int width, int height, int count, VkFormat format, VkImageUsageFlags usage,
                 bool linear = false) {
    out.push_back({what, map ? "method" : scenePlace, map ? "map.size" : "/camera", width, height, count,
                   bytesOf(width, height, count, format, usage, linear)});
  };
  // Sizes the device cannot make at all are validate()'s and checkDeviceMemory's to refuse, by
  // their limits, before the device is asked about them.
  const uint32_t maxLayers = context->properties().limits.maxImageArrayLayers;
  const int size = method.mapSize, mapLayers = std::max(1, int(layers.layers.size()));
  auto sized = [&](const char* what, bool map, int width, int height, int count, VkFormat format,
                   VkImageUsageFlags usage, bool linear = false) {
    if (uint32_t(count) > maxLayers)
      out.push_back({what, map ? "method" : scenePlace, map ? "map.size" : "/camera", width, height, count, 0});
    else add(what, map, width, height, count, format, usage, linear);
  };
  const VkImageUsageFlags depthUsage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  sized("shadow map depth", true, size, size, mapLayers, vkDepthFormat(method.mapFormat), depthUsage);
  VkFormatProperties fp;
  const VkFormat twin = vkDepthStencilFormat(method.mapFormat);
  vkGetPhysicalDeviceFormatProperties(context->physical(), twin, &fp);
  const VkFormatFeatureFlags need =
      VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
  if ((fp.optimalTilingFeatures & need) == need && uint32_t(mapLayers) <= maxLayers) {
    const uint64_t twinBytes = bytesOf(size, size, mapLayers, twin, depthUsage, false);
    out.back().bytes = std::max(out.back().bytes, twinBytes);
  }
  const VkImageUsageFlags colorUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  sized("shadow map ids", true, size, size, mapLayers, kIdFormat, colorUsage);
  if (isMomentFilter(method.filter)) {
    const int lightLayers = std::max(1, layers.lightLayers);
    sized("moments map", true, size, size, lightLayers, momentsFormat(method.filter), colorUsage);
    sized("moments rows", true, size, size, lightLayers, momentsFormat(method.filter), colorUsage);
  }
  const int width = scene.camera.width, height = scene.camera.height;
  add("camera depth", false, width, height, 1, kCameraDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT);
  add("camera ids", false, width, height, 1, kIdFormat, colorUsage, true);
  for (int i = 0; i < resolveAttachments(method.filter); ++i)
    add("camera resolve target", false, width, height, 1, kResolveFormats[i], VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
        true);
  add("camera lookup target", false, width, height, 1, kLookupFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, true);
  plannedKey = key;
  planned = out;
  return out;
}

// Upload: the scene's geometry, materials and projector images (cached by content hash).
void Rasterizer::Impl::upload(const Scene& sc) {
  std::string key = raster::sceneKey(sc);
  if (scene && scene->hash == key) return;
  scene.reset();
  visibilityKey.clear();
  shadowKey.clear();
  scene = std::make_unique<raster::SceneGpu>(raster::uploadScene(*context, sc, key));
}

// Whether a frame of evidence on demand can take its occluder ids from the map's stencil: the
// device renders and samples the map format's depth+stencil twin, and the scene's objects fit in
// 8 bits (the uploaded scene's).
bool Rasterizer::Impl::stencilIdsApply(const Method& method) {
  if (scene->objectIds.size() > kMaxStencilObjects) return false;
  auto it = stencilFormatOk.find(method.mapFormat);
  if (it == stencilFormatOk.end()) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(context->physical(), vkDepthStencilFormat(method.mapFormat), &fp);
    const VkFormatFeatureFlags need =
        VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
    it = stencilFormatOk.emplace(method.mapFormat, (fp.optimalTilingFeatures & need) == need).first;
  }
  return it->second;
}

// Targets: the map layers, the camera's images, the projector planes, the descriptor set.
// stencilIds: the map in its depth+stencil format (stencilIdsApply), for the stencil ids.
void Rasterizer::Impl::prepareTargets(const Scene& sc, const Method& method, const raster::FrameLayers& layers,
                                      bool stencilIds) {
  const Camera& camera = sc.camera;
  ensureImages(method.mapSize, stencilIds ? vkDepthStencilFormat(method.mapFormat) : vkDepthFormat(method.mapFormat),
               std::max(1, int(layers.layers.size())), camera.width, camera.height, isMomentFilter(method.filter));
  const size_t channelCount = size_t(kProjectorChannels) * sc.projectors.size();
  size_t outputBytes = std::max<size_t>(1, channelCount * size_t(camera.width) * size_t(camera.height)) * sizeof(float);
  if (output.size() != outputBytes) output = vk::Buffer(*context, outputBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  ensureMoments(method.filter, method.mapSize, layers.lightLayers);
  raster::updatePlanes(*scene, raster::cameraRaysOrigin(camera));
  writeDescriptors();
}

// Where each uploaded projector image lies in the projector texel table.
std::vector<raster::ProjectorTexels> Rasterizer::Impl::projectorTexels() const {
  std::vector<raster::ProjectorTexels> out;
  for (const raster::ProjectorImage& pi : scene->projectors) out.push_back({pi.firstTexel, pi.width, pi.height});
  return out;
}

// Pipelines: the id writers for the map's format (the one prepareTargets chose) and clamp, the
// resolve for its specialization.
Rasterizer::Impl::FramePipelines Rasterizer::Impl::pipelinesFor(const Method&, const raster::FrameLayers& layers,
                                                                const raster::ResolveSpecialization& spec, bool partial,
                                                                bool planes) {
  VkFormat mapFormat = mapDepth.format();
  bool depthClamp = layers.depthClamp;
  FramePipelines p;
  p.ids = {idPipeline(mapFormat, depthClamp, false, true), idPipeline(mapFormat, depthClamp, true, true),
           idPipeline(kCameraDepthFormat, false, false, false), idPipeline(kCameraDepthFormat, false, true, false)};
  for (const raster::MapLayer& l : layers.layers)
    if (l.lightDepth) {
      p.ids.shadowLightDepthPlain = idPipeline(mapFormat, depthClamp, false, false, true);
      p.ids.shadowLightDepthTested = idPipeline(mapFormat, depthClamp, true, false, true);
    }
  // The lookup: the same specialization, the evidence and the projectors compiled out, the
  // visible point from the group's surface where the method needs no normal.
  raster::ResolveSpecialization lookupSpec = spec;
  lookupSpec[abi::kSpecLookupOnly] = 1u;
  lookupSpec[abi::kSpecProjectorCount] = 0u;
  lookupSpec[abi::kSpecSurface] = lookupReadsSurface(spec) ? 1u : 0u;
  const bool light = spec[abi::kSpecLightType] != uint32_t(abi::kLightNone);
  if (partial) {
    // Evidence on demand: the resolve over the listed pixels only (pass 5), no projectors; the
    // lookup over those listed for the occluder alone.
    raster::ResolveSpecialization compactSpec = spec;
    compactSpec[abi::kSpecCompact] = 1u;
    compactSpec[abi::kSpecProjectorCount] = 0u;
    p.evidence = resolvePipeline(compactSpec);
    p.evidenceFirstUse = evidenceWarmed.insert({compactSpec, techniqueKey}).second;
    if (light) {
      raster::ResolveSpecialization occluderSpec = lookupSpec;
      occluderSpec[abi::kSpecCompact] = 1u;
      p.evidenceOccluder = resolvePipeline(occluderSpec);
      p.evidenceFirstUse = evidenceWarmed.insert({occluderSpec, techniqueKey}).second || p.evidenceFirstUse;
    }
  } else {
    p.resolve = resolvePipeline(spec);
    p.resolveSurface = resolveWritesSurface(spec);
  }
  if (planes) {
    // A group's first frame: pass 3a draws its planes (m, cascade; kept on demand) and its surface
    // (the lookup's). They depend on no bias or filter (footprintKey), so every filter's group
    // shares one pipeline.
    raster::ResolveSpecialization planesSpec = spec;
    planesSpec[abi::kSpecPlanesOnly] = 1u;
    planesSpec[abi::kSpecProjectorCount] = 0u;
    for (int k : {abi::kSpecFilter, abi::kSpecPcfSize, abi::kSpecAdaptive, abi::kSpecReceiverPlane,
                  abi::kSpecNormalOffset, abi::kSpecTechniqueNormal})
      planesSpec[size_t(k)] = 0u;
    static_assert(int(Filter::None) == 0, "kSpecFilter 0 is filter none");
    p.planes = resolvePipeline(planesSpec);
  }
  if (light) p.lookup = resolvePipeline(lookupSpec);
  // lavapipe compiles shaders at first use: the first frame of a combination runs twice.
  std::string warmKey = std::to_string(int(mapFormat)) + "/" + std::to_string(depthClamp) + "/" +
                        std::to_string(partial) + "/" + std::to_string(planes);
  for (uint32_t k : spec) warmKey += "/" + std::to_string(k);
  warmKey += "/" + techniqueKey;
  p.firstUse = warmed.insert(warmKey).second;
  return p;
}

// Submit: records and runs the frame (twice at a pipeline's first use, the second one timed).
// Draws the visibility buffer unless the one of the same scene and camera is still there.
Rasterizer::Impl::Drawn Rasterizer::Impl::submit(const Scene& sc, const Method& method,
                                                 const raster::FrameLayers& layers, const FramePipelines& pipes) {
  const Camera& camera = sc.camera;
  std::vector<LayerDraw> layerDraws;
  for (const raster::MapLayer& l : layers.layers)
    layerDraws.push_back({raster::clipFromTex() * l.texFromWorld, l.lightDepth, l.depthFromWorld});
  glm::mat4 cameraClip = camera.clipFromView() * camera.viewFromWorld();
  const std::string key = cameraKey(sc);
  const bool drawVisibility = visibilityKey != key;
  visibilityKey.clear();  // until this frame is through
  // At a pipeline's first use both runs draw the maps: the timed one must not inherit the first's.
  const std::string mapKey = shadowPassKey(layerDraws, pipes.ids, method);
  const bool drawShadow = !keepShadowMaps || shadowKey != mapKey || pipes.firstUse;
  shadowKey.clear();
  for (int run = 0; run < (pipes.firstUse ? 2 : 1); ++run) {
    VkCommandBuffer cmd = commands->begin();
    warmupRun = pipes.firstUse && run == 0;  // one pixel per pass: compiles, draws next to nothing
    try {
      record(cmd, layerDraws, layers.lightLayers, pipes, method, cameraClip, camera.width, camera.height,
             drawVisibility, drawShadow);
    } catch (...) {
      warmupRun = false;
      throw;
    }
    warmupRun = false;
    commands->submitAndWait();
  }
  visibilityKey = key;
  shadowKey = mapKey;
  last.valid = true;
  last.layerDraws = layerDraws;
  last.lightLayers = layers.lightLayers;
  last.pipes = pipes;
  last.method = method;
  last.cameraClip = cameraClip;
  last.width = camera.width;
  last.height = camera.height;
  last.light = pipes.lookup != VK_NULL_HANDLE;
  return {drawVisibility, drawShadow};
}

// What pass 1 reads besides the scene's buffers: the map image and its format, the pipelines
// (depth clamp, material tests, light depth, stencil ids), the depth bias and cull, and per layer
// its clip matrix and light-depth row. Equal keys draw equal maps.
std::string Rasterizer::Impl::shadowPassKey(const std::vector<LayerDraw>& layerDraws, const IdPipelines& pipes,
                                            const Method& method) const {
  std::string key = scene->hash;
  auto add = [&](const auto& value) { key.append(reinterpret_cast<const char*>(&value), sizeof(value)); };
  add(mapDepth.get()), add(mapDepth.format()), add(mapDepth.width()), add(mapDepth.layers());
  add(pipes.shadowPlain), add(pipes.shadowTested), add(pipes.shadowLightDepthPlain), add(pipes.shadowLightDepthTested);
  add(method.biasConstant), add(method.biasSlope), add(method.biasClamp), add(method.cull), add(method.mapSize);
  for (const LayerDraw& l : layerDraws) add(l.clip), add(l.lightDepth), add(l.depthRow);
  return key;
}

// Timestamps: the passes' GPU times of the last submit (kTimestamps says which stamp is where).
Rasterizer::Impl::PassTimes Rasterizer::Impl::readTimestamps(Drawn drawn) {
  uint64_t stamps[kTimestamps] = {};
  VK_CHECK(vkGetQueryPoolResults(context->device(), queries.get(), 0, kTimestamps, sizeof(stamps), stamps,
                                 sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  const double msPerTick = context->properties().limits.timestampPeriod * 1e-6;
  if (drawn.visibility) visibilityGpuMs = double(stamps[3] - stamps[1]) * msPerTick;
  if (drawn.shadow) shadowLayersGpuMs = double(stamps[5] - stamps[0]) * msPerTick;
  PassTimes t;
  // Kept maps: the layers' time when they were drawn, and this frame's moments pass.
  t.shadowGpuMs = shadowLayersGpuMs + double(stamps[1] - stamps[5]) * msPerTick;
  t.resolveGpuMs = double(stamps[4] - stamps[3]) * msPerTick;
  t.lookupGpuMs = double(stamps[2] - stamps[4]) * msPerTick;
  t.momentsGpuMs = double(stamps[1] - stamps[5]) * msPerTick;
  return t;
}

// The visibility buffer's key: the scene, the camera's matrices, the image size.
std::string Rasterizer::Impl::cameraKey(const Scene& sc) const { return cameraKey(sc.camera); }

std::string Rasterizer::Impl::cameraKey(const Camera& camera) const {
  glm::mat4 cameraClip = camera.clipFromView() * camera.viewFromWorld();
  return scene->hash + "/" + hashHex(fnv1a64(&cameraClip, sizeof(cameraClip))) + "/" + std::to_string(camera.width) +
         "x" + std::to_string(camera.height);
}

// fit=sdsm's samples, as an engine's depth reduction reads its depth buffer: pass 2 recorded alone
// for the fit camera (its own submit: the fit must be known before pass 1), its ids read back and
// each hit pixel's world point reconstructed on the CPU (sdsm.h's visiblePoint: the ray through
// the pixel's center and the plane of its triangle, as resolve.frag does). Kept per scene and fit
// camera (a sweep over methods reduces once). The main submit then draws its own visibility buffer
// again (visibilityKey cleared), so camera_gpu_ms stays the camera pass's, without this one.
const std::vector<glm::vec3>& Rasterizer::Impl::visiblePoints(const Scene& sc, const Light* light, const Method& method,
                                                              const Camera& fitCamera, bool stencilIds) {
  const std::string key = cameraKey(fitCamera);
  if (samplesKey == key) return samplePoints;
  samplesKey.clear();
  if (fitCamera.width != sc.camera.width || fitCamera.height != sc.camera.height)
    throw InputError("fit camera: error: got an image of " + std::to_string(fitCamera.width) + "x" +
                     std::to_string(fitCamera.height) + "; expected the scene camera's " +
                     std::to_string(sc.camera.width) + "x" + std::to_string(sc.camera.height) +
                     " (fit=sdsm samples it with the camera pass's images)");
  // The camera's images and the descriptor set record() binds, as the frame will have them (the
  // layer count is the same with or without the samples).
  prepareTargets(sc, method, raster::fitFrameLayers(sc, light, method, fitCamera), stencilIds);
  FramePipelines pipes;
  pipes.ids = {VK_NULL_HANDLE, VK_NULL_HANDLE, idPipeline(kCameraDepthFormat, false, false, false),
               idPipeline(kCameraDepthFormat, false, true, false)};
  const glm::mat4 clip = fitCamera.clipFromView() * fitCamera.viewFromWorld();
  VkCommandBuffer cmd = commands->begin();
  record(cmd, {}, 0, pipes, method, clip, fitCamera.width, fitCamera.height, true, false, true);
  commands->submitAndWait();
  visibilityKey.clear();  // cameraIds hold the fit camera's ids now
  cameraIds.invalidate(*context);
  const CameraRays rays(fitCamera);
  const std::vector<glm::vec3>& vertices = scene->triangleVertices;
  const size_t triangles = vertices.size() / 3;
  std::vector<glm::vec3> halves[2];
  auto reduce = [&](size_t y0, size_t y1) {
    std::vector<glm::vec3>& out = halves[y1 == size_t(fitCamera.height) ? 1 : 0];  // rows in order after the join
    for (size_t y = y0; y < y1; ++y) {
      const uint32_t* ids = mappedRow<uint32_t>(cameraIds, y);
      for (int x = 0; x < fitCamera.width; ++x) {
        if (ids[x] == 0 || ids[x] > triangles) continue;
        const size_t t = size_t(ids[x] - 1);
        glm::vec3 p;
        if (raster::visiblePoint(rays, fitCamera.position, x, int(y), vertices[3 * t], vertices[3 * t + 1],
                                 vertices[3 * t + 2], p))
          out.push_back(p);
      }
    }
  };
  inTwoHalves(size_t(fitCamera.height), reduce);
  samplePoints = std::move(halves[0]);
  samplePoints.insert(samplePoints.end(), halves[1].begin(), halves[1].end());
  samplesKey = key;
  return samplePoints;
}

// Evidence on demand's group: everything m and the cascade index are computed from in resolve.frag
// (the visible point, the pixel's layer and its projection, the cascade splits, the cube face),
// none of which is a bias or a filter. The specialization constants that change that code (light
// type, cascaded, affine) are part of it; the filter's is not (the same bits whatever the filter:
// tests/compare_on_demand_test.cpp).
std::string Rasterizer::Impl::footprintKey(const Scene& sc, const abi::Params& p,
                                           const raster::ResolveSpecialization& spec) const {
  const int lightLayers = std::clamp(p.sizes.y, 0, abi::kMaxLightLayers);
  uint64_t h = fnv1a64(p.texFromWorld, sizeof(glm::mat4) * size_t(lightLayers));
  h = fnv1a64(p.layerInfo, sizeof(glm::vec4) * size_t(lightLayers), h);
  for (const glm::vec4* v : {&p.lightPosType, &p.lightDirCos, &p.cameraOrigin, &p.rayX, &p.rayY, &p.rayC,
                             &p.cascadeView, &p.cascadeFar[0], &p.cascadeFar[1]})
    h = fnv1a64(v, sizeof(glm::vec4), h);
  const float splits[2] = {p.cascadeInfo.y, p.cascadeInfo.z};  // not x: the blend band
  h = fnv1a64(splits, sizeof(splits), h);
  const int32_t sizes[2] = {p.sizes.x, p.sizes.y};
  h = fnv1a64(sizes, sizeof(sizes), h);
  for (int k : {abi::kSpecLightType, abi::kSpecCascaded, abi::kSpecAffine}) h = fnv1a64(&spec[size_t(k)], 4, h);
  return cameraKey(sc) + "/" + hashHex(h);
}

Rasterizer::Impl::Footprint* Rasterizer::Impl::findFootprint(const std::string& key) {
  for (auto it = footprints.begin(); it != footprints.end(); ++it)
    if (it->key == key) {
      footprints.splice(footprints.begin(), footprints, it);
      return &footprints.front();
    }
  return nullptr;
}

// id (global triangle + 1, 0: none) -> (object id, the object's primitive index), as floats.
void Rasterizer::Impl::idsOf(uint32_t id, float& objectId, float& prim) const {
  if (id == 0) {
    objectId = prim = 0.0f;
    return;
  }
  const uint32_t object = scene->triangleObject[id - 1];
  objectId = float(scene->objectIds[object]);
  prim = float(id - 1 - scene->objectTriangleBase[object]);
}

// Row y of the camera planes from the visibility buffer: hit (0/1), object_id, prim_id.
void Rasterizer::Impl::cameraRow(int y, float* hit, float* objectId, float* primId) const {
  const uint32_t* ids = mappedRow<uint32_t>(cameraIds, size_t(y));
  for (int x = 0; x < cameraIds.width(); ++x) {
    hit[x] = ids[x] ? 1.0f : 0.0f;
    idsOf(ids[x], objectId[x], primId[x]);
  }
}

// The first frame of a group on demand, after the planes pass (pass 3 specialized to kSpecPlanesOnly):
// keeps the camera planes (hit, object_id, prim_id from the visibility buffer, as readback() makes
// them) unless those of this camera are kept, and the group's m and cascade from the planes pass.
Rasterizer::Impl::Footprint& Rasterizer::Impl::keepPlanes(const std::string& key, const std::string& camera, int width,
                                                          int height) {
  const size_t n = size_t(width) * size_t(height);
  cameraIds.invalidate(*context);
  resolveOut[0].invalidate(*context);
  const bool cameraToo = cameraPlanes.key != camera || cameraPlanes.hit.empty();
  if (cameraPlanes.key != camera) footprints.clear();  // of another camera: never found again
  if (cameraToo) {
    cameraPlanes.key.clear();
    cameraPlanes.hit.resize(n);
    cameraPlanes.objectId.resize(n);
    cameraPlanes.primId.resize(n);
  }
  footprints.remove_if([&](const Footprint& f) { return f.key == key; });  // one whose planes are lent
  while (footprints.size() >= kKeptFootprints) footprints.pop_back();
  Footprint f{key, std::vector<float>(n), std::vector<float>(n)};
  auto split = [&](size_t y0, size_t y1) {
    for (int y = int(y0); y < int(y1); ++y) {
      const size_t o = size_t(y) * size_t(width);
      if (cameraToo)
        cameraRow(y, cameraPlanes.hit.data() + o, cameraPlanes.objectId.data() + o, cameraPlanes.primId.data() + o);
      const float* a = mappedRow<float>(resolveOut[0], size_t(y));  // m, 2 * cascade + in_map
      for (int x = 0; x < width; ++x) {
        f.m[o + size_t(x)] = a[4 * x];
        f.cascade[o + size_t(x)] = float(int(a[4 * x + 1]) >> 1);
      }
    }
  };
  inTwoHalves(size_t(height), split);
  if (cameraToo) cameraPlanes.key = camera;
  footprints.push_front(std::move(f));
  return footprints.front();
}

// The group's surface image: the kept one (kept = true: the planes pass need not draw it), else a
// slot for the planes pass (the least recently used one past kKeptFootprints), its key cleared
// until render() has drawn it. Most recently used first.
Rasterizer::Impl::SurfaceImage& Rasterizer::Impl::surfaceFor(const std::string& key, int width, int height,
                                                             bool& kept) {
  auto it = std::find_if(surfaces.begin(), surfaces.end(), [&](const SurfaceImage& s) { return s.key == key; });
  kept = it != surfaces.end();
  if (!kept) it = surfaces.size() < kKeptFootprints ? surfaces.emplace(surfaces.end()) : std::prev(surfaces.end());
  surfaces.splice(surfaces.begin(), surfaces, it);
  SurfaceImage& s = surfaces.front();
  if (!kept) {
    s.key.clear();
    if (s.image.width() != width || s.image.height() != height)
      s.image = vk::Image(*context, width, height, 1, kSurfaceFormat,
                          VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT);
  }
  return s;
}

// Evidence on demand, after the shadow and lookup passes: reads the lookup's bytes, lists the
// fractional pixels and those `select` asks for, resolves only those (pass 5: resolve.frag with
// kSpecCompact into kCompactWidth-wide targets, one texel per listed pixel) and builds the frame
// from the bytes, the kept planes and the listed pixels' evidence.
Frame Rasterizer::Impl::partialFrame(const Scene& sc, const Light& light, const Method& method,
                                     const EvidenceSelector& select, Footprint& footprint, const FramePipelines& pipes,
                                     RasterTimings& t) {
  const int width = sc.camera.width, height = sc.camera.height;
  const size_t n = size_t(width) * size_t(height);
  auto t0 = std::chrono::steady_clock::now();
  lookupOut.invalidate(*context);
  // The bytes in place when the rows are not padded (the mapped image is the row-major plane).
  const uint8_t* vis8 = static_cast<const uint8_t*>(lookupOut.mapped());
  if (lookupOut.rowPitch() != size_t(width)) {
    lookupRows.resize(n);
    for (int y = 0; y < height; ++y)
      std::memcpy(lookupRows.data() + size_t(y) * size_t(width), vis8 + size_t(y) * lookupOut.rowPitch(),
                  size_t(width));
    vis8 = lookupRows.data();
  }
  // The vis plane: the one handed back (only the changed bytes rewritten), else a spare one.
  std::vector<float> visPlane;
  const bool visFull = visKept.plane.size() != n || visKept.bytes.size() != n;
  if (!visFull) {
    visPlane = std::move(visKept.plane);
  } else if (!spare.empty()) {
    visPlane = std::move(spare.back());
    spare.pop_back();
  }
  visKept.plane.clear();
  visPlane.resize(n);
  visKept.bytes.resize(n);
  // Two threads: the vis plane and the fractional bytes beside the selector.
  std::thread visHelper(visFromBytes, vis8, n, visFull, visKept.bytes.data(), visPlane.data(), std::ref(fractional));
  asked.full.clear();
  asked.occluder.clear();
  try {
    select(vis8, width, height, asked);
  } catch (...) {
    visHelper.join();
    throw;
  }
  visHelper.join();
  // The listed pixels, each sorted, once, below n: those asked for every channel, then those whose
  // map texel's evidence alone is asked for and the fractional ones (their exact vis), less the
  // first list's.
  auto sortedOnce = [n](std::vector<uint32_t>& v) {
    if (!std::is_sorted(v.begin(), v.end())) std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    v.erase(std::lower_bound(v.begin(), v.end(), uint32_t(n)), v.end());
  };
  sortedOnce(asked.full);
  sortedOnce(asked.occluder);
  std::vector<uint32_t> listed = std::move(asked.full);
  occluderOrFractional.clear();
  std::set_union(fractional.begin(), fractional.end(), asked.occluder.begin(), asked.occluder.end(),
                 std::back_inserter(occluderOrFractional));
  occluderListed.clear();
  std::set_difference(occluderOrFractional.begin(), occluderOrFractional.end(), listed.begin(), listed.end(),
                      std::back_inserter(occluderListed));
  const size_t fullCount = listed.size(), occluderCount = occluderListed.size(), count = fullCount + occluderCount;
  const int attachments = resolveAttachments(method.filter);
  double readMs = msSince(t0);

  // ---- Pass 5: the evidence of the listed pixels ----
  double evidenceMs = 0;
  int compactWidth = kCompactWidth;
  if (count > 0) {
    const size_t bytes = count * sizeof(uint32_t);
    if (evidencePixels.size() < bytes) {
      evidencePixels =
          vk::Buffer(*context, std::max<size_t>(bytes, 2 * evidencePixels.size()), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
      writeDescriptors();
    }
    // One buffer: the full list, then the occluder's (the second draw starts at `first`), each
    // pixel as x | y << 16 (the shader then needs no integer division, which SIMD lanes lack).
    uint32_t* packed = static_cast<uint32_t*>(evidencePixels.mapped());
    packPixels(listed, uint32_t(width), packed);
    packPixels(occluderListed, uint32_t(width), packed + fullCount);
    // kCompactWidth wide, wider when a list needs more rows than the device's largest image.
    const int maxSize = maxMapSize();
    const size_t longest = std::max(fullCount, occluderCount);
    while ((longest + size_t(compactWidth) - 1) / size_t(compactWidth) > size_t(maxSize)) compactWidth *= 2;
    auto rowsOf = [&](size_t k) { return int((k + size_t(compactWidth) - 1) / size_t(compactWidth)); };
    // A compact target of at least `rows` rows (made anew when short, at least twice as tall).
    auto ensureCompact = [&](vk::Image& image, VkFormat format, int rows) {
      if (image.height() >= rows && image.width() == compactWidth) return;
      const int allocRows = std::min(maxSize, std::max(rows, image.width() == compactWidth ? 2 * image.height() : 0));
      image = vk::Image();  // released first
      image = vk::Image(*context, compactWidth, allocRows, 1, format, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                        VK_IMAGE_ASPECT_COLOR_BIT, true);
    };
    if (fullCount > 0)
      for (int i = 0; i < attachments; ++i) ensureCompact(evidenceOut[i], kResolveFormats[i], rowsOf(fullCount));
    if (occluderCount > 0) ensureCompact(occluderOut, kResolveFormats[0], rowsOf(occluderCount));
    for (int run = 0; run < (pipes.evidenceFirstUse ? 2 : 1); ++run) {
      VkCommandBuffer cmd = commands->begin();
      VkQueryPool pool = evidenceQueries.get();
      vkCmdResetQueryPool(cmd, pool, 0, 2);
      vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, pool, 0);
      VkDescriptorSet set = descriptorSet;
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout.get(), 0, 1, &set, 0, nullptr);
      // One draw per list: `targets` images, `k` pixels from `first` on, through `pipeline`.
      auto drawList = [&](vk::Image* targets, int targetCount, size_t first, size_t k, VkPipeline pipeline) {
        VkRenderingAttachmentInfo colors[kResolveAttachments];
        for (int i = 0; i < targetCount; ++i) {
          vk::transition(cmd, targets[i], VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                         VK_PIPELINE_STAGE_2_HOST_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                         VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
          colors[i] = overwrittenColor(targets[i].layerView(0), VK_IMAGE_LAYOUT_GENERAL);
        }
        drawFullscreen(
            cmd, colors, uint32_t(targetCount), uint32_t(compactWidth), uint32_t(rowsOf(k)), pipeline,
            [&] {
              // count, the compact width, the list's start (resolve.frag's push block)
              DrawPush push{glm::mat4(1.0f), uint32_t(k), uint32_t(compactWidth), uint32_t(first), 0};
              vkCmdPushConstants(cmd, pipelineLayout.get(), VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                                 0, sizeof(push), &push);
            },
            pipes.evidenceFirstUse && run == 0);
      };
      if (fullCount > 0) drawList(evidenceOut, attachments, 0, fullCount, pipes.evidence);
      if (occluderCount > 0) drawList(&occluderOut, 1, fullCount, occluderCount, pipes.evidenceOccluder);
      barrierToHost(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
      vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);
      commands->submitAndWait();
    }
    uint64_t stamps[2] = {};
    VK_CHECK(vkGetQueryPoolResults(context->device(), evidenceQueries.get(), 0, 2, sizeof(stamps), stamps,
                                   sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    evidenceMs = double(stamps[1] - stamps[0]) * context->properties().limits.timestampPeriod * 1e-6;
    if (fullCount > 0)
      for (int i = 0; i < attachments; ++i) evidenceOut[i].invalidate(*context);
    if (occluderCount > 0) occluderOut.invalidate(*context);
  }

  // ---- The frame: the readback's channels, in its order ----
  auto t1 = std::chrono::steady_clock::now();
  const bool momentChannels = isMomentFilter(method.filter);
  Frame frame;
  frame.width = width;
  frame.height = height;
  frame.names = {"hit", "object_id", "prim_id"};
  const std::string p = "light." + light.name + ".";
  for (const char* name : {"vis", "receiver_depth", "map_depth", "m", "bias_depth", "bias_world", "occluder_id",
                           "occluder_prim", "in_map", "cascade"})
    frame.names.push_back(p + name);
  if (momentChannels)
    for (const char* name : {"moment_mean", "moment_variance", "moment_bound"}) frame.names.push_back(p + name);
  frame.data.resize(frame.names.size());
  // Planes: 0 hit, 1 object_id, 2 prim_id, 3 vis, 4 receiver_depth, 5 map_depth, 6 m, 7 bias_depth,
  // 8 bias_world, 9 occluder_id, 10 occluder_prim, 11 in_map, 12 cascade, 13.. the moments'.
  // The kept ones are lent to the frame, vis is the plane filled from the bytes above, the
  // evidence planes come zeroed from zeroSpare when a frame handed them back, the rest from spare.
  std::vector<float>* kept[13] = {&cameraPlanes.hit, &cameraPlanes.objectId, &cameraPlanes.primId};
  kept[6] = &footprint.m;
  kept[12] = &footprint.cascade;
  if (!zeroSpare.empty() && zeroSpare.front().size() != n) zeroSpare.clear();
  lent = Lent();
  lent.footprintKey = footprint.key;
  std::vector<uint8_t> zeroed(frame.data.size(), 0);
  bool toFill = false;
  for (size_t c = 0; c < frame.data.size(); ++c) {
    std::vector<float>* from = c < 13 ? kept[c] : nullptr;
    if (from) {
      frame.data[c] = std::move(*from);
      from->clear();
      lent.kept[c == 6 ? 3 : c == 12 ? 4 : c] = frame.data[c].data();
      continue;
    }
    if (c == 3) {
      frame.data[c] = std::move(visPlane);  // filled above
      lent.vis = frame.data[c].data();
      continue;
    }
    std::vector<std::vector<float>>& pool = !zeroSpare.empty() ? zeroSpare : spare;
    zeroed[c] = &pool == &zeroSpare;
    toFill = toFill || !zeroed[c];
    if (!pool.empty()) {
      frame.data[c] = std::move(pool.back());
      pool.pop_back();
    }
  }
  spare.clear();
  auto fill = [&](size_t first, size_t step) {
    for (size_t c = first; c < frame.data.size(); c += step) {
      std::vector<float>& plane = frame.data[c];
      if ((c < 13 && kept[c]) || zeroed[c] || c == 3) continue;
      plane.assign(n, 0.0f);
    }
  };
  if (toFill) {  // evidence planes not handed back zeroed
    std::thread helper(fill, 1, 2);
    fill(0, 2);
    helper.join();
  }
  for (size_t c = 4; c < frame.data.size(); ++c)
    if (c != 6 && c != 12) lent.zeroed.push_back(frame.data[c].data());
  const std::vector<uint32_t>& objectIds = scene->objectIds;
  // The stencil ids hold the object index + 1 (the primitive stays unresolved: occluder_prim 0).
  const bool stencilIds = mapDepth.hasStencil();
  // The occluder's channels of a listed pixel from its id in the map (exact up to 2^24) and
  // 2 * cascade + in_map (the cascade is kept).
  auto putOccluder = [&](size_t i, float id, float cascadeInMap) {
    const uint32_t occluder = uint32_t(id);
    if (occluder != 0 && stencilIds) frame.data[9][i] = float(objectIds[occluder - 1]);
    else idsOf(occluder, frame.data[9][i], frame.data[10][i]);
    frame.data[11][i] = float(int(cascadeInMap) & 1);
  };
  // Each listed pixel's channels into the planes: distinct pixels, so two threads take half a
  // list each where it is long (a row with acne everywhere lists a third of the frame).
  auto scatter = [&](size_t k0, size_t k1) {
    for (size_t k = k0; k < k1; ++k) {
      const size_t i = listed[k];
      const size_t y = k / size_t(compactWidth), x = k % size_t(compactWidth);
      const float* a = mappedRow<float>(evidenceOut[0], y) + 4 * x;
      const float* b = mappedRow<float>(evidenceOut[1], y) + 4 * x;
      frame.data[3][i] = a[0];
      frame.data[4][i] = a[1];
      frame.data[5][i] = a[2];
      frame.data[7][i] = b[0];
      frame.data[8][i] = b[1];
      putOccluder(i, b[2], b[3]);
      if (momentChannels) {
        const float* c = mappedRow<float>(evidenceOut[2], y) + 4 * x;
        for (int j = 0; j < 3; ++j) frame.data[size_t(13 + j)][i] = c[j];
      }
    }
  };
  auto scatterOccluder = [&](size_t k0, size_t k1) {
    for (size_t k = k0; k < k1; ++k) {
      const size_t i = occluderListed[k];
      const float* a = mappedRow<float>(occluderOut, k / size_t(compactWidth)) + 4 * (k % size_t(compactWidth));
      frame.data[3][i] = a[0];
      putOccluder(i, a[1], a[2]);
    }
  };
  if (fullCount >= kParallelScatter) inTwoHalves(fullCount, scatter);
  else scatter(0, fullCount);
  if (occluderCount >= kParallelScatter) inTwoHalves(occluderCount, scatterOccluder);
  else scatterOccluder(0, occluderCount);
  // Both lists: recycle() sets these pixels of the planes back.
  listed.insert(listed.end(), occluderListed.begin(), occluderListed.end());
  lent.listed = std::move(listed);
  t.evidenceGpuMs = evidenceMs;
  t.evidencePixels = count;
  t.partialEvidence = true;
  t.readbackMs = readMs + msSince(t1);
  return frame;
}

namespace {

// Metadata: what the frame is of, for its EXR header and raster.json.
nlohmann::json frameMeta(const Scene& scene, const Light* light, const Camera& fit, const Method& method,
                         const std::string& device) {
  nlohmann::json lights = nlohmann::json::array(), projectors = nlohmann::json::array();
  for (auto& l : scene.lights) lights.push_back(l.name);
  for (auto& p : scene.projectors) projectors.push_back(p.name);
  return {{"kind", "raster"},
          {"scene", scene.name},
          {"scene_hash", scene.hash},
          {"camera_hash", scene.camera.hash()},
          {"fit_camera_hash", fit.hash()},
          {"width", scene.camera.width},
          {"height", scene.camera.height},
          {"light", light ? light->name : ""},
          {"lights", lights},
          {"projectors", projectors},
          {"method", methodToJson(method)},
          {"device", device}};
}

}  // namespace

Frame Rasterizer::render(const Scene& scene, const Method& requested, const std::string& lightName,
                         RasterTimings* timings, const Camera* fitCamera, const EvidenceSelector* select) {
  auto t0 = std::chrono::steady_clock::now();
  const Method method = withEffectiveFilter(requested);
  Impl& im = *impl_;
  // Planes lent to a frame not handed back before this render stay with it (its group's next
  // frame is a full one): recycle() only takes back what the last render lent.
  im.lent = Impl::Lent();
  const Light* light = im.validate(scene, method, lightName);
  const Camera& fit = fitCamera ? *fitCamera : scene.camera;  // what the light frustum follows
  checkOrthographicFit(scene, light, method, fit);
  im.upload(scene);
  // Evidence on demand: with a selector, a light, no projectors (their planes are every pixel's)
  // and the group's planes kept from an earlier frame.
  const bool onDemand = select && *select && light && scene.projectors.empty();
  const bool stencilIds = onDemand && im.stencilIdsApply(method);
  if (!im.surfacePlaceholder.get())
    im.surfacePlaceholder =
        vk::Image(*im.context, 1, 1, 1, kSurfaceFormat, VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT);
  if (!im.surfaceBound) im.surfaceBound = &im.surfacePlaceholder;  // fit=sdsm's sample pass writes the descriptors
  const std::vector<glm::vec3>* visible =
      raster::fitReadsVisiblePoints(light, method) ? &im.visiblePoints(scene, light, method, fit, stencilIds) : nullptr;
  const raster::FrameLayers layers = raster::fitFrameLayers(scene, light, method, fit, visible);
  checkDeviceMemory(im.plannedImages(scene, method, layers), im.memoryLimits());
  const abi::Params params = raster::packResolveParams(scene, light, method, fit, layers, im.projectorTexels());
  im.params.upload(&params, sizeof(params));
  const raster::ResolveSpecialization spec = raster::resolveSpecialization(scene, light, method, layers);
  const std::string group = light ? im.footprintKey(scene, params, spec) : std::string();
  const std::string camera = onDemand ? im.cameraKey(scene) : std::string();
  Impl::Footprint* footprint =
      onDemand && im.cameraPlanes.key == camera && !im.cameraPlanes.hit.empty() ? im.findFootprint(group) : nullptr;
  if (footprint && footprint->m.empty()) footprint = nullptr;  // lent to a frame not handed back
  // On demand, a group's first frame draws its planes (m, cascade) and its surface in pass 3a and
  // keeps them, then goes on like the group's next ones (the surface drawn again where it was not
  // kept); a full frame's resolve writes the surface beside its channels. Every frame on demand
  // reads the occluder's object from the map's stencil (no id attachment).
  const bool groupStart = onDemand && !footprint;
  const bool lookupSurface = light && lookupReadsSurface(spec);
  const bool resolveSurface = light && !onDemand;  // a full frame's resolve writes the group's surface
  bool surfaceKept = false;
  Impl::SurfaceImage* surface = groupStart || lookupSurface || resolveSurface
                                    ? &im.surfaceFor(group, scene.camera.width, scene.camera.height, surfaceKept)
                                    : nullptr;
  const bool drawPlanes = groupStart || (onDemand && lookupSurface && !surfaceKept);
  const bool drawsSurface = drawPlanes || resolveSurface;
  if (drawsSurface) surface->key.clear();  // until drawn
  im.surfaceBound = surface ? &surface->image : &im.surfacePlaceholder;
  im.prepareTargets(scene, method, layers, stencilIds);
  im.useTechnique(method);
  const Impl::FramePipelines pipes = im.pipelinesFor(method, layers, spec, onDemand, drawPlanes);
  const Impl::Drawn drawn = im.submit(scene, method, layers, pipes);
  if (drawsSurface) surface->key = group;
  const Impl::PassTimes passes = im.readTimestamps(drawn);

  RasterTimings local;
  RasterTimings& t = timings ? *timings : local;
  t = RasterTimings();
  Frame frame;
  if (onDemand) {
    auto tRead = std::chrono::steady_clock::now();
    if (groupStart) footprint = &im.keepPlanes(group, camera, scene.camera.width, scene.camera.height);
    const double planesMs = msSince(tRead);
    frame = im.partialFrame(scene, *light, method, *select, *footprint, pipes, t);
    if (drawPlanes) t.evidenceGpuMs += passes.resolveGpuMs;  // the planes pass (3a)
    if (groupStart) t.readbackMs += planesMs;
  } else {
    auto tRead = std::chrono::steady_clock::now();
    frame = im.readback(scene, light, method, scene.camera.width, scene.camera.height);
    t.readbackMs = msSince(tRead);
    t.evidenceGpuMs = passes.resolveGpuMs;
    t.evidencePixels = frame.pixelCount();
  }
  frame.meta = frameMeta(scene, light, fit, requested, deviceName());
  if (onDemand) frame.meta["evidence_group"] = group;  // CompareContext (compare.h): same hit, ids, m, cascade
  if (t.partialEvidence) {
    frame.meta["evidence"] = "partial";
    frame.meta["evidence_pixels"] = t.evidencePixels;
    if (stencilIds) frame.meta["occluder_prim"] = "unresolved";  // the stencil ids: objects only
  }
  t.shadowGpuMs = passes.shadowGpuMs;
  t.shadowMapsKept = !drawn.shadow;
  t.visibilityGpuMs = im.visibilityGpuMs;
  t.cameraGpuMs = im.visibilityGpuMs + t.evidenceGpuMs;
  t.lookupGpuMs = light ? passes.lookupGpuMs : 0.0;
  t.momentsGpuMs = isMomentFilter(method.filter) ? passes.momentsGpuMs : 0.0;
  t.renderWallMs = msSince(t0);
  return frame;
}

}  // namespace shadowlab
