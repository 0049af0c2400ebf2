#pragma once
// The instance, the chosen physical device and one logical device with one queue that does
// graphics and compute. Move-only; owns everything it creates.
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "vk/handle.h"

namespace shadowlab::vk {

struct ContextOptions {
  std::string device;       // substring of the device name; empty: llvmpipe if present, else first
  bool validation = false;  // VK_LAYER_KHRONOS_validation + a counting debug messenger
};

class Context {
 public:
  explicit Context(const ContextOptions& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  Context(Context&&) = delete;  // held by unique_ptr: the messenger keeps a pointer to the counter
  Context& operator=(Context&&) = delete;

  VkDevice device() const { return device_; }
  VkPhysicalDevice physical() const { return physical_; }
  VkQueue queue() const { return queue_; }
  uint32_t queueFamily() const { return queueFamily_; }
  VkCommandPool commandPool() const { return commandPool_.get(); }
  const VkPhysicalDeviceProperties& properties() const { return properties_; }
  std::string deviceName() const;  // "llvmpipe (LLVM 15.0.6, 256 bits) / llvmpipe"-style: device / driver
  int validationMessages() const { return validationMessages_->load(); }
  bool validationEnabled() const { return messenger_ != VK_NULL_HANDLE; }

  // First memory type allowed by `typeBits` having all of `required` (and preferring `preferred`).
  uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred = 0) const;
  // The one place memory is allocated: `requirements.size` bytes of memoryType(...)'s type;
  // `typeIndex` (optional) receives the type chosen. `what` names it in an out-of-memory error
  // (check.h's VK_CHECK_ALLOC).
  Memory allocate(const VkMemoryRequirements& requirements, VkMemoryPropertyFlags required,
                  VkMemoryPropertyFlags preferred = 0, uint32_t* typeIndex = nullptr,
                  const std::string& what = "memory") const;
  const VkPhysicalDeviceMemoryProperties& memoryProperties() const { return memory_; }
  // maxMemoryAllocationSize (VkPhysicalDeviceVulkan11Properties): the largest single allocation.
  VkDeviceSize maxAllocationBytes() const { return maxAllocationBytes_; }
  bool hostVisible(uint32_t memoryType) const {
    return memory_.memoryTypes[memoryType].propertyFlags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
  }
  bool hostCoherent(uint32_t memoryType) const {
    return memory_.memoryTypes[memoryType].propertyFlags & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  }
  // Makes device writes to mapped, non-coherent `memory` visible to the host (whole allocation).
  void invalidate(VkDeviceMemory memory) const;
  // On a CPU device (lavapipe), device memory is host RAM: asks for transparent huge pages for a
  // large mapped allocation (`mapped`, `size` bytes) before its first use. Elsewhere a no-op.
  void adviseHugePages(void* mapped, VkDeviceSize size) const;
  // Set when a submission did not finish in time: the owner must then not wait for the device
  // (vkDeviceWaitIdle has no timeout) before it destroys what the device may still use.
  void markHung() const;
  bool hung() const { return hung_; }

 private:
  void release();  // also used when the constructor fails half way

  mutable bool hung_ = false;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  CommandPool commandPool_;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  VkDeviceSize maxAllocationBytes_ = 0;
  std::string driverName_;
  std::unique_ptr<std::atomic<int>> validationMessages_ = std::make_unique<std::atomic<int>>(0);
};

}  // namespace shadowlab::vk
