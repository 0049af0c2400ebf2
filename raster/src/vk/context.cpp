#include "vk/context.h"

#include "shadowlab/raster/raster.h"

#include <dlfcn.h>
#include <link.h>
#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <cstring>

#include "shadowlab/scenes/error.h"
#include "vk/check.h"

namespace shadowlab::vk {

#if defined(__SANITIZE_ADDRESS__)
// AddressSanitizer builds only (scripts/sanitize.sh). The Vulkan loader dlopens the driver (Mesa's
// lavapipe, with LLVM) in vkCreateInstance and dlcloses it in vkDestroyInstance. The blocks that
// the driver keeps for its whole life are then referenced only from its unmapped globals, so
// LeakSanitizer reports them at exit as leaks from "<unknown module>", which no suppression can
// name. Marking every library loaded by now RTLD_NODELETE keeps the driver mapped: its blocks stay
// reachable and a real leak in it is reported under the library's name.
void keepLoadedLibrariesMapped() {
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void*) {
        if (info->dlpi_name && info->dlpi_name[0]) dlopen(info->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
        return 0;
      },
      nullptr);
}
#else
void keepLoadedLibrariesMapped() {}
#endif

const char* resultName(VkResult r) {
  switch (r) {
#define SHADOWLAB_RESULT(x) \
  case x: return #x;
    SHADOWLAB_RESULT(VK_SUCCESS)
    SHADOWLAB_RESULT(VK_NOT_READY)
    SHADOWLAB_RESULT(VK_TIMEOUT)
    SHADOWLAB_RESULT(VK_INCOMPLETE)
    SHADOWLAB_RESULT(VK_ERROR_OUT_OF_HOST_MEMORY)
    SHADOWLAB_RESULT(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    SHADOWLAB_RESULT(VK_ERROR_INITIALIZATION_FAILED)
    SHADOWLAB_RESULT(VK_ERROR_DEVICE_LOST)
    SHADOWLAB_RESULT(VK_ERROR_MEMORY_MAP_FAILED)
    SHADOWLAB_RESULT(VK_ERROR_LAYER_NOT_PRESENT)
    SHADOWLAB_RESULT(VK_ERROR_EXTENSION_NOT_PRESENT)
    SHADOWLAB_RESULT(VK_ERROR_FEATURE_NOT_PRESENT)
    SHADOWLAB_RESULT(VK_ERROR_INCOMPATIBLE_DRIVER)
    SHADOWLAB_RESULT(VK_ERROR_TOO_MANY_OBJECTS)
    SHADOWLAB_RESULT(VK_ERROR_FORMAT_NOT_SUPPORTED)
    SHADOWLAB_RESULT(VK_ERROR_FRAGMENTED_POOL)
    SHADOWLAB_RESULT(VK_ERROR_OUT_OF_POOL_MEMORY)
    SHADOWLAB_RESULT(VK_ERROR_UNKNOWN)
#undef SHADOWLAB_RESULT
    default: return "VK_RESULT_UNKNOWN_CODE";
  }
}

VkResult injectedResult(const char* expression) {
  struct Injection {
    std::string text;
    VkResult result = VK_ERROR_DEVICE_LOST;
  };
  static const Injection injection = [] {
    Injection in;
    const char* v = std::getenv("SHADOWLAB_VK_FAIL");
    if (!v || !*v) return in;
    in.text = v;
    const size_t eq = in.text.find('=');
    if (eq != std::string::npos) {
      const std::string result = in.text.substr(eq + 1);
      in.text.resize(eq);
      for (VkResult r : {VK_ERROR_OUT_OF_HOST_MEMORY, VK_ERROR_OUT_OF_DEVICE_MEMORY, VK_ERROR_DEVICE_LOST})
        if (result == resultName(r)) in.result = r;
    }
    return in;
  }();
  return !injection.text.empty() && std::strstr(expression, injection.text.c_str()) ? injection.result : VK_SUCCESS;
}

void throwVkError(const char* expression, VkResult result, const char* file, int line) {
  throw DriverError(std::string(file) + ":" + std::to_string(line) + ": error: " + expression + " returned " +
                    resultName(result) + " (" + std::to_string(int(result)) + ")");
}

void throwAllocationError(const char* expression, VkResult result, const std::string& what, const std::string& device,
                          const char* file, int line) {
  if (result != VK_ERROR_OUT_OF_DEVICE_MEMORY && result != VK_ERROR_OUT_OF_HOST_MEMORY)
    throwVkError(expression, result, file, line);
  std::string call = expression;
  call.resize(call.find('('));
  throw DriverError("device " + device + " could not allocate " + what + " (" + resultName(result) + " at " + call +
                    "); lower map.size, cascades.count or the camera's size");
}

namespace {

VKAPI_ATTR VkBool32 VKAPI_CALL onValidationMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  if (severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)) {
    static_cast<std::atomic<int>*>(user)->fetch_add(1);
    // Tests require zero messages; printing them is what makes a failure actionable.
    std::fprintf(stderr, "shadowlab: vulkan validation: %s\n", data->pMessage);
  }
  return VK_FALSE;
}

bool hasLayer(const char* name) {
  uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  for (auto& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

}  // namespace

Context::Context(const ContextOptions& options) {
  const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";
  bool validation = options.validation && hasLayer(kValidationLayer);

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "shadowlab";
  app.apiVersion = VK_API_VERSION_1_3;
  std::vector<const char*> layers, extensions;
  if (validation) {
    layers.push_back(kValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  VkDebugUtilsMessengerCreateInfoEXT messengerInfo{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  messengerInfo.messageSeverity =
      VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                              VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  messengerInfo.pfnUserCallback = onValidationMessage;
  messengerInfo.pUserData = validationMessages_.get();

  VkInstanceCreateInfo instanceInfo{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  instanceInfo.pApplicationInfo = &app;
  instanceInfo.enabledLayerCount = uint32_t(layers.size());
  instanceInfo.ppEnabledLayerNames = layers.data();
  instanceInfo.enabledExtensionCount = uint32_t(extensions.size());
  instanceInfo.ppEnabledExtensionNames = extensions.data();
  if (validation) instanceInfo.pNext = &messengerInfo;  // also reports instance creation itself
  VK_CHECK(vkCreateInstance(&instanceInfo, nullptr, &instance_));
  keepLoadedLibrariesMapped();

  try {
    if (validation) {
      auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
      if (!create) throw DriverError("vkCreateDebugUtilsMessengerEXT is not available");
      VK_CHECK(create(instance_, &messengerInfo, nullptr, &messenger_));
    }

    uint32_t count = 0;
    VK_CHECK(vkEnumeratePhysicalDevices(instance_, &count, nullptr));
    std::vector<VkPhysicalDevice> devices(count);
    VK_CHECK(vkEnumeratePhysicalDevices(instance_, &count, devices.data()));
    if (devices.empty()) throw DriverError("no Vulkan device found (is mesa-vulkan-drivers installed?)");
    std::string wanted = options.device.empty() ? "llvmpipe" : options.device;
    std::string names;
    for (VkPhysicalDevice d : devices) {
      VkPhysicalDeviceProperties p;
      vkGetPhysicalDeviceProperties(d, &p);
      names += std::string(names.empty() ? "" : ", ") + p.deviceName;
      if (!physical_ && std::strstr(p.deviceName, wanted.c_str())) physical_ = d;
    }
    if (!physical_) {
      if (!options.device.empty())
        throw InputError("shadowlab: error: no Vulkan device matches \"" + options.device +
                         "\"; expected a substring of one of: " + names);
      physical_ = devices[0];
    }
    vkGetPhysicalDeviceProperties(physical_, &properties_);
    vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
    if (properties_.apiVersion < VK_API_VERSION_1_3)
      throw DriverError(std::string("device ") + properties_.deviceName + " does not support Vulkan 1.3");

    VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    VkPhysicalDeviceVulkan11Properties properties11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_PROPERTIES};
    driver.pNext = &properties11;
    VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props2.pNext = &driver;
    vkGetPhysicalDeviceProperties2(physical_, &props2);
    driverName_ = driver.driverName;
    maxAllocationBytes_ = properties11.maxMemoryAllocationSize;

    uint32_t familyCount = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &familyCount, nullptr);
    std::vector<VkQueueFamilyProperties> families(familyCount);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &familyCount, families.data());
    bool found = false;
    for (uint32_t i = 0; i < familyCount && !found; ++i) {
      VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
      if ((families[i].queueFlags & need) == need && families[i].timestampValidBits > 0) {
        queueFamily_ = i;
        found = true;
      }
    }
    if (!found) throw DriverError("no queue family with graphics, compute and timestamps");

    VkPhysicalDeviceVulkan13Features supported13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceFeatures2 supported{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    supported.pNext = &supported13;
    vkGetPhysicalDeviceFeatures2(physical_, &supported);
    const VkPhysicalDeviceFeatures& f = supported.features;
    if (!f.depthBiasClamp || !f.depthClamp || !f.geometryShader || !f.fragmentStoresAndAtomics ||
        !supported13.dynamicRendering || !supported13.synchronization2 || !supported13.maintenance4)
      throw DriverError(std::string("device ") + properties_.deviceName +
                        " lacks one of the features shadowlab needs: depthBiasClamp, depthClamp, "
                        "geometryShader, fragmentStoresAndAtomics, dynamicRendering, synchronization2, maintenance4");
    VkPhysicalDeviceVulkan13Features features13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    features13.dynamicRendering = VK_TRUE;
    features13.synchronization2 = VK_TRUE;
    features13.maintenance4 = VK_TRUE;  // glslang's SPIR-V 1.6 declares the workgroup size by LocalSizeId
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    features.pNext = &features13;
    features.features.depthBiasClamp = VK_TRUE;            // a nonzero bias.clamp is illegal without it
    features.features.depthClamp = VK_TRUE;                // directional maps keep casters behind the near plane
    features.features.geometryShader = VK_TRUE;            // gl_PrimitiveID in a fragment shader requires it
    features.features.fragmentStoresAndAtomics = VK_TRUE;  // the resolve pass writes a storage buffer

    float priority = 1.0f;
    VkDeviceQueueCreateInfo queueInfo{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queueInfo.queueFamilyIndex = queueFamily_;
    queueInfo.queueCount = 1;
    queueInfo.pQueuePriorities = &priority;
    VkDeviceCreateInfo deviceInfo{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    deviceInfo.pNext = &features;
    deviceInfo.queueCreateInfoCount = 1;
    deviceInfo.pQueueCreateInfos = &queueInfo;
    VK_CHECK(vkCreateDevice(physical_, &deviceInfo, nullptr, &device_));
    vkGetDeviceQueue(device_, queueFamily_, 0, &queue_);

    VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    poolInfo.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    poolInfo.queueFamilyIndex = queueFamily_;
    VkCommandPool pool;
    VK_CHECK(vkCreateCommandPool(device_, &poolInfo, nullptr, &pool));
    commandPool_ = CommandPool(device_, pool);
  } catch (...) {
    release();
    throw;
  }
}

Context::~Context() { release(); }

void Context::release() {
  commandPool_.reset();
  if (device_) vkDestroyDevice(device_, nullptr);
  device_ = VK_NULL_HANDLE;
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
  }
  messenger_ = VK_NULL_HANDLE;
  if (instance_) vkDestroyInstance(instance_, nullptr);
  instance_ = VK_NULL_HANDLE;
}

std::string Context::deviceName() const {
  return std::string(properties_.deviceName) + (driverName_.empty() ? "" : " (" + driverName_ + ")");
}

void Context::invalidate(VkDeviceMemory memory) const {
  VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
  range.memory = memory;
  range.size = VK_WHOLE_SIZE;
  VK_CHECK(vkInvalidateMappedMemoryRanges(device_, 1, &range));
}

// The shadow maps and the per-pixel images are tens of MB, read in scattered 4x4-pixel blocks:
// with 4 KiB pages the resolve pass spends about 3 ms of its ~35 at 1080p on TLB misses (measured
// with glibc.malloc.hugetlb=1, which does this for every allocation). Best effort: the kernel
// may refuse (THP off) or have no huge page free; nothing depends on it.
void Context::adviseHugePages(void* mapped, VkDeviceSize size) const {
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  if (properties_.deviceType != VK_PHYSICAL_DEVICE_TYPE_CPU || mapped == nullptr || size < 2 * kHuge) return;
  uintptr_t begin = (reinterpret_cast<uintptr_t>(mapped) + kHuge - 1) & ~(kHuge - 1);
  uintptr_t end = (reinterpret_cast<uintptr_t>(mapped) + uintptr_t(size)) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

uint32_t Context::memoryType(uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const {
  for (int pass = 0; pass < 2; ++pass) {
    VkMemoryPropertyFlags want = pass == 0 ? (required | preferred) : required;
    for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i)
      if ((typeBits & (1u << i)) && (memory_.memoryTypes[i].propertyFlags & want) == want) return i;
  }
  throw DriverError("no Vulkan memory type with the required properties");
}

Memory Context::allocate(const VkMemoryRequirements& requirements, VkMemoryPropertyFlags required,
                         VkMemoryPropertyFlags preferred, uint32_t* typeIndex, const std::string& what) const {
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = requirements.size;
  alloc.memoryTypeIndex = memoryType(requirements.memoryTypeBits, required, preferred);
  VkDeviceMemory memory;
  VK_CHECK_ALLOC(vkAllocateMemory(device_, &alloc, nullptr, &memory), what, deviceName());
  if (typeIndex) *typeIndex = alloc.memoryTypeIndex;
  return Memory(device_, memory);
}

void Context::markHung() const {
  hung_ = true;
  markRasterDeviceHung();
}

}  // namespace shadowlab::vk
