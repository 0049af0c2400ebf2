#pragma once
// The Vulkan devices this machine offers (what `--device NAME` picks among), for
// `shadowlab devices` and scripts/gpu-check.sh. No Vulkan header leaks through this interface.
#include <string>
#include <vector>

namespace shadowlab {

struct RasterDeviceInfo {
  std::string name;        // VkPhysicalDeviceProperties::deviceName ("NVIDIA H100 80GB HBM3", "llvmpipe (LLVM ...)")
  std::string type;        // "discrete", "integrated", "virtual", "cpu" or "other"
  std::string driver;      // driver name ("NVIDIA", "llvmpipe"); empty when the driver does not say
  std::string driverInfo;  // driver version text as the driver reports it
  std::string apiVersion;  // highest Vulkan version the device supports, "1.3.246"
  bool vulkan13 = false;   // shadowlab needs Vulkan 1.3
  bool isDefault = false;  // the one an empty --device picks (llvmpipe when present, else the first)
};

// Creates a bare Vulkan instance and lists its physical devices in the loader's order. Throws
// DriverError when no Vulkan loader or driver answers (the message names VK_DRIVER_FILES).
std::vector<RasterDeviceInfo> listRasterDevices();

}  // namespace shadowlab
