#pragma once
// The scene as the GPU sees it: one interleaved vertex buffer (position, uv), one index buffer
// with per-object local indices, and the tables the shaders read (triangle materials, material
// alpha textures, the triangle and object tables of the resolve pass, projector images).
// The resolve pass reads its per-pixel tables through texel buffers (texelFetch): on lavapipe a
// storage-buffer load at a per-pixel address is a bounds-checked loop over the SIMD lanes, a
// texel fetch one gather.
// Uploaded once per scene hash and reused across a sweep.
#include <cstdint>
#include <string>
#include <vector>

#include "shadowlab/scenes/scene.h"
#include "vk/buffer.h"
#include "vk/handle.h"

namespace shadowlab::raster {

struct Draw {
  uint32_t objectIndex = 0;
  uint32_t firstIndex = 0;
  uint32_t indexCount = 0;
  int32_t vertexOffset = 0;
  uint32_t triangleBase = 0;
  bool castsShadow = true;
  bool hasAlpha = false;     // some triangle's material is alpha-tested
  bool anyOneSided = false;  // some triangle's material culls its back faces
  bool allOneSided = false;  // every triangle's material culls its back faces
};

struct ProjectorImage {
  int32_t firstTexel = 0;  // index of its first float in the projector texel table
  int32_t width = 0;
  int32_t height = 0;
};

struct SceneGpu {
  std::string hash;
  std::vector<Draw> draws;
  std::vector<ProjectorImage> projectors;
  std::vector<uint32_t> objectIds;           // Object::id by object index
  std::vector<uint32_t> objectTriangleBase;  // first global triangle index by object index
  std::vector<uint32_t> triangleObject;      // object index by global triangle index
  vk::Buffer vertices;                       // vec3 position + vec2 uv per vertex
  vk::Buffer indices;                        // uint32 local indices
  // resolve: one RGBA32F texel per triangle (triangle t at texel t + 1, texel 0 a placeholder), its plane relative to
  // the camera: (n, dot(n, v0 - o)), n the unit normal (v1 - v0) x (v2 - v0), o = planesOrigin (updatePlanes).
  vk::Buffer trianglePlanes;
  vk::BufferView trianglePlanesView;
  glm::dvec3 planesOrigin{0.0};
  bool planesValid = false;
  std::vector<glm::vec3> triangleVertices;  // host: 3 per triangle, world space
  vk::Buffer triangleMaterials;             // uint per triangle
  vk::Buffer materials;                     // MaterialGpu per material
  vk::Buffer alphaTexels;                   // all alpha textures, float
  vk::Buffer projectorTexels;               // all projector images, RGB float
};

SceneGpu uploadScene(const vk::Context& context, const Scene& scene, const std::string& hash);
// Fills trianglePlanes for a camera at `origin` (in double; a no-op when it already is).
void updatePlanes(SceneGpu& scene, glm::dvec3 origin);

// The scene's content hash (Scene::hash, or one computed over the geometry when the scene was
// built in code and has none).
std::string sceneKey(const Scene& scene);

}  // namespace shadowlab::raster
