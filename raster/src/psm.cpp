#include "shadowlab/raster/psm.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

namespace shadowlab::raster {

namespace {

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// Sets row `row` of m (glm: m[column][row]) to (xyz, w).
void setRow(glm::dmat4& m, int row, glm::dvec3 xyz, double w) {
  m[0][row] = xyz.x;
  m[1][row] = xyz.y;
  m[2][row] = xyz.z;
  m[3][row] = w;
}

}  // namespace

const char* toString(PsmLight kind) {
  switch (kind) {
    case PsmLight::Directional: return "directional";
    case PsmLight::Source: return "source";
    case PsmLight::Sink: return "sink";
  }
  return "?";
}

PsmCamera psmVirtualCamera(const Camera& camera, double zNear, double zFar, double zCasterMin, double zCasterMax,
                           double slideBack) {
  zNear = std::isfinite(zNear) ? std::max(zNear, 1e-4) : 1e-4;
  if (!(zFar >= zNear)) zFar = zNear;
  if (!std::isfinite(zCasterMin) || zCasterMin > zNear) zCasterMin = zNear;
  if (!(zCasterMax >= zFar)) zCasterMax = zFar;
  if (!(slideBack >= 0.0) || !std::isfinite(slideBack)) slideBack = 0.0;
  PsmCamera out;
  out.slide = std::max(0.0, zNear - zCasterMin) + slideBack * (zFar - zNear);
  out.nearView = zCasterMin + out.slide;  // >= zNear > 0
  out.farView = std::max(zCasterMax + out.slide, out.nearView * (1.0 + 1e-6) + 1e-9);
  glm::dvec3 eye(camera.position), target(camera.lookAt);
  glm::dvec3 forward = glm::normalize(target - eye);
  glm::dvec3 virtualEye = eye - out.slide * forward;
  glm::dmat4 viewFromWorld = glm::lookAt(virtualEye, virtualEye + forward, glm::dvec3(camera.up));
  double cot = 1.0 / std::tan(0.5 * glm::radians(double(camera.vfovDeg)));
  double aspect = double(camera.width) / double(std::max(camera.height, 1));
  double n = out.nearView, f = out.farView;
  glm::dmat4 clipFromView(0.0);  // glm: m[column][row]
  clipFromView[0][0] = cot / aspect;
  clipFromView[1][1] = cot;
  clipFromView[2][2] = -(f + n) / (f - n);
  clipFromView[3][2] = -2.0 * f * n / (f - n);
  clipFromView[2][3] = -1.0;
  out.clipFromWorld = clipFromView * viewFromWorld;
  return out;
}

PsmMap psmTexFromClip(glm::dvec4 lightClip, const std::vector<glm::dvec4>& visibleClip,
                      const std::vector<glm::dvec4>& casterClip) {
  PsmMap out;
  if (visibleClip.empty()) return out;
  std::vector<glm::dvec3> visible, all;
  for (const glm::dvec4& c : visibleClip) {
    if (!(c.w > 0.0)) return out;
    visible.push_back(glm::dvec3(c) / c.w);
  }
  all = visible;
  for (const glm::dvec4& c : casterClip) {
    if (!(c.w > 0.0)) return out;
    all.push_back(glm::dvec3(c) / c.w);
  }
  const glm::dvec3 C(lightClip);
  const double Cw = lightClip.w, lenC = glm::length(C);
  if (!(lenC > 0.0) || !std::isfinite(lenC) || !std::isfinite(Cw)) return out;
  // C.w at the rounding level of C.xyz: the light perpendicular to the view, directional in PPS.
  const bool directional = std::abs(Cw) <= 1e-12 * lenC;
  const double sigma = Cw < 0.0 && !directional ? -1.0 : 1.0;
  const double absW = directional ? 0.0 : std::abs(Cw);
  out.light = directional ? PsmLight::Directional : (sigma > 0 ? PsmLight::Source : PsmLight::Sink);

  double inf = std::numeric_limits<double>::infinity();
  glm::dvec3 lo(inf), hi(-inf);
  for (const glm::dvec3& q : visible) lo = glm::min(lo, q), hi = glm::max(hi, q);
  // The point the light's frustum looks at: on the view axis (the unit cube's center in x, y, as
  // in the paper), at the visible body's middle depth. A light along the view axis then looks
  // straight down it: its image plane is parallel to the infinity plane and the map is
  // orthographic (warp 0), the fallback's case.
  const glm::dvec3 center(0.0, 0.0, 0.5 * (lo.z + hi.z));
  double scale = 0;
  for (const glm::dvec3& q : all) scale = std::max(scale, glm::length(q));
  // z'(q) = |C.w| a.q - sigma a.C: the distance from c along a, times |C.w| (for C.w = 0: -a.C).
  auto zPrime = [&](glm::dvec3 a, glm::dvec3 q) { return absW * glm::dot(a, q) - sigma * glm::dot(a, C); };
  auto holds = [&](glm::dvec3 a) {
    const double eps = 1e-9 * (absW * scale + lenC);
    for (const glm::dvec3& q : all)
      if (!(zPrime(a, q) > eps)) return false;
    return true;
  };
  // The axis: from c towards the visible body's box center; where that cone misses a caster (c
  // close to a wide body), the normal of the infinity plane c lies on (every point in front of the
  // virtual camera lies below it), which holds them all when c is finite.
  glm::dvec3 toCenter = sigma * (center * absW * sigma - C);  // sigma (center C.w - C.xyz)
  if (directional) toCenter = -C;
  bool centered = glm::length(toCenter) > 0.0;
  glm::dvec3 a = centered ? glm::normalize(toCenter) : glm::dvec3(0, 0, -1);
  if (!centered || !holds(a)) {
    centered = false;
    a = glm::dvec3(0, 0, -1);
    if (directional || !holds(a)) return out;
  }
  glm::dvec3 e1 = glm::dvec3(1, 0, 0) - a.x * a;
  if (glm::length(e1) < 0.1) e1 = glm::dvec3(0, 1, 0) - a.y * a;
  e1 = glm::normalize(e1);
  glm::dvec3 e2 = glm::cross(a, e1);
  // e_i.c: exactly e_i.center when a points at the center (finite as C.w -> 0).
  double g1 = centered ? glm::dot(e1, center) : glm::dot(e1, C) / Cw;
  double g2 = centered ? glm::dot(e2, center) : glm::dot(e2, C) / Cw;

  double t0 = inf, t1 = -inf, zMin = inf;
  for (const glm::dvec3& q : all) {
    double t = glm::dot(a, q);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
    zMin = std::min(zMin, zPrime(a, q));
  }
  const double rho = absW / zMin;
  auto w = [&](glm::dvec3 q) { return 1.0 + rho * (glm::dot(a, q) - t0); };
  double x1 = inf, x2 = inf, X1 = -inf, X2 = -inf;
  for (const glm::dvec3& q : visible) {
    double wq = w(q);
    double u = (glm::dot(e1, q) - g1) / wq, v = (glm::dot(e2, q) - g2) / wq;
    x1 = std::min(x1, u), X1 = std::max(X1, u);
    x2 = std::min(x2, v), X2 = std::max(X2, v);
  }
  // A hair of padding so the extreme vertices rasterize inside the map, as the other fits do.
  const double kMinSide = 1e-9;
  double pad1 = std::max((X1 - x1) * 1e-4, kMinSide), pad2 = std::max((X2 - x2) * 1e-4, kMinSide);
  x1 -= pad1, X1 += pad1, x2 -= pad2, X2 += pad2;
  double span = t1 - t0;
  double padT = std::max(span * 1e-4, kMinSide);
  if (absW > 0.0) padT = std::min(padT, 0.5 * zMin / absW);  // keep w > 0 at the padded near end
  double t0p = t0 - padT, t1p = t1 + padT, spanP = t1p - t0p;
  double w0p = 1.0 + rho * (t0p - t0), w1p = 1.0 + rho * (t1p - t0);

  glm::dmat4 m(0.0);
  // w = 1 + rho (a.q - t0)
  glm::dvec3 wLin = rho * a;
  double wConst = 1.0 - rho * t0;
  setRow(m, 3, wLin, wConst);
  // u w = (e1.q - g1 - x1 w) / (X1 - x1); v w likewise across e2.
  setRow(m, 0, (e1 - x1 * wLin) / (X1 - x1), (-g1 - x1 * wConst) / (X1 - x1));
  setRow(m, 1, (e2 - x2 * wLin) / (X2 - x2), (-g2 - x2 * wConst) / (X2 - x2));
  // Source: depth grows away from c; sink (inverted): it grows towards c.
  if (sigma > 0) setRow(m, 2, a * (w1p / spanP), -t0p * w1p / spanP);
  else setRow(m, 2, -a * (w0p / spanP), t1p * w0p / spanP);
  if (!finite(m)) return out;
  out.texFromClip = m;
  out.ok = true;
  return out;
}

PsmTexels psmTexels(const glm::dmat4& texFromWorld, glm::dvec3 towardLight, const std::vector<glm::dvec3>& points,
                    int mapSize) {
  PsmTexels out;
  glm::dvec3 l = glm::normalize(towardLight);
  glm::dvec3 helper = std::abs(l.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  glm::dvec3 b1 = glm::normalize(glm::cross(l, helper)), b2 = glm::cross(l, b1);
  double detMin = std::numeric_limits<double>::infinity(), detMax = 0;
  const double size = double(std::max(mapSize, 1));
  for (const glm::dvec3& p : points) {
    glm::dvec4 t = texFromWorld * glm::dvec4(p, 1.0);
    if (!(t.w > 0.0)) continue;
    // d(u)/d(b) = (U' w - U w') / w^2 with U' = the row's linear part along b.
    glm::dvec4 d1 = texFromWorld * glm::dvec4(b1, 0.0), d2 = texFromWorld * glm::dvec4(b2, 0.0);
    double w2 = t.w * t.w;
    double j00 = (d1.x * t.w - t.x * d1.w) / w2, j01 = (d2.x * t.w - t.x * d2.w) / w2;
    double j10 = (d1.y * t.w - t.y * d1.w) / w2, j11 = (d2.y * t.w - t.y * d2.w) / w2;
    double det = std::abs(j00 * j11 - j01 * j10);
    double sumSq = j00 * j00 + j01 * j01 + j10 * j10 + j11 * j11;
    double sMax = std::sqrt(0.5 * (sumSq + std::sqrt(std::max(sumSq * sumSq - 4.0 * det * det, 0.0))));
    if (!(det > 0.0) || !std::isfinite(det)) continue;
    double sMin = det / sMax;  // the smallest stretch: the texel's larger world side is 1 / (size sMin)
    detMin = std::min(detMin, det);
    detMax = std::max(detMax, det);
    out.texelWorldPerW = std::max(out.texelWorldPerW, 1.0 / (size * sMin * t.w));
  }
  if (detMax > 0.0) out.warp = std::cbrt(detMax / detMin) - 1.0;
  return out;
}

PsmFit psmFit(const Camera& camera, glm::dvec3 towardLight, const std::vector<glm::dvec3>& visible,
              const std::vector<glm::dvec3>& casters, double slideBack, int mapSize) {
  PsmFit out;
  if (visible.empty() || !(glm::length(towardLight) > 0.0)) return out;
  towardLight = glm::normalize(towardLight);
  glm::dvec3 eye(camera.position), forward = glm::normalize(glm::dvec3(camera.lookAt) - eye);
  double inf = std::numeric_limits<double>::infinity();
  double zNear = inf, zFar = -inf, zCasterMin = inf, zCasterMax = -inf;
  for (const glm::dvec3& p : visible) {
    double z = glm::dot(p - eye, forward);
    zNear = std::min(zNear, z), zFar = std::max(zFar, z);
  }
  zCasterMin = zNear, zCasterMax = zFar;
  for (const glm::dvec3& p : casters) {
    double z = glm::dot(p - eye, forward);
    zCasterMin = std::min(zCasterMin, z), zCasterMax = std::max(zCasterMax, z);
  }
  out.camera = psmVirtualCamera(camera, zNear, zFar, zCasterMin, zCasterMax, slideBack);
  const glm::dmat4& clip = out.camera.clipFromWorld;
  std::vector<glm::dvec4> visibleClip, casterClip;
  for (const glm::dvec3& p : visible) visibleClip.push_back(clip * glm::dvec4(p, 1.0));
  for (const glm::dvec3& p : casters) casterClip.push_back(clip * glm::dvec4(p, 1.0));
  PsmMap map = psmTexFromClip(clip * glm::dvec4(towardLight, 0.0), visibleClip, casterClip);
  if (!map.ok) return out;
  out.light = map.light;
  out.texFromWorld = map.texFromClip * clip;
  out.texels = psmTexels(out.texFromWorld, towardLight, visible, mapSize);
  out.ok = finite(out.texFromWorld) && out.texels.texelWorldPerW > 0.0 && std::isfinite(out.texels.texelWorldPerW);
  return out;
}

}  // namespace shadowlab::raster
