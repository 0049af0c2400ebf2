#pragma once
// Pipeline construction for dynamic rendering (no render passes). Everything a sweep varies at
// draw time (depth bias, cull mode, viewport) is dynamic state; what needs a new pipeline is
// named in the descriptions below and is the rasterizer's pipeline-cache key.
#include <cstdint>
#include <vector>

#include "vk/context.h"
#include "vk/handle.h"

namespace shadowlab::vk {

ShaderModule createShaderModule(const Context& context, const uint32_t* code, size_t bytes);

struct GraphicsPipelineDesc {
  VkShaderModule vertex = VK_NULL_HANDLE;
  VkShaderModule fragment = VK_NULL_HANDLE;  // none: a depth-only pipeline
  VkPipelineLayout layout = VK_NULL_HANDLE;
  std::vector<VkVertexInputBindingDescription> bindings;
  std::vector<VkVertexInputAttributeDescription> attributes;
  std::vector<VkFormat> colorFormats;
  VkFormat depthFormat = VK_FORMAT_UNDEFINED;
  VkFrontFace frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  bool depthClamp = false;  // keeps casters outside [near, far] in the map (directional lights)
  bool depthBias = false;   // depth bias values come from vkCmdSetDepthBias
  bool depthTest = true;    // less-than test and write (false: no depth attachment)
  // stencil: every fragment that passes the depth test writes the dynamic stencil reference
  // (vkCmdSetStencilReference) into the attachment's stencil aspect.
  VkFormat stencilFormat = VK_FORMAT_UNDEFINED;
  std::vector<uint32_t> fragmentSpecialization;  // 32-bit constants 0..n-1 of the fragment shader
};

PipelineHandle createGraphicsPipeline(const Context& context, const GraphicsPipelineDesc& desc);

}  // namespace shadowlab::vk
