#pragma once
// Evidence on demand (render() with an EvidenceSelector, a light, no projectors, and the group's
// planes kept): the full resolve is skipped. After the shadow, visibility and lookup passes the
// CPU reads the bytes back, lists the fractional pixels and those the selector asks for (where the
// decision disagrees with the reference), and
//   Pass 5 (evidence): resolve.frag specialized to kSpecCompact draws a kCompactWidth-wide target
//                    with one fragment per listed pixel (evidencePixels[k] instead of
//                    gl_FragCoord), the same channels as the full resolve for those pixels only;
//                    the pixels listed for the map texel's evidence alone
//                    (EvidenceRequest::occluder, and the fractional ones) go through the lookup's
//                    specialization made compact instead (kSpecLookupOnly + kSpecCompact: vis,
//                    occluder, in_map; about half the cost per pixel on lavapipe);
// the frame is then the bytes (0/1 exactly), the kept planes of the group (hit, object_id,
// prim_id from the visibility buffer; m and cascade per footprintKey: the light's layers, the
// camera, the cascade splits) and the listed pixels' evidence, zeros elsewhere. A group's first
// frame draws those planes first (the planes pass, resolve_pass.h) and keeps them (keepPlanes).
#include <functional>
#include <list>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "passes/lookup_pass.h"
#include "passes/resolve_pipelines.h"
#include "passes/visibility_pass.h"
#include "shadowlab/raster/raster.h"
#include "vk/commands.h"

namespace shadowlab::raster {

// Evidence on demand's group: everything m, the cascade index and the group's surface (the point's
// map coordinates) are computed from in resolve.frag (the visible point, the pixel's layer and its
// projection, the light-depth row, the cascade splits, the cube face), none of which is a bias or a
// filter. The specialization constants that change that code (light type, cascaded, affine, light
// depth) are part of it; the filter's is not (the same bits whatever the filter:
// tests/compare_on_demand_test.cpp). `cameraKey`: VisibilityPass::cameraKey.
std::string footprintKey(const std::string& cameraKey, const abi::Params& params, const ResolveSpecialization& spec);

class EvidencePass {
 public:
  explicit EvidencePass(const vk::Context& context);
  // Planes lent to a frame not handed back before this render stay with it (its group's next
  // frame is a full one): recycle() only takes back what the last render lent.
  void forgetLent() { lent_ = Lent(); }
  // The planes that depend on no bias or filter, kept per group (footprintKey).
  struct Footprint {
    std::string key;  // footprintKey
    std::vector<float> m, cascade;
  };
  // The group's kept planes, with the camera planes of `camera` (VisibilityPass::cameraKey); none
  // where either is not kept or is lent to a frame not handed back.
  Footprint* kept(const std::string& camera, const std::string& group);
  // The first frame of a group on demand, after the planes pass: keeps the camera planes (hit,
  // object_id, prim_id from the visibility buffer, as the full readback makes them) unless those of
  // this camera are kept, and the group's m and cascade from `planes` (the planes pass's target).
  Footprint& keepPlanes(const vk::Context& context, const SceneGpu& scene, const VisibilityPass& visibility,
                        const vk::Image& planes, const std::string& key, const std::string& camera, int width,
                        int height);
  // The pass's two pipelines (the full list's and the occluder list's, with a light) and whether
  // one is used for the first time (lavapipe compiles at first use: the pass then runs twice).
  struct Pipelines {
    VkPipeline evidence = VK_NULL_HANDLE;
    VkPipeline occluder = VK_NULL_HANDLE;
    bool firstUse = false;
  };
  Pipelines pipelines(const PassContext& pc, ResolvePipelines& resolve, const ResolveSpecialization& spec,
                      const ResolveSpecialization& lookupSpec, bool light);
  // What partialFrame needs of the frame around it.
  struct FrameInputs {
    const PassContext* pc;
    vk::Commands* commands;
    VkDescriptorSet set;
    std::function<void()> writeDescriptors;  // after the pixel buffer grew
    const SceneGpu* scene;
    LookupPass* lookup;
    bool stencilIds;  // the map's stencil holds the occluders' objects
    int maxImageSize;
  };
  // Reads the lookup's bytes, lists the fractional pixels and those `select` asks for, resolves
  // only those (pass 5: kCompactWidth-wide targets, one texel per listed pixel) and builds the
  // frame from the bytes, the kept planes and the listed pixels' evidence; planes from `spare`.
  Frame partialFrame(const FrameInputs& in, const Scene& scene, const Light& light, const Method& method,
                     const EvidenceSelector& select, Footprint& footprint, const Pipelines& pipes,
                     std::vector<std::vector<float>>& spare, RasterTimings& t);
  // Takes back the planes the last partial frame borrowed (Rasterizer::recycle); the others go
  // to `spare`.
  void recycle(Frame&& frame, std::vector<std::vector<float>>& spare);
  void bind(BindingResources& r) const { r[abi::kBindingEvidencePixels].buffer = &pixels_; }

 private:
  // The listed pixels, the compact targets (kCompactWidth wide, as many rows as the list needs;
  // [2] for filterable maps only), their two timestamps.
  vk::Buffer pixels_;
  vk::Image out_[kResolveAttachments];
  vk::Image occluderOut_;  // the pixels listed for the occluder's evidence alone: vis, occluder, in_map
  vk::QueryPool queries_;
  std::set<std::pair<ResolveSpecialization, std::string>> warmed_;
  // The planes that depend on the scene and the camera only (hit, object_id, prim_id, as the last
  // full frame read them back) and, per group, on the light's layers too (m, cascade): what
  // evidence on demand copies instead of resolving.
  struct CameraPlanes {
    std::string key;  // the visibility key they were read with
    std::vector<float> hit, objectId, primId;
  } cameraPlanes_;
  std::list<Footprint> footprints_;  // most recently used first, at most kKeptFootprints
  // The kept planes are lent (moved, not copied) to the last partial frame; recycle() moves them
  // back and re-zeroes that frame's evidence planes at its listed pixels only, for the next one.
  // A frame not handed back leaves its group without planes: its next frame is a full one.
  struct Lent {
    std::string footprintKey;
    const float* kept[5] = {};         // hit, object_id, prim_id, m, cascade
    std::vector<const float*> zeroed;  // evidence planes: 0 except at `listed`
    const float* vis = nullptr;        // the vis plane: the bytes' values except at `listed`
    std::vector<uint32_t> listed;
  } lent_;
  std::vector<std::vector<float>> zeroSpare_;  // planes of zeros (recycled evidence planes)
  // The vis plane of the last partial frame, handed back by recycle() with its listed pixels set
  // back to what the bytes say, and the lookup bytes it encodes: the next partial frame rewrites
  // only the pixels whose byte changed. `plane` is empty while lent (or never handed back).
  struct VisPlane {
    std::vector<float> plane;
    std::vector<uint8_t> bytes;
  } visKept_;
  EvidenceRequest asked_;
  std::vector<uint32_t> fractional_;
  // partialFrame's lists beside `asked_` (kept, so a frame with acne everywhere needs no fresh
  // memory for them): the occluder's list with the fractional pixels, and that less the full list.
  std::vector<uint32_t> occluderOrFractional_, occluderListed_;
};

}  // namespace shadowlab::raster
