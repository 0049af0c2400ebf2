// referenceHash, the camera hash and the readable picture.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "picture_shading.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/number_text.h"

namespace shadowlab {

std::string referenceHash(const Scene& scene, const ReferenceOptions& options) {
  // Version tag first: bump it whenever the reference's output changes for the same inputs
  // (channels, origin offset, sample pattern), so stale cache entries stop matching. /2: the cache
  // holds the Compare channel set, where /1 entries hold every channel.
  std::string key = "shadowlab.reference/2;scene=" + scene.hash + ";camera=" + scene.camera.hash() +
                    ";spp=" + std::to_string(options.spp);
  // Light samples change only a sized light's values: a scene of hard lights keeps its key.
  if (std::any_of(scene.lights.begin(), scene.lights.end(), [](const Light& light) { return light.sized(); }))
    key += ";light_samples=" + std::to_string(options.lightSamples);
  // A shifted trace is another frame; an unshifted one keeps its key.
  if (options.pixelOffset != glm::vec2(0.0f))
    key += ";pixel_offset=" + numberText(options.pixelOffset.x) + "," + numberText(options.pixelOffset.y);
  return hashHex(fnv1a64(key.data(), key.size()));
}

namespace reference_detail {

PictureShader::PictureShader(const Scene& scene) : scene_(scene), light_(scene.findLight(scene.lightOrDefault(""))) {
  static const std::vector<uint8_t> table = [] {
    std::vector<uint8_t> t(kEncodeSteps);
    for (int k = 0; k < kEncodeSteps; ++k)
      t[k] = uint8_t(std::lround(std::pow(double(k) / (kEncodeSteps - 1), 1.0 / 2.2) * 255.0));
    return t;
  }();
  encode_ = table.data();
  if (light_ && light_->type == LightType::Directional) {
    const glm::vec3 toLight = -light_->direction;
    directionalLength_ = glm::length(toLight);
    directionalUnit_ = toLight / directionalLength_;
  }
}

}  // namespace reference_detail

std::vector<uint8_t> referencePicture(const Scene& scene, const Frame& frame) {
  const reference_detail::PictureShader shader(scene);
  const size_t pixels = frame.pixelCount();
  std::vector<uint8_t> rgb(pixels * 3);
  std::unordered_map<uint32_t, const Object*> objectsById;
  for (const Object& object : scene.objects) objectsById[object.id] = &object;
  const Light* light = shader.light();
  const std::vector<float>* vis = nullptr;
  if (light && frame.has("light." + light->name + ".vis")) vis = &frame.get("light." + light->name + ".vis");
  std::vector<const std::vector<float>*> coverage;
  std::vector<std::array<const std::vector<float>*, 3>> colors;
  for (const Projector& projector : scene.projectors) {
    const std::string prefix = "proj." + projector.name + ".";
    if (!frame.has(prefix + "coverage")) continue;
    coverage.push_back(&frame.get(prefix + "coverage"));
    colors.push_back({&frame.get(prefix + "R"), &frame.get(prefix + "G"), &frame.get(prefix + "B")});
  }
  const auto& hit = frame.get("hit");
  const auto& objectId = frame.get("object_id");
  const auto& primId = frame.get("prim_id");
  const std::vector<float>* p[3] = {&frame.get("P.x"), &frame.get("P.y"), &frame.get("P.z")};
  const std::vector<float>* n[3] = {&frame.get("N.x"), &frame.get("N.y"), &frame.get("N.z")};
  std::vector<float> pixelCoverage(coverage.size());
  std::vector<glm::vec3> pixelRgb(coverage.size());
  for (size_t i = 0; i < pixels; ++i) {
    const bool isHit = hit[i] > 0.5f;
    glm::vec3 albedo(0.8f);
    if (isHit) {
      auto found = objectsById.find(uint32_t(objectId[i]));
      albedo = shader.albedo(found != objectsById.end() ? found->second : nullptr, size_t(primId[i]));
    }
    for (size_t k = 0; k < coverage.size(); ++k) {
      pixelCoverage[k] = (*coverage[k])[i];
      pixelRgb[k] = glm::vec3((*colors[k][0])[i], (*colors[k][1])[i], (*colors[k][2])[i]);
    }
    shader.shade(isHit, albedo, glm::vec3((*n[0])[i], (*n[1])[i], (*n[2])[i]),
                 glm::vec3((*p[0])[i], (*p[1])[i], (*p[2])[i]), vis ? (*vis)[i] : 1.0f, coverage.size(),
                 pixelCoverage.data(), pixelRgb.data(), &rgb[i * 3]);
  }
  return rgb;
}

}  // namespace shadowlab
