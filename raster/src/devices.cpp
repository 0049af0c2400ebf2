// listRasterDevices: the same enumeration vk::Context does when it picks a device, without
// creating one, so listing works even where a device lacks what shadowlab needs.
#include "shadowlab/raster/devices.h"

#include <vulkan/vulkan.h>

#include <cstring>

#include "shadowlab/scenes/error.h"
#include "vk/check.h"

namespace shadowlab {

namespace {

std::string typeName(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

std::string versionText(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
         std::to_string(VK_API_VERSION_PATCH(v));
}

}  // namespace

std::vector<RasterDeviceInfo> listRasterDevices() {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "shadowlab";
  app.apiVersion = VK_API_VERSION_1_3;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult created = vkCreateInstance(&info, nullptr, &instance);
  if (created != VK_SUCCESS)
    throw DriverError(std::string("no Vulkan driver answered (vkCreateInstance: ") + vk::resultName(created) +
                      "); expected an installed ICD (mesa-vulkan-drivers for lavapipe) or VK_DRIVER_FILES naming a "
                      "driver's JSON, e.g. /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json");
  std::vector<RasterDeviceInfo> out;
  try {
    uint32_t count = 0;
    VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, nullptr));
    std::vector<VkPhysicalDevice> devices(count);
    VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, devices.data()));
    vk::keepLoadedLibrariesMapped();  // the drivers' init blocks stay reachable after vkDestroyInstance
    for (VkPhysicalDevice d : devices) {
      VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
      VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
      VkPhysicalDeviceProperties& p = props.properties;
      vkGetPhysicalDeviceProperties(d, &p);
      if (p.apiVersion >= VK_API_VERSION_1_2) {  // VkPhysicalDeviceDriverProperties is core in 1.2
        props.pNext = &driver;
        vkGetPhysicalDeviceProperties2(d, &props);
      }
      RasterDeviceInfo r;
      r.name = p.deviceName;
      r.type = typeName(p.deviceType);
      r.driver = driver.driverName;
      r.driverInfo = driver.driverInfo;
      r.apiVersion = versionText(p.apiVersion);
      r.vulkan13 = p.apiVersion >= VK_API_VERSION_1_3;
      out.push_back(r);
    }
  } catch (...) {
    vkDestroyInstance(instance, nullptr);
    throw;
  }
  vkDestroyInstance(instance, nullptr);
  // vk::Context's rule for an empty --device: the first whose name holds "llvmpipe", else the first.
  bool picked = false;
  for (auto& r : out)
    if (!picked && r.name.find("llvmpipe") != std::string::npos) picked = r.isDefault = true;
  if (!picked && !out.empty()) out.front().isDefault = true;
  return out;
}

}  // namespace shadowlab
