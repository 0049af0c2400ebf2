#include "passes/descriptor_set.h"

#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "vk/check.h"

namespace shadowlab::raster {

namespace {

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
static_assert(std::size(kBindings) == kBindingCount, "one resource per binding");
// Every binding is read by the fragment shaders (id.frag: 0..2, resolve.frag: all).
constexpr VkShaderStageFlags kBindingStages = VK_SHADER_STAGE_FRAGMENT_BIT;

}  // namespace

DescriptorSet::DescriptorSet(const vk::Context& context) : context_(&context) {
  VkDevice device = context.device();
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
  setLayout_ = vk::DescriptorSetLayout(device, layout);

  VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(DrawPush)};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &layout;
  pl.pushConstantRangeCount = 1;
  pl.pPushConstantRanges = &push;
  VkPipelineLayout pipeLayout;
  VK_CHECK(vkCreatePipelineLayout(device, &pl, nullptr, &pipeLayout));
  pipelineLayout_ = vk::PipelineLayout(device, pipeLayout);

  std::vector<VkDescriptorPoolSize> sizes;
  for (const auto& [type, count] : typeCounts) sizes.push_back({type, count});
  VkDescriptorPoolCreateInfo dp{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dp.maxSets = 1;
  dp.poolSizeCount = uint32_t(sizes.size());
  dp.pPoolSizes = sizes.data();
  VkDescriptorPool pool;
  VK_CHECK(vkCreateDescriptorPool(device, &dp, nullptr, &pool));
  pool_ = vk::DescriptorPool(device, pool);
  VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  alloc.descriptorPool = pool;
  alloc.descriptorSetCount = 1;
  alloc.pSetLayouts = &layout;
  VK_CHECK(vkAllocateDescriptorSets(device, &alloc, &set_));
}

void DescriptorSet::write(const BindingResources& resources) const {
  VkDescriptorBufferInfo bufferInfos[kBindingCount]{};
  std::vector<VkWriteDescriptorSet> writes;
  for (const BindingRow& row : kBindings) {
    const BindingResource& r = resources[row.binding];
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set_;
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
  vkUpdateDescriptorSets(context_->device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
}

}  // namespace shadowlab::raster
