#pragma once
// glTF 2.0 files (.gltf, .glb) as scene content: the meshes of one glTF scene flattened into one
// world-space triangle mesh (with the nodes' shadowlab objects marked in it, for a file that
// `shadowlab export` wrote: Part), its MASK materials as alpha-tested Materials, its KHR_lights_punctual
// lights and its cameras, converted into the structures of scene.h so that neither renderer knows
// glTF exists. The mapping table is scenes/FORMAT.md ("glTF files"). Parsing is tinygltf's
// (Debian's libtinygltf-dev, compiled in gltf_tinygltf.cpp without image decoding); this file's
// code checks what tinygltf lets through (types, ranges, cycles, non-finite values) and names the
// file and the JSON pointer or accessor of every problem. Internal to shadowlab_scenes.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "shadowlab/scenes/loader.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab::gltf {

// True for a path ending in .gltf or .glb (any case): such a path is a scene by itself.
bool isGltfPath(const std::string& path);

// "" for a regular file (after symbolic links); else what `path` is, for a message: "not found",
// "a directory, not a file", "a character device, not a regular file", ...
std::string notARegularFile(const std::filesystem::path& path);

struct Request {
  std::string path;                      // the .gltf / .glb file
  int sceneIndex = -1;                   // glTF scene; -1: the file's "scene", else scene 0
  std::string cameraName;                // a glTF camera by name, or
  int cameraIndex = -1;                  // by index into "cameras"; both unset: the first instanced camera
  std::string objectName;                // prefix of the materials this file adds ("<object>/<material>")
  uint32_t fallbackMaterial = 0;         // what OPAQUE double-sided primitives draw with
  std::vector<SceneOverride> overrides;  // JSON pointers into the glTF document (a glTF path as a scene)
  uint64_t triangleBudget = ~0ull;       // more triangles than this is an error (the scene's limit)
  std::string budgetWhy;                 // the reason, for that error
  // Where the request was made (the scene file and the JSON pointer of the object), for errors
  // about the request itself: a scene or camera the file does not have.
  std::string requestFile;
  std::string requestPtr;
};

// A mesh node that says which shadowlab object it is (extras.shadowlab.object, written by
// exportGlb): a glTF path loaded as the scene becomes one object per such node (loader.cpp).
struct Part {
  std::string name;  // the node's name (sanitized)
  uint32_t id = 0;   // 1..2^24-1
  bool castsShadow = true;
  size_t firstVertex = 0, vertexCount = 0;      // in Content::positions (and uvs)
  size_t firstTriangle = 0, triangleCount = 0;  // in Content::triangles
};

struct Content {
  // The flattened mesh in the glTF scene's world space (node transforms applied).
  std::vector<glm::vec3> positions;
  std::vector<glm::vec2> uvs;  // empty unless a MASK material reads a texture; then one per position
  std::vector<glm::uvec3> triangles;
  std::vector<uint32_t> triangleMaterial;  // indices into the scene's materials (appended by load)
  std::vector<Light> lights;               // KHR_lights_punctual instances, world space
  bool hasCamera = false;                  // a camera was found (or chosen)
  int cameraIndex = -1;                    // which one (into the file's "cameras")
  Camera camera;                           // width 640, height from aspectRatio (480 without)
  bool infiniteFar = false;                // no zfar: the caller sets farPlane from the scene's bounds
  bool cameraExact = false;                // the camera is extras.shadowlab.camera's, bit for bit
  std::vector<Part> parts;                 // empty unless every mesh node carries extras.shadowlab.object
  std::vector<bool> lightExact;            // per light: direction and position from extras.shadowlab.light
  std::vector<std::string> lightRadiusPtr;  // per light: the JSON pointer of its radius ("" without one)
  std::vector<std::string> warnings;       // GCC-style "file: warning: ..." lines
  uint64_t hash = 0;                       // FNV-1a over the (overridden) glTF JSON and the buffers read
};

// Loads `request.path`, appending the materials it needs to `materials`. Throws InputError naming
// the file and the JSON pointer (or accessor) of the problem.
Content load(const Request& request, std::vector<Material>& materials);

// A name made of letters, digits, '_' and '-' (the scene's names become channel names).
std::string sanitizeName(const std::string& name);

// The camera a scene without one gets: it looks at the bounds' center from above and in front
// (direction (0.6, 0.5, 1) normalized), far enough for the bounding sphere to fill 90% of a 45
// degree field of view, 640x480, near and far planes around the sphere.
Camera framingCamera(glm::vec3 boundsMin, glm::vec3 boundsMax);

}  // namespace shadowlab::gltf
