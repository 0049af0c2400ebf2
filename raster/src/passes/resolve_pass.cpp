#include "passes/resolve_pass.h"

#include <algorithm>
#include <iterator>

namespace shadowlab::raster {

void ResolvePass::ensureImages(const vk::Context& c, int width, int height, bool momentChannels, size_t outputBytes) {
  if (out_[0].width() != width || out_[0].height() != height) {
    for (int i = 0; i < kResolveAttachments; ++i) {
      out_[i] = vk::Image();
      if (i < 2)
        out_[i] = vk::Image(c, width, height, 1, kResolveFormats[i], VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                            VK_IMAGE_ASPECT_COLOR_BIT, true, "camera resolve target");
    }
  }
  // The moment channels' target (33 MB at 1080p) only once a filterable map needs it; kept after.
  if (momentChannels && out_[2].width() != width)
    out_[2] = vk::Image(c, width, height, 1, kResolveFormats[2], VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
                        VK_IMAGE_ASPECT_COLOR_BIT, true, "camera resolve target");
  if (output_.size() != outputBytes) output_ = vk::Buffer(c, outputBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
}

ResolvePass::SurfaceImage& ResolvePass::surfaceFor(const vk::Context& context, const std::string& key, int width,
                                                   int height, bool& kept) {
  auto it = std::find_if(surfaces_.begin(), surfaces_.end(), [&](const SurfaceImage& s) { return s.key == key; });
  kept = it != surfaces_.end();
  if (!kept) it = surfaces_.size() < kKeptFootprints ? surfaces_.emplace(surfaces_.end()) : std::prev(surfaces_.end());
  surfaces_.splice(surfaces_.begin(), surfaces_, it);
  SurfaceImage& s = surfaces_.front();
  if (!kept) {
    s.key.clear();
    if (s.image.width() != width || s.image.height() != height)
      s.image = vk::Image(context, width, height, 1, kSurfaceFormat,
                          VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT);
  }
  return s;
}

void ResolvePass::ensureBound(const vk::Context& context) {
  if (!surfacePlaceholder_.get())
    surfacePlaceholder_ =
        vk::Image(context, 1, 1, 1, kSurfaceFormat, VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT);
  if (!surfaceBound_) surfaceBound_ = &surfacePlaceholder_;
}

void ResolvePass::recordPlanes(VkCommandBuffer cmd, VkPipeline planes, int width, int height, bool warmup) const {
  const vk::Image& surface = *surfaceBound_;
  if (planes != VK_NULL_HANDLE) {
    VkRenderingAttachmentInfo colors[2];
    vk::transition(cmd, out_[0], VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_HOST_BIT, 0,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    colors[0] = overwrittenColor(out_[0].layerView(0), VK_IMAGE_LAYOUT_GENERAL);
    colors[1] = overwrittenColor(surface.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
    drawFullscreen(cmd, colors, 2, uint32_t(width), uint32_t(height), planes, {}, warmup);
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  } else if (&surface == &surfacePlaceholder_) {
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                   VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  }
}

void ResolvePass::record(VkCommandBuffer cmd, VkPipeline resolve, int attachments, bool writeSurface, int width,
                         int height, bool warmup) const {
  const vk::Image& surface = *surfaceBound_;
  VkRenderingAttachmentInfo colors[kResolveAttachments + 1];
  for (int i = 0; i < attachments; ++i) {
    // After the planes pass (pass 3a), which wrote out_[0] too.
    vk::transition(cmd, out_[i], VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_HOST_BIT | VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
    colors[i] = overwrittenColor(out_[i].layerView(0), VK_IMAGE_LAYOUT_GENERAL);
  }
  if (writeSurface)  // the group's surface, for the lookup (as the planes pass draws it on demand)
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  const int targets = attachments + (writeSurface ? 1 : 0);
  if (writeSurface) colors[attachments] = overwrittenColor(surface.layerView(0), VK_IMAGE_LAYOUT_GENERAL);
  drawFullscreen(cmd, colors, uint32_t(targets), uint32_t(width), uint32_t(height), resolve, {}, warmup);
  if (writeSurface)
    vk::transition(cmd, surface, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL,
                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
}

void ResolvePass::bind(const PassContext& pc, BindingResources& r) const {
  r[abi::kBindingSurface].image = sampledImage(pc.nearest, surfaceBound_->layerView(0), VK_IMAGE_LAYOUT_GENERAL);
  r[abi::kBindingOutPlanes].buffer = &output_;
}

// Each attachment is read once, row by row, its components scattered to their planes; the rows
// are split over two threads (the split is bound by memory bandwidth, which one core does not
// saturate). Ids arrive as global triangle index + 1 (0: none) and leave as the object's id and
// its own primitive index.
Frame ResolvePass::readback(const vk::Context& context, const Scene& sc, const SceneGpu& sceneGpu,
                            const VisibilityPass& visibility, const Light* light, const Method& method, int width,
                            int height, std::vector<std::vector<float>>& spare) const {
  const bool momentChannels = light && isMomentFilter(method.filter);
  output_.invalidate(context);
  visibility.ids().invalidate(context);
  for (int i = 0; i < resolveAttachments(method.filter); ++i) out_[i].invalidate(context);
  Frame frame;
  frame.width = width;
  frame.height = height;
  const size_t n = size_t(width) * size_t(height);
  const bool hasLight = light != nullptr;
  const int projectorCount = int(sc.projectors.size());
  frame.names = {"hit", "object_id", "prim_id"};
  if (light) {
    const std::string p = "light." + light->name + ".";
    for (const char* name : {"vis", "receiver_depth", "map_depth", "m", "bias_depth", "bias_world", "occluder_id",
                             "occluder_prim", "in_map", "cascade"})
      frame.names.push_back(p + name);
    // Filterable maps: the moments' evidence at the lookup (resolve.frag's outC).
    if (momentChannels)
      for (const char* name : {"moment_mean", "moment_variance", "moment_bound"}) frame.names.push_back(p + name);
  }
  for (int j = 0; j < projectorCount; ++j) {
    const std::string p = "proj." + sc.projectors[size_t(j)].name + ".";
    for (const char* name : {"coverage", "R", "G", "B", "reverse"}) frame.names.push_back(p + name);
  }
  frame.data.resize(frame.names.size());
  // Recycled planes first (resized to this frame; every element is overwritten below).
  for (size_t c = 0; c < frame.data.size() && !spare.empty(); ++c) {
    frame.data[c] = std::move(spare.back());
    spare.pop_back();
  }
  spare.clear();
  auto allocate = [&](size_t first, size_t step) {
    for (size_t c = first; c < frame.data.size(); c += step) frame.data[c].resize(n);
  };
  {
    std::thread helper(allocate, 1, 2);
    allocate(0, 2);
    helper.join();
  }
  const float* planes = static_cast<const float*>(output_.mapped());
  auto split = [&](size_t y0, size_t y1) {
    for (int y = int(y0); y < int(y1); ++y) {
      const size_t o = size_t(y) * size_t(width);
      visibility.cameraRow(sceneGpu, y, frame.data[0].data() + o, frame.data[1].data() + o, frame.data[2].data() + o);
      if (hasLight) {
        float* out[10];
        for (int c = 0; c < 10; ++c) out[c] = frame.data[size_t(3 + c)].data() + o;
        const float* a = mappedRow<float>(out_[0], size_t(y));
        const float* b = mappedRow<float>(out_[1], size_t(y));
        for (int x = 0; x < width; ++x) {
          for (int k = 0; k < 4; ++k) out[k][x] = a[4 * x + k];
          out[4][x] = b[4 * x];
          out[5][x] = b[4 * x + 1];
          idsOf(sceneGpu, uint32_t(b[4 * x + 2]), out[6][x], out[7][x]);  // exact up to 2^24
          const int packed = int(b[4 * x + 3]);                           // 2 * cascade + in_map
          out[8][x] = float(packed & 1);
          out[9][x] = float(packed >> 1);
        }
        if (momentChannels) {
          const float* c = mappedRow<float>(out_[2], size_t(y));
          float* mean = frame.data[13].data() + o;
          float* variance = frame.data[14].data() + o;
          float* bound = frame.data[15].data() + o;
          for (int x = 0; x < width; ++x) {
            mean[x] = c[4 * x];
            variance[x] = c[4 * x + 1];
            bound[x] = c[4 * x + 2];
          }
        }
      }
      const size_t first = hasLight ? (momentChannels ? 16 : 13) : 3;
      for (int p = 0; p < abi::kProjectorChannels * projectorCount; ++p) {
        const float* in = planes + size_t(p) * n + o;
        std::copy(in, in + width, frame.data[first + size_t(p)].data() + o);
      }
    }
  };
  inTwoHalves(size_t(height), split);
  return frame;
}

}  // namespace shadowlab::raster
