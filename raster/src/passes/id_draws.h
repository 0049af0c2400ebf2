#pragma once
// The scene drawn into an id target: what the shadow pass (pass 1, from the light) and the
// visibility pass (pass 2, from the camera) share. id.vert/.frag (material tests), the plain
// shaders without the uv varying, id_light_depth.vert/.frag (fit=tsm's light-depth layers).
#include <map>
#include <tuple>

#include "passes/pass_common.h"
#include "scene_gpu.h"
#include "vk/handle.h"

namespace shadowlab::raster {

// The id-writing pipelines of one frame: the plain writer and the one with material tests
// (alpha cutoff, one-sided back faces), for the shadow pass and for the camera pass.
struct IdPipelines {
  VkPipeline shadowPlain = VK_NULL_HANDLE, shadowTested = VK_NULL_HANDLE;
  VkPipeline cameraPlain = VK_NULL_HANDLE, cameraTested = VK_NULL_HANDLE;
  // Light-depth layers (fit=tsm): the same two, with id_light_depth.vert/.frag.
  VkPipeline shadowLightDepthPlain = VK_NULL_HANDLE, shadowLightDepthTested = VK_NULL_HANDLE;
};

class IdDraws {
 public:
  explicit IdDraws(const vk::Context& context);
  // Keyed by what needs a new pipeline: (depth format, depth clamp, material tests, depth bias,
  // light depth); a depth+stencil format: the stencil ids, no id attachment.
  VkPipeline pipeline(const PassContext& pc, VkFormat format, bool depthClamp, bool materialTests, bool depthBias,
                      bool lightDepth = false);

 private:
  vk::ShaderModule idVert_, idFrag_, idPlainVert_, idPlainFrag_, idLightDepthVert_, idLightDepthFrag_;
  std::map<std::tuple<VkFormat, bool, bool, bool, bool>, vk::PipelineHandle> pipelines_;
};

// Every draw of the scene with `clip`: plain draws first, then those that need the material tests
// (discard turns early depth testing off, so only the draws that need it pay for it).
// shadowPass: the casters only, culled with `shadowCull`, each draw's object index + 1 into the
// stencil where `stencilIds`; a light-depth layer (`lightDepth`) draws with its own pipelines and
// `shaderBias` in the push constants (its fragment shader writes the depth, which replaces the
// rasterizer's bias).
void drawScene(VkCommandBuffer cmd, const PassContext& pc, const SceneGpu& scene, const IdPipelines& pipes,
               const glm::mat4& clip, bool shadowPass, VkCullModeFlags shadowCull, bool stencilIds,
               const glm::vec4& shaderBias = glm::vec4(0.0f), const LayerDraw* lightDepth = nullptr);

// Begins rendering depth (cleared to the far plane, stencil 0) and ids (cleared to 0) of w x h.
// idView VK_NULL_HANDLE: no id attachment (the stencil ids: depthView holds both aspects).
// warmup: a scissor of one pixel.
void beginIdRendering(VkCommandBuffer cmd, VkImageView depthView, VkImageView idView, int w, int h, bool warmup,
                      VkImageLayout idLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);

}  // namespace shadowlab::raster
