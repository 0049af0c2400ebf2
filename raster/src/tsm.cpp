#include "shadowlab/raster/tsm.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace shadowlab::raster {

namespace {

constexpr double kTsmMinAxis = 1e-4;

double cross2(glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; }

// glm matrices are column-major: m[column][row]. Rows of a 2D homogeneous map (x, y, 1).
glm::dmat3 fromRows(glm::dvec3 r0, glm::dvec3 r1, glm::dvec3 r2) { return glm::transpose(glm::dmat3(r0, r1, r2)); }

}  // namespace

double tsmEta(double lambda, double deltaPrime, double focusLine) {
  const double inf = std::numeric_limits<double>::infinity();
  if (!std::isfinite(lambda) || !std::isfinite(deltaPrime) || !std::isfinite(focusLine) || !(lambda > 0.0) ||
      !(focusLine > 0.0 && focusLine < 1.0))
    return inf;
  if (!(deltaPrime > 0.0)) return 0.0;
  double xi = 1.0 - 2.0 * focusLine;
  double denominator = lambda * (1.0 - xi) - 2.0 * deltaPrime;  // 2 (focusLine lambda - deltaPrime)
  if (!(denominator > 0.0)) return inf;
  double eta = lambda * deltaPrime * (1.0 + xi) / denominator;
  return std::isfinite(eta) ? eta : inf;
}

glm::dmat3 tsmTrapezoidToSquare(const std::array<glm::dvec2, 4>& t) {
  // T1, R: the top's center u to the origin, the top (t3 -> t2) along +x, the base towards +y.
  glm::dvec2 u = 0.5 * (t[2] + t[3]);
  glm::dvec2 ex = glm::normalize(t[2] - t[3]);
  glm::dvec2 ey(-ex.y, ex.x);
  if (glm::dot(0.5 * (t[0] + t[1]) - u, ey) < 0.0) ey = -ey;
  // T2: q, where the sides t0 t3 and t1 t2 meet, to the origin. On the line through t3 along
  // t3 - t0 at parameter a: t3 + a (t3 - t0) = t2 + b (t2 - t1).
  glm::dvec2 d0 = t[3] - t[0], d1 = t[2] - t[1];
  double det = cross2(d0, d1);
  double a = cross2(t[2] - t[3], d1) / det;
  glm::dvec2 q = t[3] + a * d0;
  // In the frame at q: x' = (p - q) . ex, s = (p - q) . ey (s > 0 over the trapezoid).
  double eta = glm::dot(u - q, ey);                       // the top's distance from q
  double lambda = glm::dot(0.5 * (t[0] + t[1]) - u, ey);  // top to base
  // H: shear x'' = x' - c s, c = the top center's x' over its s: the trapezoid symmetric about x'' = 0.
  double c = glm::dot(u - q, ex) / eta;
  // S1: the sides at x'' = +-k s, k = half the top's width over eta; X = x'' / (k s) in [-1, 1].
  double k = 0.5 * glm::length(t[2] - t[3]) / eta;
  // N, T3, S2: Y = A - B / s with Y(eta) = +1 (top), Y(eta + lambda) = -1 (base).
  double B = -2.0 * eta * (eta + lambda) / lambda;
  double A = 1.0 + B / eta;
  // Homogeneous, w = s / eta: (X w, Y w, w) = (x'' / (k eta), (A s - B) / eta, s / eta).
  glm::dvec3 sRow(ey.x, ey.y, -glm::dot(q, ey));  // s as a function of (x, y, 1)
  glm::dvec3 xRow(ex.x, ex.y, -glm::dot(q, ex));  // x'
  glm::dvec3 xShear = xRow - c * sRow;            // x''
  return fromRows(xShear / (k * eta), (A * sRow - glm::dvec3(0, 0, B)) / eta, sRow / eta);
}

TsmMap tsmFit(const std::vector<glm::dvec3>& hull, glm::dvec2 nearCenter, glm::dvec2 farCenter, glm::dvec2 focusPoint,
              double focusLine, double zMin, double zMax, int mapSize) {
  TsmMap out;
  if (hull.empty()) return out;
  // The center line: its direction es (near to far), et across it.
  glm::dvec2 axis = farCenter - nearCenter;
  double axisLength = glm::length(axis);
  double extent = 0.0;
  for (const glm::dvec3& p : hull) extent = std::max(extent, glm::length(glm::dvec2(p) - nearCenter));
  // No center line: the view along the light (the centers project to one point, up to the float
  // rounding of the camera and light matrices, about 1e-7 of the extent).
  if (!(axisLength > kTsmMinAxis * extent) || !std::isfinite(axisLength)) return out;
  glm::dvec2 es = axis / axisLength, et(es.y, -es.x);
  // Top and base: the hull's extremes along the line, padded by a hair so that no hull vertex
  // rasterizes on the map's border.
  double inf = std::numeric_limits<double>::infinity();
  double sTop = inf, sBase = -inf;
  for (const glm::dvec3& p : hull) {
    double s = glm::dot(glm::dvec2(p) - nearCenter, es);
    sTop = std::min(sTop, s);
    sBase = std::max(sBase, s);
  }
  double pad = std::max((sBase - sTop) * 1e-4, 1e-9 * extent);
  sTop -= pad;
  sBase += pad;
  double lambda = sBase - sTop;
  double deltaPrime = glm::dot(focusPoint - nearCenter, es) - sTop;
  double eta = tsmEta(lambda, deltaPrime, focusLine);
  if (!(eta > 0.0) || !std::isfinite(eta)) return out;
  // q on the center line, eta before the top; the sides: the extreme slopes t / s seen from q.
  glm::dvec2 q = nearCenter + es * (sTop - eta);
  double slopeMin = inf, slopeMax = -inf;
  for (const glm::dvec3& p : hull) {
    glm::dvec2 d = glm::dvec2(p) - q;
    double slope = glm::dot(d, et) / glm::dot(d, es);  // s >= eta > 0
    slopeMin = std::min(slopeMin, slope);
    slopeMax = std::max(slopeMax, slope);
  }
  double slopePad = std::max((slopeMax - slopeMin) * 1e-4, 1e-9);
  slopeMin -= slopePad;
  slopeMax += slopePad;
  auto at = [&](double s, double slope) { return q + es * s + et * (slope * s); };
  out.trapezoid = {at(eta + lambda, slopeMin), at(eta + lambda, slopeMax), at(eta, slopeMax), at(eta, slopeMin)};
  out.q = q;
  out.lambda = lambda;
  out.deltaPrime = deltaPrime;
  out.eta = eta;
  glm::dmat3 nt = tsmTrapezoidToSquare(out.trapezoid);
  // Rows of N_T over (x, y, 1); u w = (X w + w) / 2, v w = (w - Y w) / 2 (v = 0 on the top).
  glm::dmat3 rows = glm::transpose(nt);
  glm::dvec3 xw = rows[0], yw = rows[1], w = rows[2];
  glm::dvec3 uw = 0.5 * (xw + w), vw = 0.5 * (w - yw);
  double h = std::max(zMax - zMin, 1e-9);
  glm::dmat4 m(0.0);  // m[column][row], columns x, y, z, 1 of light view space
  auto setRow = [&](int row, glm::dvec3 r) {
    m[0][row] = r.x;
    m[1][row] = r.y;
    m[3][row] = r.z;
  };
  setRow(0, uw);
  setRow(1, vw);
  setRow(3, w);
  m[2][2] = -1.0 / h;  // depth w = (zMax - z) / h
  m[3][2] = zMax / h;
  out.texFromLight = m;
  out.depthFromLight = glm::dvec4(0.0, 0.0, -1.0 / h, zMax / h);
  double topWidth = (slopeMax - slopeMin) * eta;
  double steepest = std::max(std::abs(slopeMin), std::abs(slopeMax));
  out.texelWorldPerW = std::max(topWidth, lambda * std::sqrt(1.0 + steepest * steepest)) / double(std::max(mapSize, 1));
  out.valid = true;
  return out;
}

}  // namespace shadowlab::raster
