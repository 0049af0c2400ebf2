#pragma once
// fit=sdsm's samples, as an engine's depth reduction reads its depth buffer: the visibility pass
// recorded alone for the fit camera (its own submit: the fit must be known before the shadow
// pass), its ids read back and each hit pixel's world point reconstructed on the CPU (sdsm.h's
// visiblePoint: the ray through the pixel's center and the plane of its triangle, as resolve.frag
// does). Kept per scene and fit camera (a sweep over methods reduces once). The frame then draws
// its own visibility buffer again, so camera_gpu_ms stays the camera pass's, without this one.
// What an engine pays for its samples is in the method's time instead: the pass's GPU timestamps
// (sdsm_gpu_ms, part of method_gpu_ms), timed when the samples were taken and reported by every
// frame that uses them; the readback and the CPU reduction are sdsm_reduce_ms, beside it (an
// engine reduces on the GPU, e.g. MJP's DepthReduction compute pass).
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
  // The visibility pass for the fit camera between two timestamps, its ids then readable by the
  // host. `warmup`: a pipeline's first use (lavapipe compiles it then), submitted once untimed.
  void record(VkCommandBuffer cmd, const PassContext& pc, VkDescriptorSet set, const SceneGpu& scene,
              const VisibilityPass& visibility, const IdPipelines& pipes, const Camera& fitCamera, bool warmup);
  // After the submit: the visible points of the recorded ids, kept as `key`'s, with the pass's
  // GPU time and the reduction's CPU time.
  const std::vector<glm::vec3>& reduce(const vk::Context& context, const SceneGpu& scene,
                                       const VisibilityPass& visibility, const Camera& fitCamera,
                                       const std::string& key);
  // The kept samples' costs (0 before any): the sample pass's GPU ms, the readback and reduction's CPU ms.
  double gpuMs() const { return gpuMs_; }
  double reduceMs() const { return reduceMs_; }

 private:
  std::vector<glm::vec3> points_;
  std::string key_;  // empty: none kept
  vk::QueryPool queries_;  // 2 timestamps around the pass
  double gpuMs_ = 0, reduceMs_ = 0;
};

}  // namespace shadowlab::raster
