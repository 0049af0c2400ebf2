#pragma once
// Pass 3a (planes, a group's first frame on demand): resolve.frag specialized to kSpecPlanesOnly:
//   m and 2 * cascade + in_map (evidence on demand keeps them per group) and the group's surface
//   (kSurfaceFormat: the visible point's map coordinates or the point, whether the light reaches
//   it), kept for up to kKeptFootprints groups (surfaceFor).
// Pass 3 (resolve, a full-screen fragment pass): per pixel, the visible point, the map lookup with
//   the method's bias and filter, the evidence channels into two color attachments
//   (kResolveFormats), the projectors into a storage buffer (one plane per channel), with a light
//   the group's surface into one more attachment (the lookup reads it).
// The attachments are linear images in host memory: readback() splits them into the Frame's
// channel planes in place, without a copy to a buffer first.
#include <list>
#include <string>
#include <vector>

#include "passes/visibility_pass.h"
#include "shadowlab/scenes/frame.h"

namespace shadowlab::raster {

class ResolvePass {
 public:
  // The attachments of a width x height camera (the moment channels' at the first filterable map
  // only, kept after) and the projector planes' buffer of `outputBytes`.
  void ensureImages(const vk::Context& context, int width, int height, bool momentChannels, size_t outputBytes);
  // The groups' surfaces (kSurfaceFormat), keyed like the footprints (footprintKey), most recently
  // used first, at most kKeptFootprints: the planes pass draws one on demand, a full frame's
  // resolve writes its group's.
  struct SurfaceImage {
    std::string key;  // empty until a pass has drawn it
    vk::Image image;
  };
  // The group's surface image: the kept one (kept = true: the planes pass need not draw it), else a
  // slot for the planes pass (the least recently used one past kKeptFootprints), its key cleared
  // until render() has drawn it.
  SurfaceImage& surfaceFor(const vk::Context& context, const std::string& key, int width, int height, bool& kept);
  // The 1x1 placeholder (never read: every binding needs an image), bound where nothing is yet
  // (fit=sdsm's sample pass writes the descriptors before the frame's surface is known).
  void ensureBound(const vk::Context& context);
  // The frame's surface (kBindingSurface: the lookup reads it), or none: the placeholder.
  void bindSurface(SurfaceImage* surface) { surfaceBound_ = surface ? &surface->image : &surfacePlaceholder_; }
  // Pass 3a where `planes` (else makes the placeholder readable where it is bound).
  void recordPlanes(VkCommandBuffer cmd, VkPipeline planes, int width, int height, bool warmup) const;
  // Pass 3: `attachments` channels (resolveAttachments), the surface too where `writeSurface`.
  void record(VkCommandBuffer cmd, VkPipeline resolve, int attachments, bool writeSurface, int width, int height,
              bool warmup) const;
  void bind(const PassContext& pc, BindingResources& r) const;
  // The frame's channels from the visibility buffer (hit, object_id, prim_id), the attachments
  // (the light's channels, see resolve.frag's outA/outB) and the projector planes; planes from
  // `spare` first.
  Frame readback(const vk::Context& context, const Scene& scene, const SceneGpu& sceneGpu,
                 const VisibilityPass& visibility, const Light* light, const Method& method, int width, int height,
                 std::vector<std::vector<float>>& spare) const;
  // The planes pass's first attachment (m, 2 * cascade + in_map), host-readable.
  const vk::Image& planes() const { return out_[0]; }

 private:
  // out_[2] (the moment channels) is allocated at the first filterable map only.
  vk::Image out_[kResolveAttachments];
  vk::Buffer output_;  // the projector channels
  std::list<SurfaceImage> surfaces_;
  vk::Image surfacePlaceholder_;
  vk::Image* surfaceBound_ = nullptr;
};

}  // namespace shadowlab::raster
