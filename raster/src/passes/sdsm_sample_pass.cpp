#include "passes/sdsm_sample_pass.h"

#include <chrono>

#include "shadowlab/raster/sdsm.h"
#include "shadowlab/scenes/error.h"
#include "vk/check.h"

namespace shadowlab::raster {

void SdsmSamplePass::checkCamera(const Camera& fitCamera, const Camera& camera) {
  if (fitCamera.width != camera.width || fitCamera.height != camera.height)
    throw InputError("fit camera: error: got an image of " + std::to_string(fitCamera.width) + "x" +
                     std::to_string(fitCamera.height) + "; expected the scene camera's " +
                     std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                     " (fit=sdsm samples it with the camera pass's images)");
}

void SdsmSamplePass::record(VkCommandBuffer cmd, const PassContext& pc, VkDescriptorSet set, const SceneGpu& s,
                            const VisibilityPass& visibility, const IdPipelines& pipes, const Camera& fitCamera,
                            bool warmup) {
  if (!queries_.get()) {
    VkQueryPoolCreateInfo q{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    q.queryType = VK_QUERY_TYPE_TIMESTAMP;
    q.queryCount = 2;
    VkQueryPool pool;
    VK_CHECK(vkCreateQueryPool(pc.context->device(), &q, nullptr, &pool));
    queries_ = vk::QueryPool(pc.context->device(), pool);
  }
  VkQueryPool pool = queries_.get();
  vkCmdResetQueryPool(cmd, pool, 0, 2);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, pool, 0);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pc.layout, 0, 1, &set, 0, nullptr);
  VkBuffer vb = s.vertices.get();
  VkDeviceSize zero = 0;
  vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &zero);
  vkCmdBindIndexBuffer(cmd, s.indices.get(), 0, VK_INDEX_TYPE_UINT32);
  const glm::mat4 clip = fitCamera.clipFromView() * fitCamera.viewFromWorld();
  visibility.record(cmd, pc, s, pipes, clip, fitCamera.width, fitCamera.height, true, warmup);
  barrierToHost(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, pool, 1);
}

const std::vector<glm::vec3>& SdsmSamplePass::reduce(const vk::Context& context, const SceneGpu& scene,
                                                     const VisibilityPass& visibility, const Camera& fitCamera,
                                                     const std::string& key) {
  key_.clear();
  uint64_t stamps[2] = {};
  VK_CHECK(vkGetQueryPoolResults(context.device(), queries_.get(), 0, 2, sizeof(stamps), stamps, sizeof(uint64_t),
                                 VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  gpuMs_ = double(stamps[1] - stamps[0]) * context.properties().limits.timestampPeriod * 1e-6;
  const auto t0 = std::chrono::steady_clock::now();
  visibility.ids().invalidate(context);
  const CameraRays rays(fitCamera);
  const std::vector<glm::vec3>& vertices = scene.triangleVertices;
  const size_t triangles = vertices.size() / 3;
  std::vector<glm::vec3> halves[2];
  auto reduceRows = [&](size_t y0, size_t y1) {
    std::vector<glm::vec3>& out = halves[y1 == size_t(fitCamera.height) ? 1 : 0];  // rows in order after the join
    for (size_t y = y0; y < y1; ++y) {
      const uint32_t* ids = mappedRow<uint32_t>(visibility.ids(), y);
      for (int x = 0; x < fitCamera.width; ++x) {
        if (ids[x] == 0 || ids[x] > triangles) continue;
        const size_t t = size_t(ids[x] - 1);
        glm::vec3 p;
        if (visiblePoint(rays, fitCamera.position, x, int(y), vertices[3 * t], vertices[3 * t + 1], vertices[3 * t + 2],
                         p))
          out.push_back(p);
      }
    }
  };
  inTwoHalves(size_t(fitCamera.height), reduceRows);
  points_ = std::move(halves[0]);
  points_.insert(points_.end(), halves[1].begin(), halves[1].end());
  reduceMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  key_ = key;
  return points_;
}

}  // namespace shadowlab::raster
