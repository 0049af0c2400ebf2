// Polygon faces -> triangles (polygon.h). The ear clipping follows mapbox/earcut (ISC licence;
// not packaged by Debian): the same ear test, the same order of ears and the same clean-up pass
// when no ear is found, without its hole elimination (a face has no holes; a keyhole face brings
// its own bridge) and without its last-resort passes, which cut self-intersecting polygons into
// something: such a face is refused instead.
#include "shadowlab/scenes/polygon.h"
#include "shadowlab/scenes/number_text.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace shadowlab {

namespace {

constexpr double kTwoPi = 6.28318530717958647692;

// The face seen along its normal: the two coordinates left when the normal's largest component is
// dropped, ordered so that the face runs counter-clockwise (positive area). A parallel projection
// keeps a flat polygon simple or not, and keeps its corners' coordinates exactly as written.
std::vector<glm::dvec2> project(const std::vector<glm::vec3>& c, const glm::dvec3& normal) {
  const glm::dvec3 a = glm::abs(normal);
  const int drop = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
  // (u, v, dropped) right-handed: y z x, z x y, x y z.
  int u = (drop + 1) % 3, v = (drop + 2) % 3;
  if (normal[drop] < 0) std::swap(u, v);
  std::vector<glm::dvec2> p(c.size());
  for (size_t i = 0; i < c.size(); ++i) p[i] = glm::dvec2(c[i][u], c[i][v]);
  return p;
}

double cross(glm::dvec2 a, glm::dvec2 b) { return a.x * b.y - a.y * b.x; }

// The face's total turning angle (counter-clockwise positive; 2 pi once around) and whether it is
// convex (every turn a left turn or straight, once around) or on one line. Repeated consecutive
// corners are skipped.
struct Turns {
  double turning = 0;
  bool convexOrLine = false;
};
Turns turns(const std::vector<glm::dvec2>& all) {
  std::vector<glm::dvec2> p;
  for (const auto& q : all)
    if (p.empty() || q != p.back()) p.push_back(q);
  while (p.size() > 1 && p.back() == p.front()) p.pop_back();
  const size_t n = p.size();
  Turns t;
  if (n < 3) {
    t.convexOrLine = true;
    return t;
  }
  bool straight = true, leftOnly = true;
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 e1 = p[i] - p[(i + n - 1) % n], e2 = p[(i + 1) % n] - p[i];
    const double c = cross(e1, e2), scale = glm::length(e1) * glm::length(e2);
    if (std::fabs(c) > 1e-12 * scale) straight = false;
    if (c < -1e-9 * scale) leftOnly = false;
    t.turning += std::atan2(c, glm::dot(e1, e2));
  }
  t.convexOrLine = straight || (leftOnly && std::fabs(t.turning - kTwoPi) < 1e-6);
  return t;
}

// Proper crossing: each segment's ends strictly on either side of the other's line.
bool segmentsCross(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c, glm::dvec2 d) {
  const double eps = 1e-12 * glm::length(b - a) * glm::length(d - c);
  const double o1 = cross(b - a, c - a), o2 = cross(b - a, d - a);
  const double o3 = cross(d - c, a - c), o4 = cross(d - c, b - c);
  return ((o1 > eps && o2 < -eps) || (o1 < -eps && o2 > eps)) && ((o3 > eps && o4 < -eps) || (o3 < -eps && o4 > eps));
}

// mapbox/earcut's linked-list ear clipping on a counter-clockwise ring (its area() is negative at
// a convex corner).
class EarClipper {
 public:
  // `p` counter-clockwise, linked in order (earcut's outer ring, whose signedArea is positive).
  explicit EarClipper(const std::vector<glm::dvec2>& p) {
    for (size_t k = 0; k < p.size(); ++k) insert(uint32_t(k), p[k]);
    const int last = int(nodes_.size()) - 1;
    if (last > 0 && equals(last, nodes_[size_t(last)].next)) remove(last);
  }

  // Triangles as (prev, ear, next), wound like the ring; false when no ear is left to cut.
  bool run(std::vector<std::array<uint32_t, 3>>& out) {
    int ear = first_;
    int stop = ear;
    int pass = 0;
    while (node(ear).prev != node(ear).next) {
      const int prev = node(ear).prev, next = node(ear).next;
      if (isEar(ear)) {
        out.push_back({node(prev).i, node(ear).i, node(next).i});
        remove(ear);
        // Skipping the next corner gives fewer sliver triangles (earcut's choice).
        ear = node(next).next;
        stop = ear;
        continue;
      }
      ear = next;
      if (ear == stop) {
        if (pass > 0) return false;
        // No ear: drop repeated and collinear corners (they enclose nothing) and try again.
        ear = filterPoints(ear);
        stop = ear;
        pass = 1;
      }
    }
    return true;
  }

 private:
  struct Node {
    uint32_t i;
    double x, y;
    int prev, next;
  };
  std::vector<Node> nodes_;
  int first_ = -1;

  const Node& node(int k) const { return nodes_[size_t(k)]; }
  void insert(uint32_t i, glm::dvec2 q) {
    const int k = int(nodes_.size());
    if (first_ < 0) {
      nodes_.push_back({i, q.x, q.y, k, k});
      first_ = k;
      return;
    }
    const int last = nodes_[size_t(first_)].prev;
    nodes_.push_back({i, q.x, q.y, last, first_});
    nodes_[size_t(last)].next = k;
    nodes_[size_t(first_)].prev = k;
  }
  void remove(int k) {
    const Node& n = node(k);
    nodes_[size_t(n.prev)].next = n.next;
    nodes_[size_t(n.next)].prev = n.prev;
    if (first_ == k) first_ = n.next;
  }
  bool equals(int a, int b) const { return node(a).x == node(b).x && node(a).y == node(b).y; }
  double area(int p, int q, int r) const {
    const Node &a = node(p), &b = node(q), &c = node(r);
    return (b.y - a.y) * (c.x - b.x) - (b.x - a.x) * (c.y - b.y);
  }
  static bool pointInTriangle(double ax, double ay, double bx, double by, double cx, double cy, double px, double py) {
    return (cx - px) * (ay - py) >= (ax - px) * (cy - py) && (ax - px) * (by - py) >= (bx - px) * (ay - py) &&
           (bx - px) * (cy - py) >= (cx - px) * (by - py);
  }
  bool isEar(int ear) const {
    const Node &a = node(node(ear).prev), &b = node(ear), &c = node(node(ear).next);
    if (area(b.prev, ear, b.next) >= 0) return false;  // reflex (or straight): not an ear
    const double x0 = std::min({a.x, b.x, c.x}), y0 = std::min({a.y, b.y, c.y});
    const double x1 = std::max({a.x, b.x, c.x}), y1 = std::max({a.y, b.y, c.y});
    // No reflex corner may lie in the ear (one at a's place is the other side of a bridge).
    for (int k = c.next; k != b.prev; k = node(k).next) {
      const Node& p = node(k);
      if (p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1 && !(p.x == a.x && p.y == a.y) &&
          pointInTriangle(a.x, a.y, b.x, b.y, c.x, c.y, p.x, p.y) && area(p.prev, k, p.next) >= 0)
        return false;
    }
    return true;
  }
  int filterPoints(int start) {
    int p = start, end = start;
    bool again;
    do {
      again = false;
      if (equals(p, node(p).next) || area(node(p).prev, p, node(p).next) == 0) {
        remove(p);
        p = end = node(p).prev;
        if (p == node(p).next) break;
        again = true;
      } else {
        p = node(p).next;
      }
    } while (again || p != end);
    return end;
  }
};

}  // namespace

PolygonTriangles triangulatePolygon(const std::vector<glm::vec3>& c) {
  PolygonTriangles out;
  const size_t n = c.size();
  if (n < 3) {
    out.error = "a face of " + std::to_string(n) + " corners; expected at least 3";
    return out;
  }
  if (n == 3) {
    out.triangles.push_back({0, 1, 2});
    return out;
  }
  // Newell's normal: the face's area vector, robust to collinear and repeated corners.
  glm::dvec3 newell(0);
  glm::dvec3 lo(c[0]), hi(c[0]), centroid(0);
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 a(c[i]), b(c[(i + 1) % n]);
    newell += glm::dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    lo = glm::min(lo, a);
    hi = glm::max(hi, a);
    centroid += a / double(n);
  }
  const double size = glm::length(hi - lo);
  const bool enclosesArea = glm::length(newell) > 1e-12 * size * size;
  // A face enclosing no area (a bow tie whose halves cancel, a path out and back) is seen along the
  // normal of its widest corner triangle instead; none at all: its corners are on one line.
  glm::dvec3 normal = newell;
  if (!enclosesArea) {
    size_t far = 0;
    for (size_t i = 1; i < n; ++i)
      if (glm::length(glm::dvec3(c[i]) - glm::dvec3(c[0])) > glm::length(glm::dvec3(c[far]) - glm::dvec3(c[0])))
        far = i;
    normal = glm::dvec3(0);
    for (size_t i = 1; i < n; ++i) {
      const glm::dvec3 w = glm::cross(glm::dvec3(c[far]) - glm::dvec3(c[0]), glm::dvec3(c[i]) - glm::dvec3(c[0]));
      if (glm::length(w) > glm::length(normal)) normal = w;
    }
  }
  const bool onALine = !(glm::length(normal) > 1e-12 * size * size);
  const std::vector<glm::dvec2> p = project(c, normal);
  const Turns turn = turns(p);

  if (onALine || (enclosesArea && turn.convexOrLine)) {
    if (n == 4) {
      // tinyobjloader's quad split (its own float arithmetic): along the shorter diagonal.
      const float e02x = c[2].x - c[0].x, e02y = c[2].y - c[0].y, e02z = c[2].z - c[0].z;
      const float e13x = c[3].x - c[1].x, e13y = c[3].y - c[1].y, e13z = c[3].z - c[1].z;
      const float sqr02 = e02x * e02x + e02y * e02y + e02z * e02z;
      const float sqr13 = e13x * e13x + e13y * e13y + e13z * e13z;
      if (sqr02 < sqr13) out.triangles = {{0, 1, 2}, {0, 2, 3}};
      else out.triangles = {{0, 1, 3}, {1, 2, 3}};
    } else {
      for (uint32_t i = 1; i + 1 < n; ++i) out.triangles.push_back({0, i, i + 1});
    }
    return out;
  }

  if (n > kMaxConcavePolygonCorners) {
    out.error = "a non-convex face of " + std::to_string(n) + " corners; expected at most " +
                std::to_string(kMaxConcavePolygonCorners) + " corners in a non-convex face (split it)";
    return out;
  }
  // How far from flat: the corner farthest from the plane through the corners' mean.
  const glm::dvec3 unit = normal / glm::length(normal);
  size_t worst = 0;
  double worstDistance = 0;
  for (size_t i = 0; i < n; ++i) {
    const double d = std::fabs(glm::dot(glm::dvec3(c[i]) - centroid, unit));
    if (d > worstDistance) worst = i, worstDistance = d;
  }
  if (worstDistance > kPolygonPlanarTolerance * size) {
    out.error = "a non-convex face that is not flat (corner " + std::to_string(worst + 1) + " lies " +
                numberText(worstDistance) + " from its plane, more than " + numberText(kPolygonPlanarTolerance * 100) +
                "% of its size " + numberText(size) + "); expected a flat face, or convex faces";
    return out;
  }
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through the wrap
      if (segmentsCross(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n])) {
        out.error = "a face whose edges cross (corners " + std::to_string(i + 1) + "-" +
                    std::to_string((i + 1) % n + 1) + " and " + std::to_string(j + 1) + "-" +
                    std::to_string((j + 1) % n + 1) + "); expected a simple polygon";
        return out;
      }
    }
  if (!enclosesArea) {
    out.error =
        "a face that encloses no area yet is not a line (its edges run back over each other); expected a "
        "simple polygon";
    return out;
  }
  // Left turns all the way, but round more than once (a square written out 3 times over).
  if (turn.turning > 1.5 * kTwoPi) {
    out.error = "a face that runs round " + std::to_string(int(std::lround(turn.turning / kTwoPi))) +
                " times; expected a simple polygon (once round)";
    return out;
  }
  EarClipper clipper(p);
  if (!clipper.run(out.triangles)) {
    out.triangles.clear();
    out.error =
        "a face that ear clipping cannot cut into triangles (its edges touch or overlap); expected a simple "
        "polygon";
    return out;
  }
  return out;
}

}  // namespace shadowlab
