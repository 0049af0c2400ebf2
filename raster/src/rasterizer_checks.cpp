// The checks of a request before any GPU work: validation (the light, the method's ranges, the
// formats the device renders) and the images a frame allocates, sized by the device.
#include <algorithm>
#include <string>

#include "rasterizer_impl.h"
#include "shadowlab/scenes/number_text.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {

namespace {
namespace abi = raster::abi;
using raster::kCameraDepthFormat;
using raster::kIdFormat;
using raster::kLookupFormat;
using raster::kResolveFormats;
using raster::momentsFormat;
using raster::resolveAttachments;
using raster::vkDepthFormat;
using raster::vkDepthStencilFormat;
}  // namespace

namespace raster {
void checkOrthographicFit(const Scene& scene, const Light* light, const Method& method, const Camera& camera) {
  if (!camera.orthographic() || !light || light->type != LightType::Directional || method.fit == Fit::Sphere) return;
  throw InputError(formatError("method", "fit",
                               "got " + toString(method.fit) + " with the orthographic camera of " +
                                   (scene.path.empty() ? scene.name : scene.path) + "; expected fit=sphere (fit=" +
                                   toString(method.fit) + " follows a perspective camera's frustum)"));
}
}  // namespace raster

// Validation: everything that can be wrong with the request, before any GPU work. Returns the
// light to render (nullptr: the scene's projectors only).
const Light* Rasterizer::Impl::validate(const Scene& scene, const Method& method, const std::string& lightName) const {
  const std::string where = scene.path.empty() ? scene.name : scene.path;
  const int maxSize = maxMapSize();
  const std::string chosen = scene.lightOrDefault(lightName);
  const Light* light = chosen.empty() ? nullptr : scene.findLight(chosen);
  if (!chosen.empty()) {
    if (!light) {
      std::string names;
      for (auto& l : scene.lights) names += (names.empty() ? "" : ", ") + l.name;
      throw InputError(formatError(where, "",
                                   "no light named \"" + lightName + "\"; expected one of: " +
                                       (names.empty() ? "(the scene has no lights)" : names)));
    }
  }
  raster::checkOrthographicFit(scene, light, method, scene.camera);
  if (method.mapSize < 16 || method.mapSize > maxSize)
    throw InputError(formatError("method", "map.size",
                                 "got " + std::to_string(method.mapSize) + "; expected 16.." + std::to_string(maxSize) +
                                     " (the device's largest image)"));
  if (method.filter == Filter::Pcf && (method.filterSize < 1 || method.filterSize % 2 == 0 || method.filterSize > 15))
    throw InputError(formatError("method", "filter.size",
                                 "got " + std::to_string(method.filterSize) + "; expected an odd number 3..15"));
  if (method.filter == Filter::Poisson && (method.filterTaps < 1 || method.filterTaps > abi::kMaxTaps))
    throw InputError(
        formatError("method", "filter.taps",
                    "got " + std::to_string(method.filterTaps) + "; expected 1.." + std::to_string(abi::kMaxTaps)));
  if (method.filter == Filter::Poisson && !(method.filterRadius > 0.0f && method.filterRadius <= 32.0f))
    throw InputError(formatError("method", "filter.radius",
                                 "got " + numberText(method.filterRadius) + "; expected > 0 and <= 32 texels"));
  // The soft filters take the light's size in map units from a layer that is a plain crop (an
  // orthographic one for a directional light): a warped map's texel and depth scales change
  // across it, so no one size per layer holds (raster/METHODS.md "Soft filters").
  const bool softFilter = method.filter == Filter::Pcss || method.filter == Filter::Dpcf;
  if (softFilter && light && light->type == LightType::Directional &&
      (method.fit == Fit::Lispsm || method.fit == Fit::Psm || method.fit == Fit::Tsm))
    throw InputError(formatError("method", "fit",
                                 "got " + toString(method.fit) + " with filter=" + toString(method.filter) +
                                     " and the directional light \"" + light->name +
                                     "\"; expected fit=sphere, tight, cascades or sdsm (a warped map has no one "
                                     "light size in texels)"));
  if (scene.projectors.size() > size_t(abi::kMaxProjectors))
    throw InputError(formatError(where, "/projectors",
                                 "got " + std::to_string(scene.projectors.size()) +
                                     " projectors; the rasterizer renders at most " +
                                     std::to_string(abi::kMaxProjectors)));
  const Camera& camera = scene.camera;
  if (camera.width < 1 || camera.height < 1 || camera.width > maxSize || camera.height > maxSize)
    throw InputError(formatError(
        where, "/camera",
        "image size " + std::to_string(camera.width) + "x" + std::to_string(camera.height) + " is not renderable"));
  VkFormatProperties fp;
  vkGetPhysicalDeviceFormatProperties(context->physical(), vkDepthFormat(method.mapFormat), &fp);
  VkFormatFeatureFlags need = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
  if ((fp.optimalTilingFeatures & need) != need)
    throw InputError(formatError("method", "map.format",
                                 "got " + toString(method.mapFormat) + ", which device " + context->deviceName() +
                                     " cannot render and sample; expected another format"));
  if (isMomentFilter(method.filter)) {
    // The moments map is rendered, then sampled with linear filtering.
    const VkFormat mf = momentsFormat(method.filter);
    vkGetPhysicalDeviceFormatProperties(context->physical(), mf, &fp);
    need = VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT |
           VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
    if ((fp.optimalTilingFeatures & need) != need)
      throw InputError(formatError("method", "filter",
                                   "got " + toString(method.filter) + ", whose moments map (" +
                                       (mf == VK_FORMAT_R32G32_SFLOAT ? "RG32F" : "RGBA32F") + ") device " +
                                       context->deviceName() +
                                       " cannot render and sample with linear filtering; expected another filter"));
  }
  return light;
}

int Rasterizer::Impl::maxMapSize() const {
  const VkPhysicalDeviceLimits& l = context->properties().limits;
  return int(std::min({l.maxImageDimension2D, l.maxFramebufferWidth, l.maxFramebufferHeight}));
}

DeviceMemoryLimits Rasterizer::Impl::memoryLimits() const {
  DeviceMemoryLimits out;
  out.deviceName = context->deviceName();
  out.cpuDevice = context->properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  const VkPhysicalDeviceMemoryProperties& memory = context->memoryProperties();
  for (uint32_t i = 0; i < memory.memoryHeapCount; ++i)
    if (memory.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      out.deviceLocalHeapBytes = std::max<uint64_t>(out.deviceLocalHeapBytes, memory.memoryHeaps[i].size);
  out.maxAllocationBytes = context->maxAllocationBytes();
  out.maxImageDimension2D = context->properties().limits.maxImageDimension2D;
  out.maxImageArrayLayers = context->properties().limits.maxImageArrayLayers;
  return out;
}

// What ensureImages and ensureMoments allocate for this frame (the map in the larger of its two
// formats: the depth+stencil twin serves evidence on demand), sized by the device itself
// (vkGetDeviceImageMemoryRequirements, Vulkan 1.3: no image is created).
std::vector<DeviceImage> Rasterizer::Impl::plannedImages(const Scene& scene, const Method& method,
                                                         const raster::FrameLayers& layers) const {
  auto bytesOf = [&](int width, int height, int count, VkFormat format, VkImageUsageFlags usage, bool linear) {
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {uint32_t(width), uint32_t(height), 1};
    info.mipLevels = 1;
    info.arrayLayers = uint32_t(count);
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = linear ? VK_IMAGE_TILING_LINEAR : VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    VkDeviceImageMemoryRequirements query{VK_STRUCTURE_TYPE_DEVICE_IMAGE_MEMORY_REQUIREMENTS};
    query.pCreateInfo = &info;
    VkMemoryRequirements2 req{VK_STRUCTURE_TYPE_MEMORY_REQUIREMENTS_2};
    vkGetDeviceImageMemoryRequirements(context->device(), &query, &req);
    return uint64_t(req.memoryRequirements.size);
  };
  const std::string scenePlace = scene.path.empty() ? scene.name : scene.path;
  // A sweep asks for the same images frame after frame: the device is asked once per shape.
  const std::string key = scenePlace + "|" + std::to_string(method.mapSize) + "|" + toString(method.mapFormat) + "|" +
                          toString(method.filter) + "|" + std::to_string(layers.layers.size()) + "|" +
                          std::to_string(layers.lightLayers) + "|" + std::to_string(scene.camera.width) + "x" +
                          std::to_string(scene.camera.height);
  if (key == plannedKey) return planned;
  std::vector<DeviceImage> out;
  auto add = [&](const char* what, bool map, int width, int height, int count, VkFormat format, VkImageUsageFlags usage,
                 bool linear = false) {
    out.push_back({what, map ? "method" : scenePlace, map ? "map.size" : "/camera", width, height, count,
                   bytesOf(width, height, count, format, usage, linear)});
  };
  // Sizes the device cannot make at all are validate()'s and checkDeviceMemory's to refuse, by
  // their limits, before the device is asked about them.
  const uint32_t maxLayers = context->properties().limits.maxImageArrayLayers;
  const int size = method.mapSize, mapLayers = std::max(1, int(layers.layers.size()));
  auto sized = [&](const char* what, bool map, int width, int height, int count, VkFormat format,
                   VkImageUsageFlags usage, bool linear = false) {
    if (uint32_t(count) > maxLayers)
      out.push_back({what, map ? "method" : scenePlace, map ? "map.size" : "/camera", width, height, count, 0});
    else add(what, map, width, height, count, format, usage, linear);
  };
  const VkImageUsageFlags depthUsage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  sized("shadow map depth", true, size, size, mapLayers, vkDepthFormat(method.mapFormat), depthUsage);
  VkFormatProperties fp;
  const VkFormat twin = vkDepthStencilFormat(method.mapFormat);
  vkGetPhysicalDeviceFormatProperties(context->physical(), twin, &fp);
  const VkFormatFeatureFlags need =
      VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
  if ((fp.optimalTilingFeatures & need) == need && uint32_t(mapLayers) <= maxLayers) {
    const uint64_t twinBytes = bytesOf(size, size, mapLayers, twin, depthUsage, false);
    out.back().bytes = std::max(out.back().bytes, twinBytes);
  }
  const VkImageUsageFlags colorUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  sized("shadow map ids", true, size, size, mapLayers, kIdFormat, colorUsage);
  if (isMomentFilter(method.filter)) {
    const int lightLayers = std::max(1, layers.lightLayers);
    sized("moments map", true, size, size, lightLayers, momentsFormat(method.filter), colorUsage);
    sized("moments rows", true, size, size, lightLayers, momentsFormat(method.filter), colorUsage);
  }
  const int width = scene.camera.width, height = scene.camera.height;
  add("camera depth", false, width, height, 1, kCameraDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT);
  add("camera ids", false, width, height, 1, kIdFormat, colorUsage, true);
  for (int i = 0; i < resolveAttachments(method.filter); ++i)
    add("camera resolve target", false, width, height, 1, kResolveFormats[i], VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
        true);
  add("camera lookup target", false, width, height, 1, kLookupFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, true);
  plannedKey = key;
  planned = out;
  return out;
}

}  // namespace shadowlab
