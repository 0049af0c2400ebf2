#include "passes/visibility_pass.h"

#include "shadowlab/scenes/io.h"

namespace shadowlab::raster {

void VisibilityPass::ensureImages(const vk::Context& c, int width, int height) {
  if (cameraIds_.width() == width && cameraIds_.height() == height) return;
  cameraDepth_ = vk::Image(c, width, height, 1, kCameraDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
                           VK_IMAGE_ASPECT_DEPTH_BIT, false, "camera depth");
  keptKey.clear();
  cameraIds_ =
      vk::Image(c, width, height, 1, kIdFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                VK_IMAGE_ASPECT_COLOR_BIT, true, "camera ids");
}

void VisibilityPass::pipelines(const PassContext& pc, IdPipelines& p) {
  p.cameraPlain = ids_->pipeline(pc, kCameraDepthFormat, false, false, false);
  p.cameraTested = ids_->pipeline(pc, kCameraDepthFormat, false, true, false);
}

std::string VisibilityPass::cameraKey(const SceneGpu& scene, const Camera& camera) {
  glm::mat4 cameraClip = camera.clipFromView() * camera.viewFromWorld();
  return scene.hash + "/" + hashHex(fnv1a64(&cameraClip, sizeof(cameraClip))) + "/" + std::to_string(camera.width) +
         "x" + std::to_string(camera.height);
}

void VisibilityPass::record(VkCommandBuffer cmd, const PassContext& pc, const SceneGpu& scene, const IdPipelines& pipes,
                            const glm::mat4& cameraClip, int width, int height, bool draw, bool warmup) const {
  if (draw) {
    vk::transition(cmd, cameraDepth_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                   VK_PIPELINE_STAGE_2_NONE, 0,
                   VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                   VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
    // GENERAL throughout: the camera ids are an attachment, then sampled, then read by the host.
    vk::transition(cmd, cameraIds_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_HOST_BIT, 0,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    beginIdRendering(cmd, cameraDepth_.layerView(0), cameraIds_.layerView(0), width, height, warmup,
                     VK_IMAGE_LAYOUT_GENERAL);
    drawScene(cmd, pc, scene, pipes, cameraClip, false, VK_CULL_MODE_NONE, false);
    vkCmdEndRendering(cmd);
  }
  vk::transition(cmd, cameraIds_, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
                 VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
}

void VisibilityPass::bind(const PassContext& pc, BindingResources& r) const {
  r[abi::kBindingCameraIds].image = sampledImage(pc.nearest, cameraIds_.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
}

void VisibilityPass::cameraRow(const SceneGpu& scene, int y, float* hit, float* objectId, float* primId) const {
  const uint32_t* ids = mappedRow<uint32_t>(cameraIds_, size_t(y));
  for (int x = 0; x < cameraIds_.width(); ++x) {
    hit[x] = ids[x] ? 1.0f : 0.0f;
    idsOf(scene, ids[x], objectId[x], primId[x]);
  }
}

}  // namespace shadowlab::raster
