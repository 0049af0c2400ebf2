#include "scene_gpu.h"

#include <algorithm>

#include "shadowlab/scenes/io.h"

namespace shadowlab::raster {

namespace {

struct MaterialGpu {
  uint32_t alphaOffset, width, height, flags;
  float cutoff, pad0, pad1, pad2;
};
struct ObjectGpu {
  uint32_t id, vertexBase, triangleBase, pad;
};

template <typename T>
vk::Buffer makeBuffer(const vk::Context& context, const std::vector<T>& data, VkBufferUsageFlags usage) {
  vk::Buffer b(context, data.size() * sizeof(T), usage);
  b.upload(data.data(), data.size() * sizeof(T));
  return b;
}

}  // namespace

std::string sceneKey(const Scene& scene) {
  if (!scene.hash.empty()) return scene.hash;
  uint64_t h = fnv1a64(nullptr, 0);
  for (const Object& o : scene.objects) {
    h = fnv1a64(o.positions.data(), o.positions.size() * sizeof(glm::vec3), h);
    h = fnv1a64(o.uvs.data(), o.uvs.size() * sizeof(glm::vec2), h);
    h = fnv1a64(o.triangles.data(), o.triangles.size() * sizeof(glm::uvec3), h);
    h = fnv1a64(o.triangleMaterial.data(), o.triangleMaterial.size() * sizeof(uint32_t), h);
    h = fnv1a64(&o.id, sizeof(o.id), h);
    h = fnv1a64(&o.castsShadow, sizeof(o.castsShadow), h);
  }
  for (const Material& m : scene.materials) {
    h = fnv1a64(&m.alphaCutoff, sizeof(float), h);
    h = fnv1a64(&m.twoSided, sizeof(bool), h);
    h = fnv1a64(&m.hasAlpha, sizeof(bool), h);
    h = fnv1a64(m.alphaTexture.pixels.data(), m.alphaTexture.pixels.size() * sizeof(float), h);
  }
  for (const Projector& p : scene.projectors)
    h = fnv1a64(p.image.pixels.data(), p.image.pixels.size() * sizeof(float), h);
  return "code-" + hashHex(h);
}

SceneGpu uploadScene(const vk::Context& context, const Scene& scene, const std::string& hash) {
  SceneGpu g;
  g.hash = hash;
  std::vector<float> vertices, positions;
  std::vector<uint32_t> indices, triangleMaterials;
  std::vector<ObjectGpu> objects;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    Draw d;
    d.objectIndex = uint32_t(i);
    d.firstIndex = uint32_t(indices.size());
    d.indexCount = uint32_t(o.triangles.size() * 3);
    d.vertexOffset = int32_t(positions.size() / 3);
    d.triangleBase = uint32_t(triangleMaterials.size());
    d.castsShadow = o.castsShadow;
    objects.push_back({o.id, uint32_t(d.vertexOffset), d.triangleBase, 0});
    for (size_t v = 0; v < o.positions.size(); ++v) {
      glm::vec2 uv = v < o.uvs.size() ? o.uvs[v] : glm::vec2(0);
      vertices.insert(vertices.end(), {o.positions[v].x, o.positions[v].y, o.positions[v].z, uv.x, uv.y});
      positions.insert(positions.end(), {o.positions[v].x, o.positions[v].y, o.positions[v].z});
    }
    d.allOneSided = !o.triangles.empty();
    for (size_t t = 0; t < o.triangles.size(); ++t) {
      indices.insert(indices.end(), {o.triangles[t].x, o.triangles[t].y, o.triangles[t].z});
      uint32_t mi = t < o.triangleMaterial.size() ? o.triangleMaterial[t] : 0u;
      triangleMaterials.push_back(mi);
      const Material* mat = mi < scene.materials.size() ? &scene.materials[mi] : nullptr;
      bool oneSided = mat && !mat->twoSided;
      d.hasAlpha = d.hasAlpha || (mat && mat->hasAlpha && mat->alphaTexture.width > 0);
      d.anyOneSided = d.anyOneSided || oneSided;
      d.allOneSided = d.allOneSided && oneSided;
    }
    if (d.indexCount > 0) g.draws.push_back(d);
  }
  // The resolve pass reads object 0 and its first triangle even for pixels without a hit.
  if (objects.empty()) objects.push_back({0, 0, 0, 0});
  while (positions.size() < 9) positions.push_back(0.0f);
  while (indices.size() < 3) indices.push_back(0u);
  std::vector<MaterialGpu> materials;
  std::vector<float> alpha;
  for (const Material& m : scene.materials) {
    MaterialGpu mg{};
    mg.flags = (m.twoSided ? 1u : 0u);
    mg.cutoff = m.alphaCutoff;
    if (m.hasAlpha && m.alphaTexture.width > 0 && m.alphaTexture.height > 0) {
      mg.flags |= 2u;
      mg.alphaOffset = uint32_t(alpha.size());
      mg.width = uint32_t(m.alphaTexture.width);
      mg.height = uint32_t(m.alphaTexture.height);
      const Image& img = m.alphaTexture;
      for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) alpha.push_back(img.at(x, y, img.channels - 1));
    }
    materials.push_back(mg);
  }
  if (materials.empty()) materials.push_back(MaterialGpu{0, 0, 0, 1u, 0.5f, 0, 0, 0});
  // Triangles that name a material beyond the table fall back to material 0.
  for (uint32_t& m : triangleMaterials)
    if (m >= materials.size()) m = 0;
  std::vector<float> projectorTexels;
  for (const Projector& p : scene.projectors) {
    ProjectorImage pi{int32_t(projectorTexels.size()), p.image.width, p.image.height};
    if (p.image.width <= 0 || p.image.height <= 0) {
      // No image: project white, so coverage still reads as light.
      pi.width = pi.height = 1;
      projectorTexels.insert(projectorTexels.end(), {1.0f, 1.0f, 1.0f});
    } else {
      for (int y = 0; y < p.image.height; ++y)
        for (int x = 0; x < p.image.width; ++x)
          for (int c = 0; c < 3; ++c)
            projectorTexels.push_back(p.image.at(x, y, std::min(c, p.image.channels - 1)));
    }
    g.projectors.push_back(pi);
  }
  const VkBufferUsageFlags ssbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  g.vertices = makeBuffer(context, vertices, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  g.indices = makeBuffer(context, indices, VK_BUFFER_USAGE_INDEX_BUFFER_BIT | ssbo);
  g.positions = makeBuffer(context, positions, ssbo);
  g.objects = makeBuffer(context, objects, ssbo);
  g.triangleMaterials = makeBuffer(context, triangleMaterials, ssbo);
  g.materials = makeBuffer(context, materials, ssbo);
  g.alphaTexels = makeBuffer(context, alpha, ssbo);
  g.projectorTexels = makeBuffer(context, projectorTexels, ssbo);
  return g;
}

}  // namespace shadowlab::raster
