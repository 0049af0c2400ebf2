#pragma once
// A move-only owner for the many Vulkan objects that are destroyed with
// vkDestroyXxx(device, handle, nullptr): one template instead of a hand-written destroy list.
#include <utility>

#include <vulkan/vulkan.h>

namespace shadowlab::vk {

template <typename T, void (*Destroy)(VkDevice, T, const VkAllocationCallbacks*)>
class DeviceHandle {
 public:
  DeviceHandle() = default;
  DeviceHandle(VkDevice device, T handle) : device_(device), handle_(handle) {}
  ~DeviceHandle() { reset(); }
  DeviceHandle(const DeviceHandle&) = delete;
  DeviceHandle& operator=(const DeviceHandle&) = delete;
  DeviceHandle(DeviceHandle&& other) noexcept
      : device_(other.device_), handle_(std::exchange(other.handle_, VK_NULL_HANDLE)) {}
  DeviceHandle& operator=(DeviceHandle&& other) noexcept {
    if (this != &other) {
      reset();
      device_ = other.device_;
      handle_ = std::exchange(other.handle_, VK_NULL_HANDLE);
    }
    return *this;
  }
  void reset() {
    if (handle_ != VK_NULL_HANDLE) Destroy(device_, handle_, nullptr);
    handle_ = VK_NULL_HANDLE;
  }
  T get() const { return handle_; }
  explicit operator bool() const { return handle_ != VK_NULL_HANDLE; }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  T handle_ = VK_NULL_HANDLE;
};

using Memory = DeviceHandle<VkDeviceMemory, vkFreeMemory>;
using BufferHandle = DeviceHandle<VkBuffer, vkDestroyBuffer>;
using ImageHandle = DeviceHandle<VkImage, vkDestroyImage>;
using ImageView = DeviceHandle<VkImageView, vkDestroyImageView>;
using BufferView = DeviceHandle<VkBufferView, vkDestroyBufferView>;
using Sampler = DeviceHandle<VkSampler, vkDestroySampler>;
using ShaderModule = DeviceHandle<VkShaderModule, vkDestroyShaderModule>;
using PipelineHandle = DeviceHandle<VkPipeline, vkDestroyPipeline>;
using PipelineLayout = DeviceHandle<VkPipelineLayout, vkDestroyPipelineLayout>;
using DescriptorSetLayout = DeviceHandle<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout>;
using DescriptorPool = DeviceHandle<VkDescriptorPool, vkDestroyDescriptorPool>;
using CommandPool = DeviceHandle<VkCommandPool, vkDestroyCommandPool>;
using Fence = DeviceHandle<VkFence, vkDestroyFence>;
using QueryPool = DeviceHandle<VkQueryPool, vkDestroyQueryPool>;

}  // namespace shadowlab::vk
