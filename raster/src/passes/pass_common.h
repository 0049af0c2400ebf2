#pragma once
// What the passes share besides the frame's order (rasterizer.cpp): the device, the one pipeline
// layout (resolve_abi.h's descriptor set and DrawPush), the samplers, the full-screen vertex
// shader, and the small recording helpers every full-screen pass uses.
#include <array>
#include <cstdint>
#include <functional>
#include <thread>

#include <glm/glm.hpp>

#include "shadowlab/raster/resolve_abi.h"
#include "shadowlab/raster/resolve_params.h"
#include "vk/buffer.h"
#include "vk/context.h"
#include "vk/image.h"

namespace shadowlab::raster {

// What every pass records with (the Rasterizer owns them).
struct PassContext {
  const vk::Context* context = nullptr;
  VkPipelineLayout layout = VK_NULL_HANDLE;  // the descriptor set + DrawPush
  VkShaderModule fullscreenVert = VK_NULL_HANDLE;
  VkSampler nearest = VK_NULL_HANDLE, compare = VK_NULL_HANDLE, linear = VK_NULL_HANDLE;
};

// The push constants of every pipeline (one layout for all).
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

// What each binding of resolve_abi.h's table holds: a buffer, an image with its sampler, or a
// texel buffer view (exactly one per binding). Each pass fills its own (bind()).
struct BindingResource {
  const vk::Buffer* buffer = nullptr;
  VkDescriptorImageInfo image{};
  VkBufferView texelView = VK_NULL_HANDLE;
};
#define SHADOWLAB_COUNT_BINDING(name, binding, kind) +1
inline constexpr uint32_t kBindingCount = 0 SHADOWLAB_RESOLVE_BINDINGS(SHADOWLAB_COUNT_BINDING);
#undef SHADOWLAB_COUNT_BINDING
using BindingResources = std::array<BindingResource, kBindingCount>;

inline VkDescriptorImageInfo sampledImage(VkSampler sampler, VkImageView view, VkImageLayout layout) {
  return VkDescriptorImageInfo{sampler, view, layout};
}

inline constexpr VkFormat kIdFormat = VK_FORMAT_R32_UINT;  // global triangle + 1, 0: nothing
inline constexpr VkFormat kCameraDepthFormat = VK_FORMAT_D32_SFLOAT;
// The resolve pass's color attachments (resolve.frag's outA, outB, and outC for filterable maps).
inline constexpr int kResolveAttachments = 3;
inline constexpr VkFormat kResolveFormats[kResolveAttachments] = {
    VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT};
// The attachments a frame of `filter` writes: outC (the moments' evidence) for filterable maps only.
inline int resolveAttachments(Filter filter) { return isMomentFilter(filter) ? 3 : 2; }
// The lookup pass's one attachment: the visibility, 1 byte per pixel.
inline constexpr VkFormat kLookupFormat = VK_FORMAT_R8_UNORM;
// A group's surface (resolve.frag's kSpecSurface, surfaceTexel), the planes pass's second attachment
// and the full resolve's last: with one map layer the visible point's map coordinates (u, v,
// depth) and whether the light reaches it and they lie in the map; with cascades or a point light
// the point itself and whether the light reaches it. Kept per group, as many as the footprints
// (16 bytes per pixel: 33 MB at 1080p each).
inline constexpr VkFormat kSurfaceFormat = VK_FORMAT_R32G32B32A32_SFLOAT;
// How many groups' planes (m, cascade) and surfaces evidence on demand keeps: a sweep whose
// fastest axis is a bias or a filter needs one; a grid with map.size fastest, one per size.
inline constexpr size_t kKeptFootprints = 4;

// A colour attachment that a full-screen pass overwrites entirely (its old contents are not loaded).
VkRenderingAttachmentInfo overwrittenColor(VkImageView view, VkImageLayout layout);
// Makes the writes of `srcStage` (`srcAccess`) visible to the host's reads after the submit.
void barrierToHost(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess);
// A full-screen pass (the moments, the resolve, the lookup): one triangle drawn with `pipeline`
// over width x height into `count` colour attachments; `beforeDraw` (optional) runs after the
// pipeline is bound, e.g. for push constants.
// warmup: a scissor of one pixel (a pipeline's untimed first use, compiling its shaders: submit()).
void drawFullscreen(VkCommandBuffer cmd, const VkRenderingAttachmentInfo* colors, uint32_t count, uint32_t width,
                    uint32_t height, VkPipeline pipeline, const std::function<void()>& beforeDraw = {},
                    bool warmup = false);

// Row y of a host-readable image, as T.
template <class T>
const T* mappedRow(const vk::Image& img, size_t y) {
  return reinterpret_cast<const T*>(static_cast<const char*>(img.mapped()) + y * img.rowPitch());
}

// f(begin, end) over [0, n) in two halves, the second on a helper thread: the frame's CPU copies
// (the halves write disjoint pixels; this machine has 2 cores).
template <class F>
void inTwoHalves(size_t n, const F& f) {
  std::thread helper(f, n / 2, n);
  f(size_t(0), n / 2);
  helper.join();
}

}  // namespace shadowlab::raster
