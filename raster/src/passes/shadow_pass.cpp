#include "passes/shadow_pass.h"

namespace shadowlab::raster {

namespace {
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
}  // namespace

VkFormat vkDepthFormat(DepthFormat f) {
  switch (f) {
    case DepthFormat::D16: return VK_FORMAT_D16_UNORM;
    case DepthFormat::D24: return VK_FORMAT_X8_D24_UNORM_PACK32;
    case DepthFormat::D32F: return VK_FORMAT_D32_SFLOAT;
  }
  return VK_FORMAT_D32_SFLOAT;
}

VkFormat vkDepthStencilFormat(DepthFormat f) {
  switch (f) {
    case DepthFormat::D16: return VK_FORMAT_D16_UNORM_S8_UINT;
    case DepthFormat::D24: return VK_FORMAT_D24_UNORM_S8_UINT;
    case DepthFormat::D32F: return VK_FORMAT_D32_SFLOAT_S8_UINT;
  }
  return VK_FORMAT_D32_SFLOAT_S8_UINT;
}

bool ShadowPass::stencilIdsApply(const vk::Context& context, const SceneGpu& scene, const Method& method) {
  if (scene.objectIds.size() > kMaxStencilObjects) return false;
  auto it = stencilFormatOk_.find(method.mapFormat);
  if (it == stencilFormatOk_.end()) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(context.physical(), vkDepthStencilFormat(method.mapFormat), &fp);
    const VkFormatFeatureFlags need =
        VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
    it = stencilFormatOk_.emplace(method.mapFormat, (fp.optimalTilingFeatures & need) == need).first;
  }
  return it->second;
}

void ShadowPass::ensureImages(const vk::Context& c, int mapSize, VkFormat mapFormat, int layers) {
  if (mapDepth_.width() != mapSize || mapDepth_.format() != mapFormat || mapDepth_.layers() != layers) {
    keptKey.clear();
    mapDepth_ = vk::Image();  // released first: maps of 4096^2 and more
    mapDepth_ = vk::Image(
        c, mapSize, mapSize, layers, mapFormat,
        VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
        isDepthStencil(mapFormat) ? VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT : VK_IMAGE_ASPECT_DEPTH_BIT,
        false, "shadow map depth");
  }
  if (mapIds_.width() != mapSize || mapIds_.layers() != layers) {
    keptKey.clear();
    mapIds_ = vk::Image(c, mapSize, mapSize, layers, kIdFormat,
                        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                        false, "shadow map ids");
  }
}

void ShadowPass::pipelines(const PassContext& pc, bool depthClamp, const std::vector<MapLayer>& layers,
                           IdPipelines& p) {
  const VkFormat mapFormat = mapDepth_.format();
  p.shadowPlain = ids_->pipeline(pc, mapFormat, depthClamp, false, true);
  p.shadowTested = ids_->pipeline(pc, mapFormat, depthClamp, true, true);
  for (const MapLayer& l : layers)
    if (l.lightDepth) {
      p.shadowLightDepthPlain = ids_->pipeline(pc, mapFormat, depthClamp, false, false, true);
      p.shadowLightDepthTested = ids_->pipeline(pc, mapFormat, depthClamp, true, false, true);
    }
}

std::string ShadowPass::key(const SceneGpu& scene, const std::vector<LayerDraw>& layerDraws, const IdPipelines& pipes,
                            const Method& method) const {
  std::string key = scene.hash;
  auto add = [&](const auto& value) { key.append(reinterpret_cast<const char*>(&value), sizeof(value)); };
  add(mapDepth_.get()), add(mapDepth_.format()), add(mapDepth_.width()), add(mapDepth_.layers());
  add(pipes.shadowPlain), add(pipes.shadowTested), add(pipes.shadowLightDepthPlain), add(pipes.shadowLightDepthTested);
  add(method.biasConstant), add(method.biasSlope), add(method.biasClamp), add(method.cull), add(method.mapSize);
  for (const LayerDraw& l : layerDraws) add(l.clip), add(l.lightDepth), add(l.depthRow);
  return key;
}

void ShadowPass::record(VkCommandBuffer cmd, const PassContext& pc, const SceneGpu& scene,
                        const std::vector<LayerDraw>& layerDraws, const IdPipelines& pipes, const Method& method,
                        bool warmup) const {
  // A light-depth layer's fragment shader applies the depth bias itself (the rasterizer's bias
  // does not reach a written depth).
  glm::vec4 shaderBias(method.biasConstant * depthResolution(method.mapFormat), method.biasSlope, method.biasClamp,
                       depthResolution(method.mapFormat) > 0.0f ? 0.0f : 1.0f);
  if (shaderBias.w > 0.5f) shaderBias.x = method.biasConstant;
  // The stencil ids (evidence on demand): the shadow pass writes each draw's object index + 1
  // into the map's stencil where its fragment wins the depth test, the same fragment whose id the
  // id attachment would keep.
  const bool stencilIds = mapDepth_.hasStencil();
  const VkImageLayout mapLayout =
      stencilIds ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  vk::transition(cmd, mapDepth_, VK_IMAGE_LAYOUT_UNDEFINED, mapLayout, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0,
                 VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                 VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
  if (!stencilIds)
    vk::transition(cmd, mapIds_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  for (size_t layer = 0; layer < layerDraws.size(); ++layer) {
    beginIdRendering(cmd, mapDepth_.layerView(int(layer)), stencilIds ? VK_NULL_HANDLE : mapIds_.layerView(int(layer)),
                     method.mapSize, method.mapSize, warmup);
    vkCmdSetDepthBias(cmd, method.biasConstant, method.biasClamp, method.biasSlope);
    const LayerDraw& ld = layerDraws[layer];
    drawScene(cmd, pc, scene, pipes, ld.clip, true, vkCull(method.cull), stencilIds, shaderBias,
              ld.lightDepth ? &ld : nullptr);
    vkCmdEndRendering(cmd);
  }
  vk::transition(cmd, mapDepth_, mapLayout, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                 VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  if (!stencilIds)
    vk::transition(cmd, mapIds_, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
}

void ShadowPass::bind(const PassContext& pc, BindingResources& r) const {
  r[abi::kBindingMapDepth].image =
      sampledImage(pc.nearest, mapDepth_.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  r[abi::kBindingMapShadow].image =
      sampledImage(pc.compare, mapDepth_.arrayView(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  // With the stencil ids the map's stencil aspect (object + 1) stands in for the id attachment.
  r[abi::kBindingMapIds].image =
      sampledImage(pc.nearest, mapDepth_.hasStencil() ? mapDepth_.stencilView() : mapIds_.arrayView(),
                   VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
}

}  // namespace shadowlab::raster
