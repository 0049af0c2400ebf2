#include "passes/pass_common.h"

namespace shadowlab::raster {

VkRenderingAttachmentInfo overwrittenColor(VkImageView view, VkImageLayout layout) {
  VkRenderingAttachmentInfo color{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  color.imageView = view;
  color.imageLayout = layout;
  color.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;  // every pixel is written
  color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  return color;
}

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

void drawFullscreen(VkCommandBuffer cmd, const VkRenderingAttachmentInfo* colors, uint32_t count, uint32_t width,
                    uint32_t height, VkPipeline pipeline, const std::function<void()>& beforeDraw, bool warmup) {
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

}  // namespace shadowlab::raster
