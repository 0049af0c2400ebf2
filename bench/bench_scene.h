#pragma once
// The rasterizer benches' scene: the bundled bunny at 1920x1080, with `copies` - 1 more bunnies
// beside it (~28k triangles each; 4 copies ~111k, the ~100k triangles of the brief's speed figures).
#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "shadowlab/scenes/loader.h"

namespace shadowlab::bench {

inline const Scene& benchScene(int copies) {
  static std::map<int, Scene> cache;
  auto it = cache.find(copies);
  if (it != cache.end()) return it->second;
  Scene s = loadScene(resolveScenePath("bunny"));
  s.camera.width = 1920;
  s.camera.height = 1080;
  if (copies > 1) {
    // Extra bunnies beside the first one, in view: ~28k triangles each.
    std::vector<Object> extra;
    glm::vec3 lo = s.boundsMin(), hi = s.boundsMax();
    float step = 0.35f * std::max(hi.x - lo.x, hi.z - lo.z);
    uint32_t nextId = 1000;
    for (const Object& o : s.objects) {
      if (o.triangles.size() < 10000) continue;  // the bunny, not the floor
      for (int c = 1; c < copies; ++c) {
        Object copy = o;
        copy.id = nextId++;
        copy.name = o.name + "_" + std::to_string(c);
        glm::vec3 offset((c % 2 ? 1.0f : -1.0f) * step * float((c + 1) / 2) * 0.5f, 0, -step * 0.3f * float(c));
        for (auto& p : copy.positions) p += offset;
        extra.push_back(copy);
      }
    }
    for (auto& o : extra) s.objects.push_back(std::move(o));
    s.hash = "bench-" + std::to_string(copies);
  }
  return cache.emplace(copies, std::move(s)).first->second;
}

}  // namespace shadowlab::bench
