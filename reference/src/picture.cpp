// referenceHash, the camera hash and the readable picture.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab {

std::string referenceHash(const Scene& scene, const ReferenceOptions& options) {
  // Version tag first: bump it whenever the reference's output changes for the same inputs
  // (channels, origin offset, sample pattern), so stale cache entries stop matching. /2: the cache
  // holds the Compare channel set (issue 14), where /1 entries hold every channel.
  std::string key = "shadowlab.reference/2;scene=" + scene.hash + ";camera=" + scene.camera.hash() +
                    ";spp=" + std::to_string(options.spp);
  return hashHex(fnv1a64(key.data(), key.size()));
}

std::vector<uint8_t> referencePicture(const Scene& scene, const Frame& frame) {
  // Gamma 1/2.2 through a table: a pow per channel would cost more than tracing the shadows.
  constexpr int kEncodeSteps = 4096;
  static const std::vector<uint8_t> encode = [] {
    std::vector<uint8_t> table(kEncodeSteps);
    for (int k = 0; k < kEncodeSteps; ++k)
      table[k] = uint8_t(std::lround(std::pow(double(k) / (kEncodeSteps - 1), 1.0 / 2.2) * 255.0));
    return table;
  }();
  const size_t pixels = frame.pixelCount();
  std::vector<uint8_t> rgb(pixels * 3);
  const glm::vec3 background(0.05f, 0.07f, 0.20f);
  const float ambient = 0.15f;

  std::unordered_map<uint32_t, const Object*> objectsById;
  for (const Object& object : scene.objects) objectsById[object.id] = &object;
  const Light* light = scene.findLight(scene.lightOrDefault(""));
  const std::vector<float>* vis = nullptr;
  if (light && frame.has("light." + light->name + ".vis")) vis = &frame.get("light." + light->name + ".vis");
  struct ProjectorPlanes {
    const std::vector<float>* coverage;
    const std::vector<float>* rgb[3];
  };
  std::vector<ProjectorPlanes> projectors;
  for (const Projector& projector : scene.projectors) {
    const std::string prefix = "proj." + projector.name + ".";
    if (!frame.has(prefix + "coverage")) continue;
    projectors.push_back({&frame.get(prefix + "coverage"),
                          {&frame.get(prefix + "R"), &frame.get(prefix + "G"), &frame.get(prefix + "B")}});
  }
  const auto& hit = frame.get("hit");
  const auto& objectId = frame.get("object_id");
  const auto& primId = frame.get("prim_id");
  const std::vector<float>* p[3] = {&frame.get("P.x"), &frame.get("P.y"), &frame.get("P.z")};
  const std::vector<float>* n[3] = {&frame.get("N.x"), &frame.get("N.y"), &frame.get("N.z")};

  for (size_t i = 0; i < pixels; ++i) {
    glm::vec3 color = background;
    if (hit[i] > 0.5f) {
      glm::vec3 albedo(0.8f);
      auto found = objectsById.find(uint32_t(objectId[i]));
      if (found != objectsById.end()) {
        const Object& object = *found->second;
        const size_t prim = size_t(primId[i]);
        if (prim < object.triangleMaterial.size() && object.triangleMaterial[prim] < scene.materials.size())
          albedo = scene.materials[object.triangleMaterial[prim]].albedo;
      }
      const glm::vec3 normal((*n[0])[i], (*n[1])[i], (*n[2])[i]);
      const glm::vec3 position((*p[0])[i], (*p[1])[i], (*p[2])[i]);
      float direct = 0.0f;
      if (light) {
        const glm::vec3 toLight =
            light->type == LightType::Directional ? -light->direction : light->position - position;
        const float length = glm::length(toLight);
        const float lambert = length > 0.0f ? std::max(0.0f, glm::dot(normal, toLight / length)) : 0.0f;
        direct = lambert * (vis ? (*vis)[i] : 1.0f);
      }
      color = albedo * (ambient + (1.0f - ambient) * direct);
      for (const ProjectorPlanes& projector : projectors) {
        const float coverage = (*projector.coverage)[i];
        for (int c = 0; c < 3; ++c) color[c] += 0.6f * coverage * (*projector.rgb[c])[i];
      }
    }
    for (int c = 0; c < 3; ++c) {
      const float clamped = std::min(1.0f, std::max(0.0f, color[c]));
      rgb[i * 3 + c] = encode[size_t(clamped * float(kEncodeSteps - 1) + 0.5f)];
    }
  }
  return rgb;
}

}  // namespace shadowlab
