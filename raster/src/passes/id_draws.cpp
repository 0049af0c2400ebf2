#include "passes/id_draws.h"

#include "id_frag.h"
#include "id_light_depth_frag.h"
#include "id_light_depth_vert.h"
#include "id_plain_frag.h"
#include "id_plain_vert.h"
#include "id_vert.h"
#include "vk/pipeline.h"

namespace shadowlab::raster {

namespace {
bool isDepthStencil(VkFormat f) {
  return f == VK_FORMAT_D16_UNORM_S8_UINT || f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D32_SFLOAT_S8_UINT;
}
}  // namespace

IdDraws::IdDraws(const vk::Context& context) {
  idVert_ = vk::createShaderModule(context, kSpv_id_vert, sizeof(kSpv_id_vert));
  idFrag_ = vk::createShaderModule(context, kSpv_id_frag, sizeof(kSpv_id_frag));
  idPlainVert_ = vk::createShaderModule(context, kSpv_id_plain_vert, sizeof(kSpv_id_plain_vert));
  idPlainFrag_ = vk::createShaderModule(context, kSpv_id_plain_frag, sizeof(kSpv_id_plain_frag));
  idLightDepthVert_ = vk::createShaderModule(context, kSpv_id_light_depth_vert, sizeof(kSpv_id_light_depth_vert));
  idLightDepthFrag_ = vk::createShaderModule(context, kSpv_id_light_depth_frag, sizeof(kSpv_id_light_depth_frag));
}

VkPipeline IdDraws::pipeline(const PassContext& pc, VkFormat format, bool depthClamp, bool materialTests,
                             bool depthBias, bool lightDepth) {
  auto key = std::make_tuple(format, depthClamp, materialTests, depthBias, lightDepth);
  auto it = pipelines_.find(key);
  if (it != pipelines_.end()) return it->second.get();
  vk::GraphicsPipelineDesc d;
  // Without material tests, the plain shaders: no uv varying to set up per triangle.
  d.vertex = lightDepth ? idLightDepthVert_.get() : materialTests ? idVert_.get() : idPlainVert_.get();
  d.fragment = lightDepth ? idLightDepthFrag_.get() : materialTests ? idFrag_.get() : idPlainFrag_.get();
  d.layout = pc.layout;
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
  return pipelines_.emplace(key, vk::createGraphicsPipeline(*pc.context, d)).first->second.get();
}

void drawScene(VkCommandBuffer cmd, const PassContext& pc, const SceneGpu& s, const IdPipelines& pipes,
               const glm::mat4& clip, bool shadowPass, VkCullModeFlags shadowCull, bool stencilIds,
               const glm::vec4& shaderBias, const LayerDraw* lightDepth) {
  VkPipeline bound = VK_NULL_HANDLE;
  for (int tested = 0; tested < 2; ++tested)
    for (const Draw& d : s.draws) {
      if (shadowPass && !d.castsShadow) continue;
      VkCullModeFlags cull = shadowPass ? shadowCull : VkCullModeFlags(VK_CULL_MODE_NONE);
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
      vkCmdPushConstants(cmd, pc.layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(push),
                         &push);
      vkCmdDrawIndexed(cmd, d.indexCount, 1, d.firstIndex, d.vertexOffset, 0);
    }
}

void beginIdRendering(VkCommandBuffer cmd, VkImageView depthView, VkImageView idView, int w, int h, bool warmup,
                      VkImageLayout idLayout) {
  VkRenderingAttachmentInfo color{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  color.imageView = idView;
  color.imageLayout = idLayout;
  color.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  color.clearValue.color.uint32[0] = 0;  // id 0: nothing drawn here
  VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  depth.imageView = depthView;
  // Without an id attachment the map holds the stencil ids: both aspects are attached.
  depth.imageLayout =
      idView ? VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
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
  VkRect2D scissor{{0, 0}, {warmup ? 1u : uint32_t(w), warmup ? 1u : uint32_t(h)}};
  vkCmdSetViewport(cmd, 0, 1, &viewport);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
}

}  // namespace shadowlab::raster
