#pragma once
// The scene both renderers draw. The loader (loader.h) resolves everything a renderer
// needs: every object is a world-space triangle mesh (procedural primitives are tessellated
// here, once, so the reference and the rasterizer see the very same triangles and the same
// primitive ids), materials carry their decoded alpha textures, projectors their images.
//
// Conventions (both renderers): right-handed world, y up. Camera pixel (i, j): i = column from
// the left, j = row from the top (row 0 is the top row); its ray passes through the pixel center
// (i + 0.5, j + 0.5). Image textures: texel (0, 0) is the top-left, u grows right, v grows down.
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "shadowlab/scenes/kinds.h"

namespace shadowlab {

// A decoded single- or multi-channel float image, row 0 at the top.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;  // width * height * channels, row-major, top row first
  float at(int x, int y, int c) const { return pixels[(size_t(y) * width + x) * channels + c]; }
};

struct Material {
  std::string name;
  bool twoSided = true;      // false: back faces (seen from the camera or light) are culled
  float alphaCutoff = 0.5f;  // texels with alpha < cutoff are holes (both renderers)
  bool hasAlpha = false;     // true when alphaTexture is loaded
  Image alphaTexture;        // 1 channel, alpha in [0, 1]; sampled NEAREST with REPEAT addressing
  glm::vec3 albedo{0.8f};    // only for readable pictures
};

// The alpha lookup both renderers use (nearest texel, repeat addressing), so that the
// reference and the rasterizer agree on which points are holes.
float sampleAlphaNearest(const Image& alpha, glm::vec2 uv);

struct Object {
  std::string name;
  uint32_t id = 0;                         // stable object id, >= 1 (0 means "nothing")
  std::vector<glm::vec3> positions;        // world space
  std::vector<glm::vec2> uvs;              // empty, or one per position
  std::vector<glm::uvec3> triangles;       // indices into positions; triangle index = primitive id
  std::vector<uint32_t> triangleMaterial;  // one per triangle, index into Scene::materials
  bool castsShadow = true;
};

enum class LightType { SHADOWLAB_LIGHT_TYPES(SHADOWLAB_ENUMERATOR) };
// Every light type, in code order (kinds.h's rows).
const std::vector<KindInfo<LightType>>& lightTypeKinds();

// The largest `angular_diameter_deg` a directional light takes (a 20-degree disc is already far
// softer than any sky light an engine models as one sun).
constexpr float kMaxAngularDiameterDeg = 20.0f;

struct Light {
  std::string name;
  LightType type = LightType::Directional;
  glm::vec3 direction{0, -1, 0};  // unit; the way the light travels (from the light into the scene)
  glm::vec3 position{0};          // spot and point lights, world space
  float coneDeg = 60.0f;          // spot: full apex angle; lit only where angle(p - position, direction) <= coneDeg / 2
  float nearPlane = 0.05f;        // spot and point: depth-map near plane, world units
  // Sized lights (0 = today's hard light, bit for bit). A sized light's visibility is the visible
  // fraction of the light as seen from the point (over its solid angle).
  float radius = 0.0f;              // spot and point: a sphere light of this radius around position, world units
  float angularDiameterDeg = 0.0f;  // directional: the full angle the light's disc subtends (the sun: about 0.53)
  bool sized() const { return radius > 0.0f || angularDiameterDeg > 0.0f; }
};

struct Projector {
  std::string name;
  glm::vec3 position{0};
  glm::vec3 direction{0, 0, -1};  // unit
  glm::vec3 up{0, 1, 0};
  float fovDeg = 45.0f;  // vertical
  float aspect = 1.0f;   // width / height
  float nearPlane = 0.1f;
  float farPlane = 100.0f;
  Image image;  // RGB (3 channels), sampled NEAREST at (u, v) in [0,1]^2, v = 0 at the image's top row
  // Projective texture matrix: world -> (u*w, v*w, depth*w, w), u,v in [0,1] inside the frustum,
  // depth in [0,1] from near to far (Vulkan depth range), v = 0 at the top. Points with w <= 0
  // are behind the projector (reverse projection).
  glm::mat4 texFromWorld() const;
};

// How a camera projects (scenes/FORMAT.md "camera"): rays from one point (perspective) or parallel
// rays along the view direction from the points of a plane (orthographic).
enum class Projection { Perspective, Orthographic };

struct Camera {
  glm::vec3 position{0, 1, 5};
  glm::vec3 lookAt{0};
  glm::vec3 up{0, 1, 0};
  Projection projection = Projection::Perspective;
  float vfovDeg = 45.0f;     // perspective: vertical field of view, degrees
  float orthoHeight = 0.0f;  // orthographic: the view's height in world units (glTF: 2 ymag); width = height W / H
  int width = 640;
  int height = 480;
  float nearPlane = 0.01f;          // rasterizer only
  float farPlane = 1000.0f;         // rasterizer only
  glm::mat4 viewFromWorld() const;  // right-handed look-at, camera looks down -z
  // Vulkan clip space (y down, depth 0..1), so pixel (i, j) centers match rayDirection(i, j).
  glm::mat4 clipFromView() const;
  // Unit world-space direction through the point (x, y) of the image plane, in pixels
  // (x = i + 0.5, y = j + 0.5 is the center of pixel (i, j)). Computes the camera's basis on every
  // call; a loop over pixels uses CameraRays, which gives the same bits.
  glm::vec3 rayDirection(float x, float y) const;
  // Where that ray starts: the camera position (perspective), or the point (x, y) of the image
  // plane through the position (orthographic). CameraRays::origin gives the same bits.
  glm::vec3 rayOrigin(float x, float y) const;
  bool orthographic() const { return projection == Projection::Orthographic; }
  // The frames' "camera_hash": hashHex(fnv1a64) over the packed bytes of position.xyz, lookAt.xyz,
  // up.xyz, vfovDeg (10 float32) then width, height (2 int32), and for an orthographic camera
  // orthoHeight (1 float32) after them: exactly the fields that decide which ray each pixel casts.
  // One definition, so compare can match a reference and a raster frame.
  std::string hash() const;
};

// Camera::rayDirection with the camera's basis computed once: CameraRays(camera).direction(x, y) ==
// camera.rayDirection(x, y) bit for bit (rayDirection is defined through it), at a fraction of the
// cost (the basis needs two normalizations and a tangent).
class CameraRays {
 public:
  explicit CameraRays(const Camera& camera);
  glm::vec3 direction(float x, float y) const;
  glm::vec3 origin(float x, float y) const;  // Camera::rayOrigin
  // A perspective camera's direction(x, y) over the lanes of D: double (what direction itself
  // runs), or a std::experimental::simd of double, which gives a packet's rays in a few vector
  // operations instead of a division and a square root per ray in turn. The same IEEE operations in
  // the same order in every instantiation, so each lane has direction's bits (where no compilation
  // fuses a multiply and an add: shadowlab_scenes and shadowlab_reference are built with
  // -ffp-contract=off). out[a] holds the double result before its rounding to float.
  template <class D>
  void perspectiveDirection(const D& x, const D& y, D (&out)[3]) const {
    using std::sqrt;
    const D ndcX = 2.0 * x / double(width_) - 1.0;
    const D ndcY = 2.0 * y / double(height_) - 1.0;
    const D across = ndcX * aspect_ * tanHalfFov_, down = ndcY * tanHalfFov_;
    for (int a = 0; a < 3; ++a) out[a] = (forward_[a] + across * right_[a]) - down * trueUp_[a];
    const D inverseLength = 1.0 / sqrt((out[0] * out[0] + out[1] * out[1]) + out[2] * out[2]);
    for (int a = 0; a < 3; ++a) out[a] = out[a] * inverseLength;
  }

 private:
  glm::dvec3 position_, forward_, right_, trueUp_;
  double tanHalfFov_, aspect_;
  double halfHeight_;  // orthographic: half the view's height, world units; 0: perspective
  int width_, height_;
};

// A named camera path declared in the scene file ("paths", scenes/FORMAT.md), expanded by
// expandCameraPath (camera_path.h) for `shadowlab stability SCENE --path NAME`.
enum class CameraPathKind { Dolly, Orbit, Keyframes };

struct CameraPath {
  std::string name;
  CameraPathKind kind = CameraPathKind::Dolly;
  int frames = 0;                 // 2..kMaxPathFrames
  float distanceWorld = 0.0f;     // dolly: total travel along the view direction, world units
  float angleDeg = 0.0f;          // orbit: total rotation about look_at, degrees
  std::vector<Camera> keyframes;  // keyframes: >= 2 cameras (the scene camera's other fields)
};
std::string toString(CameraPathKind kind);  // "dolly", "orbit", "keyframes"

struct Scene {
  std::string path;  // the scene file as given
  std::string name;  // file stem, e.g. "sphere_on_plane"
  std::string hash;  // 16 hex digits over the resolved content (JSON + geometry + textures)
  // The scene: values it was loaded with (loadScene's overrides): JSON pointer and the value as
  // JSON text, in the order given. An adapter that loads the scene itself (adapters/README.md,
  // source_scene) applies them again.
  std::vector<std::pair<std::string, std::string>> overridesGiven;
  Camera camera;
  std::vector<Material> materials;  // index 0 is the default material
  std::vector<Object> objects;
  std::vector<Light> lights;
  std::vector<Projector> projectors;
  // The scene parameter that provokes this scene's failure, if declared ("failure" in the file):
  // a JSON pointer into the scene file and the values to sweep.
  std::string failurePointer;
  std::vector<double> failureValues;
  std::vector<CameraPath> paths;  // "paths" in the file, sorted by name

  // World-space axis-aligned bounds of all objects.
  glm::vec3 boundsMin() const;
  glm::vec3 boundsMax() const;
  const Light* findLight(const std::string& name) const;  // nullptr when absent
  // The light a command renders and compares when none is named: `name` when given, else the
  // first light's name ("" when the scene has no light). Every renderer and comparison uses this
  // one choice, so the compared light is always the rendered one.
  std::string lightOrDefault(const std::string& name) const;
  const CameraPath* findPath(const std::string& name) const;  // nullptr when absent
  size_t triangleCount() const;
};

}  // namespace shadowlab
