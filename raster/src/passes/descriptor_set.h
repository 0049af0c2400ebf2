#pragma once
// The one descriptor set every pass binds, its layout and the pipeline layout (the set + DrawPush),
// built from resolve_abi.h's binding table. The passes say what their bindings hold (bind());
// write() writes the whole set.
#include "passes/pass_common.h"
#include "vk/handle.h"

namespace shadowlab::raster {

class DescriptorSet {
 public:
  explicit DescriptorSet(const vk::Context& context);
  VkPipelineLayout pipelineLayout() const { return pipelineLayout_.get(); }
  VkDescriptorSet get() const { return set_; }
  // Every binding of the table from `resources` (a buffer binding without one is a logic error).
  void write(const BindingResources& resources) const;

 private:
  const vk::Context* context_;
  vk::DescriptorSetLayout setLayout_;
  vk::PipelineLayout pipelineLayout_;
  vk::DescriptorPool pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
};

}  // namespace shadowlab::raster
