#pragma once
// fit=sdsm's samples, as an engine's depth reduction reads its depth buffer: the visibility pass
// recorded alone for the fit camera (its own submit: the fit must be known before the shadow
// pass), its ids read back and each hit pixel's world point reconstructed on the CPU (sdsm.h's
// visiblePoint: the ray through the pixel's center and the plane of its triangle, as resolve.frag
// does). Kept per scene and fit camera (a sweep over methods reduces once). The frame then draws
// its own visibility buffer again, so camera_gpu_ms stays the camera pass's, without this one.
#include <string>
#include <vector>

#include "passes/visibility_pass.h"

namespace shadowlab::raster {

class SdsmSamplePass {
 public:
  // The kept samples of `key` (VisibilityPass::cameraKey of the fit camera), or none.
  const std::vector<glm::vec3>* kept(const std::string& key) const { return key == key_ ? &points_ : nullptr; }
  // Refuses a fit camera whose image is not the scene camera's (it samples with its images).
  static void checkCamera(const Camera& fitCamera, const Camera& camera);
  // The visibility pass for the fit camera, its ids then readable by the host.
  void record(VkCommandBuffer cmd, const PassContext& pc, VkDescriptorSet set, const SceneGpu& scene,
              const VisibilityPass& visibility, const IdPipelines& pipes, const Camera& fitCamera) const;
  // After the submit: the visible points of the recorded ids, kept as `key`'s.
  const std::vector<glm::vec3>& reduce(const vk::Context& context, const SceneGpu& scene,
                                       const VisibilityPass& visibility, const Camera& fitCamera,
                                       const std::string& key);

 private:
  std::vector<glm::vec3> points_;
  std::string key_;  // empty: none kept
};

}  // namespace shadowlab::raster
