// rasterPicture: the material's grey albedo, darkened where the rendered light is blocked,
// projector colours added where covered; the same look as referencePicture.
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "shadowlab/raster/raster.h"

namespace shadowlab {

std::vector<uint8_t> rasterPicture(const Scene& scene, const Frame& frame) {
  size_t n = frame.pixelCount();
  std::vector<uint8_t> rgb(n * 3);
  std::unordered_map<uint32_t, const Object*> byId;
  for (const Object& o : scene.objects) byId[o.id] = &o;
  std::string light = frame.meta.value("light", std::string());
  const std::vector<float>* vis = nullptr;
  if (!light.empty() && frame.has("light." + light + ".vis")) vis = &frame.get("light." + light + ".vis");
  const std::vector<float>& hit = frame.get("hit");
  const std::vector<float>& objectId = frame.get("object_id");
  const std::vector<float>& primId = frame.get("prim_id");
  struct ProjectorPlanes {
    const std::vector<float>*coverage, *r, *g, *b;
  };
  std::vector<ProjectorPlanes> projectors;
  for (const Projector& p : scene.projectors) {
    std::string k = "proj." + p.name + ".";
    if (frame.has(k + "coverage"))
      projectors.push_back({&frame.get(k + "coverage"), &frame.get(k + "R"), &frame.get(k + "G"), &frame.get(k + "B")});
  }
  auto toByte = [](float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return uint8_t(std::lround(std::pow(v, 1.0f / 2.2f) * 255.0f));  // sRGB-ish
  };
  for (size_t i = 0; i < n; ++i) {
    glm::vec3 c(0.02f, 0.03f, 0.08f);  // background: dark blue
    if (hit[i] > 0.5f) {
      glm::vec3 albedo(0.7f);
      auto it = byId.find(uint32_t(objectId[i]));
      if (it != byId.end()) {
        const Object& o = *it->second;
        size_t prim = size_t(primId[i]);
        uint32_t m = prim < o.triangleMaterial.size() ? o.triangleMaterial[prim] : 0;
        if (m < scene.materials.size()) albedo = scene.materials[m].albedo;
      }
      float v = vis ? (*vis)[i] : 1.0f;
      c = albedo * (0.15f + 0.85f * v);
      // The frame has no normals: outline where the visible object changes, so shapes read.
      size_t x = i % size_t(frame.width), y = i / size_t(frame.width);
      bool edge = (x + 1 < size_t(frame.width) && objectId[i + 1] != objectId[i]) ||
                  (y + 1 < size_t(frame.height) && objectId[i + size_t(frame.width)] != objectId[i]);
      if (edge) c *= 0.5f;
      for (auto& p : projectors) c += 0.6f * (*p.coverage)[i] * glm::vec3((*p.r)[i], (*p.g)[i], (*p.b)[i]);
    }
    rgb[3 * i] = toByte(c.r);
    rgb[3 * i + 1] = toByte(c.g);
    rgb[3 * i + 2] = toByte(c.b);
  }
  return rgb;
}

}  // namespace shadowlab
