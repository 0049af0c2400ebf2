#pragma once
// VK_CHECK is always on (never an assert): a failing call throws DriverError carrying the
// expression, the VkResult name and file:line, so a driver failure reaches the CLI as exit 3.
#include <string>

#include <vulkan/vulkan.h>

namespace shadowlab::vk {

const char* resultName(VkResult result);
[[noreturn]] void throwVkError(const char* expression, VkResult result, const char* file, int line);

}  // namespace shadowlab::vk

#define VK_CHECK(expr)                                                              \
  do {                                                                              \
    VkResult vkCheckResult_ = (expr);                                               \
    if (vkCheckResult_ != VK_SUCCESS)                                               \
      ::shadowlab::vk::throwVkError(#expr, vkCheckResult_, __FILE__, __LINE__);     \
  } while (0)
