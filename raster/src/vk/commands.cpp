#include "vk/commands.h"

#include <cstdint>
#include <cstdio>
#include <string>

#include "shadowlab/scenes/error.h"
#include "vk/check.h"

namespace shadowlab::vk {

namespace {
std::string seconds(uint64_t ns) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", double(ns) * 1e-9);
  return buf;
}
}  // namespace

Commands::Commands(const Context& context, uint64_t timeoutNs) : context_(context), timeoutNs_(timeoutNs) {
  VkCommandBufferAllocateInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  info.commandPool = context.commandPool();
  info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  info.commandBufferCount = 1;
  VK_CHECK(vkAllocateCommandBuffers(context.device(), &info, &cmd_));
  VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence;
  VK_CHECK(vkCreateFence(context.device(), &fenceInfo, nullptr, &fence));
  fence_ = Fence(context.device(), fence);
}

Commands::~Commands() {
  if (cmd_) vkFreeCommandBuffers(context_.device(), context_.commandPool(), 1, &cmd_);
}

VkCommandBuffer Commands::begin() {
  VK_CHECK(vkResetCommandBuffer(cmd_, 0));
  VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_CHECK(vkBeginCommandBuffer(cmd_, &info));
  return cmd_;
}

void Commands::submitAndWait() {
  VK_CHECK(vkEndCommandBuffer(cmd_));
  VkFence fence = fence_.get();
  VK_CHECK(vkResetFences(context_.device(), 1, &fence));
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd_;
  VK_CHECK(vkQueueSubmit(context_.queue(), 1, &submit, fence));
  // Bounded: a hung or lost GPU must end as a driver error (exit 3), never as a process that
  // waits forever. The largest jobs the limits allow take seconds on lavapipe.
  const VkResult waited = injectedFailure("vkWaitForFences")
                              ? VK_ERROR_DEVICE_LOST
                              : vkWaitForFences(context_.device(), 1, &fence, VK_TRUE, timeoutNs_);
  if (waited == VK_TIMEOUT) {
    context_.markHung();  // nothing may wait on this device again (see Context::hung)
    throw DriverError("vkWaitForFences: error: the device did not finish the submitted passes within " +
                      seconds(timeoutNs_) +
                      " s (--gpu-timeout-s); expected a working device and shaders that return (a hung or lost "
                      "GPU, a technique file that never returns?)");
  }
  if (waited != VK_SUCCESS) throwVkError("vkWaitForFences(...)", waited, __FILE__, __LINE__);
}

}  // namespace shadowlab::vk
