#include "scene_gpu.h"

#include <algorithm>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "vk/check.h"

namespace shadowlab::raster {

namespace {

struct MaterialGpu {
  uint32_t alphaOffset, width, height, flags;
  float cutoff, pad0, pad1, pad2;
};

template <typename T>
vk::Buffer makeBuffer(const vk::Context& context, const std::vector<T>& data, VkBufferUsageFlags usage) {
  vk::Buffer b(context, data.size() * sizeof(T), usage);
  b.upload(data.data(), data.size() * sizeof(T));
  return b;
}

vk::BufferView makeView(const vk::Context& context, const vk::Buffer& buffer, VkFormat format) {
  VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  info.buffer = buffer.get();
  info.format = format;
  info.range = VK_WHOLE_SIZE;
  VkBufferView view;
  VK_CHECK(vkCreateBufferView(context.device(), &info, nullptr, &view));
  return vk::BufferView(context.device(), view);
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
  std::vector<float> vertices;
  std::vector<uint32_t> indices, triangleMaterials;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    Draw d;
    d.objectIndex = uint32_t(i);
    d.firstIndex = uint32_t(indices.size());
    d.indexCount = uint32_t(o.triangles.size() * 3);
    d.vertexOffset = int32_t(vertices.size() / 5);
    d.triangleBase = uint32_t(triangleMaterials.size());
    d.castsShadow = o.castsShadow;
    g.objectIds.push_back(o.id);
    g.objectTriangleBase.push_back(d.triangleBase);
    for (size_t v = 0; v < o.positions.size(); ++v) {
      glm::vec2 uv = v < o.uvs.size() ? o.uvs[v] : glm::vec2(0);
      vertices.insert(vertices.end(), {o.positions[v].x, o.positions[v].y, o.positions[v].z, uv.x, uv.y});
    }
    d.allOneSided = !o.triangles.empty();
    for (size_t t = 0; t < o.triangles.size(); ++t) {
      indices.insert(indices.end(), {o.triangles[t].x, o.triangles[t].y, o.triangles[t].z});
      for (int k = 0; k < 3; ++k) g.triangleVertices.push_back(o.positions[o.triangles[t][k]]);
      g.triangleObject.push_back(uint32_t(i));
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
          for (int c = 0; c < 3; ++c) projectorTexels.push_back(p.image.at(x, y, std::min(c, p.image.channels - 1)));
    }
    g.projectors.push_back(pi);
  }
  const VkBufferUsageFlags ssbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  g.vertices = makeBuffer(context, vertices, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  g.indices = makeBuffer(context, indices, VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
  // Ids (global triangle + 1) travel as floats through the resolve pass (occluder), exact up to
  // 2^24; the plane table is a texel buffer with one extra texel.
  size_t triangles = g.triangleVertices.size() / 3;
  size_t limit = std::min<size_t>((size_t(1) << 24) - 1, context.properties().limits.maxTexelBufferElements - 1);
  if (triangles > limit)
    throw InputError(
        formatError(scene.path.empty() ? scene.name : scene.path, "/objects",
                    std::to_string(triangles) + " triangles; the rasterizer takes at most " + std::to_string(limit)));
  // Texel 0 is a placeholder plane for pixels without a hit (id 0); triangle t is texel t + 1.
  g.trianglePlanes = vk::Buffer(context, (triangles + 1) * sizeof(glm::vec4), VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT);
  g.trianglePlanesView = makeView(context, g.trianglePlanes, VK_FORMAT_R32G32B32A32_SFLOAT);
  g.triangleMaterials = makeBuffer(context, triangleMaterials, ssbo);
  g.materials = makeBuffer(context, materials, ssbo);
  g.alphaTexels = makeBuffer(context, alpha, ssbo);
  g.projectorTexels = makeBuffer(context, projectorTexels, ssbo);
  return g;
}

void updatePlanes(SceneGpu& g, glm::dvec3 origin) {
  if (g.planesValid && g.planesOrigin == origin) return;
  size_t triangles = g.triangleVertices.size() / 3;
  auto* out = static_cast<glm::vec4*>(g.trianglePlanes.mapped()) + 1;
  out[-1] = glm::vec4(0.0f, 0.0f, 1.0f, 1.0f);
  for (size_t t = 0; t < triangles; ++t) {
    glm::dvec3 v0(g.triangleVertices[3 * t]), v1(g.triangleVertices[3 * t + 1]), v2(g.triangleVertices[3 * t + 2]);
    glm::dvec3 n = glm::cross(v1 - v0, v2 - v0);
    double len = glm::length(n);
    // A degenerate triangle covers no pixel; any finite plane will do.
    n = len > 0.0 ? n / len : glm::dvec3(0.0, 0.0, 1.0);
    out[t] = glm::vec4(glm::vec3(n), float(glm::dot(n, v0 - origin)));
  }
  g.planesOrigin = origin;
  g.planesValid = true;
}

}  // namespace shadowlab::raster
