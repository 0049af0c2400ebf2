#pragma once
// Private to reference/: the readable picture's colour of one pixel, in one place for both ways it
// is drawn: referencePicture (from a frame's channels, picture.cpp) and renderReference's picture
// output (from the trace's own values, reference.cpp), which give the same bytes.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/scenes/scene.h"

namespace shadowlab::reference_detail {

class PictureShader {
 public:
  explicit PictureShader(const Scene& scene);
  // The light the picture shows (the scene's default light), or null.
  const Light* light() const { return light_; }
  // The material albedo of `object`'s triangle `prim` (0.8 grey where the object or its material is unknown).
  glm::vec3 albedo(const Object* object, size_t prim) const {
    if (object && prim < object->triangleMaterial.size() && object->triangleMaterial[prim] < scene_.materials.size())
      return scene_.materials[object->triangleMaterial[prim]].albedo;
    return glm::vec3(0.8f);
  }
  // Grey Lambert shading of `albedo` times `vis` (+ 0.15 ambient), each projector's colour times
  // 0.6 times its coverage added, gamma 1/2.2 through a table: three bytes at `out`. Background
  // (dark blue) where !hit. coverage[k], rgb[k]: projector k's values. Inline: it runs per pixel.
  void shade(bool hit, const glm::vec3& albedo, const glm::vec3& normal, const glm::vec3& position, float vis,
             size_t projectors, const float* coverage, const glm::vec3* rgb, uint8_t* out) const {
    const float ambient = 0.15f;
    glm::vec3 color(0.05f, 0.07f, 0.20f);  // background
    if (hit) {
      float direct = 0.0f;
      if (light_) {
        glm::vec3 unit = directionalUnit_;  // toLight / |toLight|, the same bits for every pixel
        float length = directionalLength_;
        if (light_->type != LightType::Directional) {
          const glm::vec3 toLight = light_->position - position;
          length = glm::length(toLight);
          unit = toLight / length;
        }
        const float lambert = length > 0.0f ? std::max(0.0f, glm::dot(normal, unit)) : 0.0f;
        direct = lambert * vis;
      }
      color = albedo * (ambient + (1.0f - ambient) * direct);
      for (size_t k = 0; k < projectors; ++k)
        for (int c = 0; c < 3; ++c) color[c] += 0.6f * coverage[k] * rgb[k][c];
    }
    for (int c = 0; c < 3; ++c) {
      const float clamped = std::min(1.0f, std::max(0.0f, color[c]));
      out[c] = encode_[size_t(clamped * float(kEncodeSteps - 1) + 0.5f)];
    }
  }

 private:
  // An enumerator, not a static constexpr variable: reference_avx2.cpp compiles this header with
  // -fno-weak, which GCC cannot honour for an inline variable.
  enum : int { kEncodeSteps = 4096 };
  const Scene& scene_;
  const Light* light_ = nullptr;
  glm::vec3 directionalUnit_{0.0f};
  float directionalLength_ = 0.0f;
  const uint8_t* encode_ = nullptr;  // gamma 1/2.2 table: a pow per channel would cost more than the trace's shadows
};

}  // namespace shadowlab::reference_detail
