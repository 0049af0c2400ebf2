// Camera paths for temporal stability (camera_path.h): dolly, orbit and keyframes.
#include "shadowlab/scenes/camera_path.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "shadowlab/scenes/error.h"

namespace shadowlab {

namespace {

void requireFrames(int frames, const char* what) {
  if (frames < 2 || frames > kMaxPathFrames)
    throw InputError(std::string(what) + ": error: frames is " + std::to_string(frames) + "; expected 2.." +
                     std::to_string(kMaxPathFrames) + " (a path needs a start and an end)");
}

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

std::string toString(CameraPathKind kind) {
  switch (kind) {
    case CameraPathKind::Dolly: return "dolly";
    case CameraPathKind::Orbit: return "orbit";
    case CameraPathKind::Keyframes: return "keyframes";
  }
  return "?";
}

std::string pathCameraProblem(const Camera& c) {
  if (!finite(c.position) || !finite(c.lookAt) || !finite(c.up)) return "its position, look_at or up is not finite";
  const glm::vec3 view = c.lookAt - c.position;
  // The scene camera's rules (loader.cpp readCamera), so a path frame is a camera the loader accepts.
  if (!(glm::length(view) > 1e-6f)) return "its look_at is its position (no view direction)";
  if (!(glm::length(c.up) > 1e-12f)) return "its up is zero";
  if (glm::length(glm::cross(glm::normalize(view), glm::normalize(c.up))) < 1e-4f)
    return "its up is parallel to the view direction";
  return "";
}

std::vector<Camera> dollyPath(const Camera& start, float distanceWorld, int frames) {
  requireFrames(frames, "dolly");
  glm::vec3 view = start.lookAt - start.position;
  float len = glm::length(view);
  if (!(len > 0.0f) || !std::isfinite(distanceWorld))
    throw InputError(
        "dolly: error: the camera has no view direction (position == look_at) or the distance is "
        "not finite; expected a camera that looks somewhere and a finite distance");
  glm::vec3 forward = view / len;
  std::vector<Camera> path;
  for (int k = 0; k < frames; ++k) {
    // Computed from the start each time (not accumulated), so the last frame lands on the end.
    float t = float(k) / float(frames - 1);
    Camera c = start;
    glm::vec3 offset = forward * (distanceWorld * t);
    c.position = start.position + offset;
    c.lookAt = start.lookAt + offset;
    path.push_back(c);
  }
  return path;
}

std::vector<Camera> orbitPath(const Camera& start, float angleDeg, int frames) {
  requireFrames(frames, "orbit");
  float upLen = glm::length(start.up);
  if (!(upLen > 0.0f) || !std::isfinite(angleDeg))
    throw InputError(
        "orbit: error: the camera's up vector is zero or the angle is not finite; expected a "
        "non-zero up and a finite angle");
  glm::vec3 axis = start.up / upLen;
  std::vector<Camera> path;
  for (int k = 0; k < frames; ++k) {
    float t = float(k) / float(frames - 1);
    glm::mat4 rot = glm::rotate(glm::mat4(1.0f), glm::radians(angleDeg * t), axis);
    Camera c = start;
    c.position = start.lookAt + glm::vec3(rot * glm::vec4(start.position - start.lookAt, 0.0f));
    path.push_back(c);
  }
  return path;
}

std::vector<Camera> keyframePath(const std::vector<Camera>& keys, int frames) {
  requireFrames(frames, "keyframes");
  if (keys.size() < 2)
    throw InputError("keyframes: error: got " + std::to_string(keys.size()) +
                     " keyframe(s); expected at least 2 (a start and an end)");
  const size_t intervals = keys.size() - 1;
  std::vector<Camera> path;
  for (int k = 0; k < frames; ++k) {
    // In double, so that frames landing on a keyframe (t integer) reproduce it exactly.
    const double t = double(k) * double(intervals) / double(frames - 1);
    const size_t i = std::min(size_t(t), intervals - 1);
    const double f = t - double(i);
    const Camera& a = keys[i];
    const Camera& b = keys[i + 1];
    auto mix = [f](glm::vec3 x, glm::vec3 y) { return glm::vec3(glm::dvec3(x) + (glm::dvec3(y) - glm::dvec3(x)) * f); };
    Camera c = a;
    c.position = f == 0.0 ? a.position : mix(a.position, b.position);
    c.lookAt = f == 0.0 ? a.lookAt : mix(a.lookAt, b.lookAt);
    c.up = f == 0.0 ? a.up : mix(a.up, b.up);
    if (glm::length(c.up) > 0.0f) c.up = glm::normalize(c.up);
    const std::string problem = pathCameraProblem(c);
    if (!problem.empty())
      throw InputError("keyframes: error: frame " + std::to_string(k) + " (between keyframes " + std::to_string(i) +
                       " and " + std::to_string(i + 1) + ") is degenerate: " + problem +
                       "; expected keyframes whose interpolation always looks somewhere");
    path.push_back(c);
  }
  return path;
}

std::vector<Camera> expandCameraPath(const Camera& start, const CameraPath& path, int frames) {
  const int n = frames > 0 ? frames : path.frames;
  switch (path.kind) {
    case CameraPathKind::Dolly: return dollyPath(start, path.distanceWorld, n);
    case CameraPathKind::Orbit: return orbitPath(start, path.angleDeg, n);
    case CameraPathKind::Keyframes: return keyframePath(path.keyframes, n);
  }
  throw InputError("camera path \"" + path.name + "\": error: unknown kind");
}

}  // namespace shadowlab
