#include "shadowlab/raster/lispsm.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "shadowlab/raster/cascades.h"

namespace shadowlab::raster {

std::vector<glm::dvec3> viewBoxIntersection(const Camera& camera, glm::vec3 boxMin, glm::vec3 boxMax) {
  // Half-spaces a . p <= b in camera space (looking down -z).
  struct Plane {
    glm::dvec3 a;
    double b;
  };
  ViewDepthRange own = cameraDepthRange(camera);
  double tanY = std::tan(0.5 * glm::radians(double(camera.vfovDeg)));
  double tanX = tanY * double(camera.width) / double(std::max(camera.height, 1));
  glm::dmat4 viewFromWorld(camera.viewFromWorld());
  glm::dmat3 rotation(viewFromWorld);
  glm::dvec3 eye(camera.position);
  std::vector<Plane> planes = {{{1, 0, tanX}, 0.0},
                               {{-1, 0, tanX}, 0.0},
                               {{0, 1, tanY}, 0.0},
                               {{0, -1, tanY}, 0.0},
                               {{0, 0, 1}, -double(own.nearView)},
                               {{0, 0, -1}, double(own.farView)}};
  // Box face x_i <= hi_i (and -x_i <= -lo_i) in world: with p_world = R^T p_camera + eye,
  // (R e) . p_camera <= hi_i - e . eye.
  for (int i = 0; i < 3; ++i) {
    glm::dvec3 e(0.0);
    e[i] = 1.0;
    planes.push_back({rotation * e, double(boxMax[i]) - eye[i]});
    planes.push_back({-(rotation * e), eye[i] - double(boxMin[i])});
  }
  double scale = double(own.farView);
  for (int i = 0; i < 3; ++i)
    scale = std::max({scale, std::abs(double(boxMin[i]) - eye[i]), std::abs(double(boxMax[i]) - eye[i])});
  for (Plane& p : planes) {
    double len = glm::length(p.a);
    p.a /= len;
    p.b /= len;
  }
  const double tolerance = 1e-9 * scale;
  std::vector<glm::dvec3> out;
  const size_t count = planes.size();
  for (size_t i = 0; i < count; ++i)
    for (size_t j = i + 1; j < count; ++j)
      for (size_t k = j + 1; k < count; ++k) {
        glm::dmat3 m = glm::transpose(glm::dmat3(planes[i].a, planes[j].a, planes[k].a));  // rows: the normals
        double det = glm::determinant(m);
        if (!(std::abs(det) > 1e-9)) continue;  // two of the planes (nearly) parallel: no single point
        glm::dvec3 p = glm::inverse(m) * glm::dvec3(planes[i].b, planes[j].b, planes[k].b);
        bool inside = true;
        for (const Plane& q : planes) inside = inside && glm::dot(q.a, p) <= q.b + tolerance;
        if (inside) out.push_back(glm::transpose(rotation) * p + eye);
      }
  return out;
}

LispsmBasis lispsmBasis(const glm::mat4& lightViewFromWorld, glm::vec3 viewForwardWorld) {
  glm::dmat4 lightView(lightViewFromWorld);
  glm::dvec3 f = glm::dmat3(lightView) * glm::dvec3(viewForwardWorld);
  double len = glm::length(f);
  LispsmBasis out;
  out.lightFromWorld = lightView;
  if (!(len > 0.0) || !std::isfinite(len)) return out;
  f /= len;
  double sinGamma = std::hypot(f.x, f.y);
  if (!(sinGamma > 0.0)) return out;
  // New y: the projected view direction; new x = y' x z (right-handed, z unchanged).
  double ax = f.x / sinGamma, ay = f.y / sinGamma;
  glm::dmat4 rotate(1.0);  // glm: m[column][row]; rows are the new axes in the old frame
  rotate[0][0] = ay;
  rotate[1][0] = -ax;
  rotate[0][1] = ax;
  rotate[1][1] = ay;
  out.lightFromWorld = rotate * lightView;
  out.sinGamma = std::min(sinGamma, 1.0);
  return out;
}

double lispsmInverseNear(double zNear, double zFar, double sinGamma, double nScale) {
  if (!(sinGamma > 0.0) || !(zNear > 0.0) || !(zFar >= zNear) || !(nScale > 0.0) || !std::isfinite(zFar) ||
      !std::isfinite(nScale))
    return 0.0;
  double nOpt = (zNear + std::sqrt(zNear * zFar)) / std::min(sinGamma, 1.0);
  double inverse = 1.0 / (nScale * nOpt);
  return std::isfinite(inverse) ? inverse : 0.0;
}

LispsmMap lispsmTexFromLight(glm::dvec3 bodyMin, glm::dvec3 bodyMax, double eyeX, double inverseNear, int mapSize) {
  // A body with no extent would make the fit singular: give every side at least a hair.
  const double kMinSide = 1e-9;
  double rho = std::isfinite(inverseNear) && inverseNear > 0.0 ? inverseNear : 0.0;
  double x0 = bodyMin.x, y0 = bodyMin.y, z0 = bodyMin.z;
  double x1 = std::max(bodyMax.x, x0 + kMinSide), y1 = std::max(bodyMax.y, y0 + kMinSide),
         z1 = std::max(bodyMax.z, z0 + kMinSide);
  if (!std::isfinite(eyeX)) eyeX = 0.5 * (x0 + x1);
  double d = y1 - y0, h = z1 - z0;
  // X = (x - eyeX) / w is linear-fractional: its extremes over the box are at the corners.
  double xMin = std::numeric_limits<double>::infinity(), xMax = -xMin;
  for (double x : {x0, x1})
    for (double y : {y0, y1}) {
      double X = (x - eyeX) / (1.0 + rho * (y - y0));
      xMin = std::min(xMin, X);
      xMax = std::max(xMax, X);
    }
  double dX = std::max(xMax - xMin, kMinSide);
  glm::dmat4 m(0.0);  // glm: m[column][row]
  // w = 1 + rho (y - y0)
  m[1][3] = rho;
  m[3][3] = 1.0 - rho * y0;
  // u w = ((x - eyeX) - xMin w) / dX
  m[0][0] = 1.0 / dX;
  m[1][0] = -xMin * rho / dX;
  m[3][0] = (-eyeX - xMin * (1.0 - rho * y0)) / dX;
  // v w = (y1 - y) / d
  m[1][1] = -1.0 / d;
  m[3][1] = y1 / d;
  // depth w = (z1 - z) / h
  m[2][2] = -1.0 / h;
  m[3][2] = z1 / h;
  LispsmMap out;
  out.texFromLight = m;
  out.texelWorldPerW = std::max(dX, d) / double(std::max(mapSize, 1));
  return out;
}

}  // namespace shadowlab::raster
