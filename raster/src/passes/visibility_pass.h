#pragma once
// Pass 2 (camera): the camera's visibility buffer, depth + id (global triangle + 1) per pixel. It
// depends on the scene and the camera only, not on the method: while both stay the same (a sweep
// over methods, a stability run with a fixed evaluation camera) it is kept and not drawn again.
// Its GPU time, measured when it was drawn, stays part of every frame's camera_gpu_ms.
#include <string>

#include "passes/id_draws.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab::raster {

// id (global triangle + 1, 0: none) -> (object id, the object's primitive index), as floats.
inline void idsOf(const SceneGpu& scene, uint32_t id, float& objectId, float& prim) {
  if (id == 0) {
    objectId = prim = 0.0f;
    return;
  }
  const uint32_t object = scene.triangleObject[id - 1];
  objectId = float(scene.objectIds[object]);
  prim = float(id - 1 - scene.objectTriangleBase[object]);
}

class VisibilityPass {
 public:
  explicit VisibilityPass(IdDraws& ids) : ids_(&ids) {}
  // The images of a width x height camera; new ones forget the key.
  void ensureImages(const vk::Context& context, int width, int height);
  // The camera side of `pipes`.
  void pipelines(const PassContext& pc, IdPipelines& pipes);
  // The visibility buffer's key: the scene, the camera's matrices, the image size.
  static std::string cameraKey(const SceneGpu& scene, const Camera& camera);
  // Records the pass where `draw` (else the buffer of the last one stays), then makes the ids
  // readable by the fragment shaders.
  void record(VkCommandBuffer cmd, const PassContext& pc, const SceneGpu& scene, const IdPipelines& pipes,
              const glm::mat4& cameraClip, int width, int height, bool draw, bool warmup) const;
  void bind(const PassContext& pc, BindingResources& r) const;
  const vk::Image& ids() const { return cameraIds_; }
  // Row y of the camera planes from the visibility buffer: hit (0/1), object_id, prim_id.
  void cameraRow(const SceneGpu& scene, int y, float* hit, float* objectId, float* primId) const;

  std::string keptKey;  // empty: the ids hold nothing reusable
  double gpuMs = 0;     // when it was drawn

 private:
  IdDraws* ids_;
  vk::Image cameraDepth_, cameraIds_;
};

}  // namespace shadowlab::raster
