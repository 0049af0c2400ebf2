#pragma once
// Camera paths: the fit camera's motion for temporal stability (shadowlab/compare/stability.h,
// `shadowlab stability`). Generated (`--path dolly|orbit`) or declared in a scene file ("paths",
// scenes/FORMAT.md). Pure functions; every one returns `frames` cameras (2 <= frames <=
// kMaxPathFrames) and copies everything but position, look_at and up from its start camera.
#include <string>
#include <vector>

#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// A path longer than this is a mistake, not a measurement.
inline constexpr int kMaxPathFrames = 1024;

// dolly: position and lookAt both move by distanceWorld * k / (frames - 1) along the unit view
// direction normalize(lookAt - position) (negative: backwards), so the view direction is
// constant. Frame 0 is `start` exactly, frame frames-1 the end; steps are equal.
std::vector<Camera> dollyPath(const Camera& start, float distanceWorld, int frames);
// orbit: position rotates about the axis through lookAt along start.up (normalized) by
// angleDeg * k / (frames - 1) degrees (right-handed: positive is counter-clockwise seen from
// above); lookAt stays, so the camera keeps looking at the same point.
std::vector<Camera> orbitPath(const Camera& start, float angleDeg, int frames);
// keyframes: piecewise linear through keys (>= 2) at equal parameter steps: frame k sits at
// t = k (K - 1) / (frames - 1) keyframe intervals, position, lookAt and up interpolated linearly
// between keys floor(t) and floor(t) + 1 (up renormalized). With frames = K (or (frames - 1) a
// multiple of (K - 1)) the keyframes are frames exactly. Throws InputError naming the frame when
// an interpolated camera is degenerate (see pathCameraProblem).
std::vector<Camera> keyframePath(const std::vector<Camera>& keys, int frames);

// The cameras of a declared path (Scene::paths) with `frames` frames (0: the path's own count),
// starting from `start` (the scene camera) for dolly and orbit.
std::vector<Camera> expandCameraPath(const Camera& start, const CameraPath& path, int frames = 0);

// Why a camera cannot be a path frame ("" when it can): position == lookAt, a zero up, an up
// parallel to the view direction, or non-finite coordinates. The same rules as the scene camera.
std::string pathCameraProblem(const Camera& camera);

}  // namespace shadowlab
