#pragma once
// Whether a render's images fit on the device, decided before any of them is allocated, without
// Vulkan types: the rasterizer reads DeviceMemoryLimits from the device (Rasterizer::memoryLimits)
// and lists the images a request needs with the device's own sizes (vkGetDeviceImageMemoryRequirements);
// checkDeviceMemory refuses the request with an InputError (exit 2) naming the image that does not
// fit, its size and the limit, so a map too large for the device is the user's size to lower, not
// a driver failure half way through a render.
//
// Measured on lavapipe (Mesa 22.3, this machine's 23 GiB of RAM): one heap of 2 GiB and a
// maxMemoryAllocationSize of 2 GiB. The allocation limit is real there (binding a 3 GiB image,
// 16384^2 x 3 layers x 4 B, fails with VK_ERROR_OUT_OF_DEVICE_MEMORY); the heap is not (three
// 1.5 GiB allocations succeed): a CPU device's memory is the machine's RAM, which the CLI's
// --max-memory estimate (app/job_limits.h) already covers. So the heap is checked on GPUs only.
#include <cstdint>
#include <string>
#include <vector>

namespace shadowlab {

struct DeviceMemoryLimits {
  std::string deviceName;
  bool cpuDevice = false;             // VK_PHYSICAL_DEVICE_TYPE_CPU (lavapipe): its heap is host RAM
  uint64_t deviceLocalHeapBytes = 0;  // the largest heap with VK_MEMORY_HEAP_DEVICE_LOCAL_BIT
  uint64_t maxAllocationBytes = 0;    // maxMemoryAllocationSize (Vulkan 1.1): the largest one image
  uint32_t maxImageDimension2D = 0;
  uint32_t maxImageArrayLayers = 0;
};

// One image a render allocates, as the device sizes it.
struct DeviceImage {
  std::string what;    // "shadow map depth", "camera targets", ...
  std::string origin;  // where its size comes from, for the error: "method" or the scene's path
  std::string place;   // the key or JSON pointer that sets it: "map.size", "/camera"
  int width = 0, height = 0, layers = 1;
  uint64_t bytes = 0;  // the device's memory requirement

  // "shadow map depth 16384^2 x 3 layers x 4 B = 3.00 GiB"
  std::string describe() const;
};

// "3.00 GiB" (two decimals; MiB, KiB below: "512.00 MiB"; bytes below 1 KiB: "40 B").
std::string formatBytes(double bytes);

// Throws InputError for the first image above the device's largest allocation, with more layers
// than it allows, or larger than its largest 2D image, and (devices other than a CPU) for images
// whose sum is above the device-local heap. The message names the image, its size, the limit and
// the largest map.size that would fit.
void checkDeviceMemory(const std::vector<DeviceImage>& images, const DeviceMemoryLimits& limits);

}  // namespace shadowlab
