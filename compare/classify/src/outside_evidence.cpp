// The evidence of a frame from another renderer (outside_frame.h prepareOutsideComparison): what
// the blind rule (classify.h classifyBlindDisagreement) reads beside the truth's own channels,
// made from the truth's surface points and normals and the map the renderer declared.
// compare/METRICS.md "Frames from other renderers" derives each plane.
#include <algorithm>
#include <cctype>
#include <cmath>

#include <glm/glm.hpp>

#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/kinds.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab {
namespace {

// A neighbour's surface point stands for the pixel's own surface when it is the same object and
// its normal within about 25 degrees of the pixel's: across a crease or a silhouette of one object
// the difference of the points is not a step along the pixel's surface.
constexpr float kSameSurfaceCos = 0.9f;

// The declared filter is a filterable map's (its failure beyond contact is light bleeding):
// shadowlab's names (vsm, evsm2, evsm4, msm) or a renderer's ("VSM", three.js "VSMShadowMap").
bool filterableName(const std::string& declared) {
  std::string key;
  for (char c : declared) key += char(std::tolower(static_cast<unsigned char>(c)));
  const std::string suffix = "shadowmap";
  if (key.size() > suffix.size() && key.compare(key.size() - suffix.size(), suffix.size(), suffix) == 0)
    key.resize(key.size() - suffix.size());
  const KindInfo<Filter>* kind = findKind(filterKinds(), key);
  return kind && isMomentFilter(kind->kind);
}

struct LayerPoint {
  glm::dvec4 clip{0.0};
  bool inside = false;  // in front of the layer (w > 0), x/w and y/w in [-1, 1]
};

LayerPoint projectPoint(const glm::mat4& clipFromWorld, const glm::dvec3& p, double edge = 1.0) {
  LayerPoint out;
  out.clip = glm::dmat4(clipFromWorld) * glm::dvec4(p, 1.0);
  const double w = out.clip.w;
  out.inside = w > 0.0 && std::fabs(out.clip.x) <= edge * w && std::fabs(out.clip.y) <= edge * w;
  return out;
}

// Texel coordinates of a clip-space point in a map of `size` texels.
glm::dvec2 texel(const glm::dvec4& clip, int size) {
  return glm::dvec2(clip.x / clip.w, clip.y / clip.w) * (0.5 * size) + 0.5 * size;
}

}  // namespace

void prepareOutsideComparison(const Frame& truthAll, Frame& outside, const DeclaredRenderer& declared,
                              CompareOptions& options) {
  options.blind = true;
  options.declaredFilterable = filterableName(declared.filter);
  options.rasterName = options.rasterName.empty() ? "outside frame" : options.rasterName;
  if (!declared.declaresMap()) {
    // No footprint: compare's boundary band is boundaryTexels x 1 pixel, read in pixels, and no
    // point is proven outside the map (no coverage) or in contact (no leak).
    outside.meta["boundary_band"] = "pixels";
    return;
  }
  const std::string light = outside.meta.value("light", std::string());
  const std::string lp = "light." + light + ".";
  const char* needed[] = {"hit", "object_id", "P.x", "P.y", "P.z", "N.x", "N.y", "N.z"};
  for (const char* name : needed) {
    if (!truthAll.has(name) || truthAll.get(name).size() != truthAll.pixelCount()) {
      throw InputError(options.referenceName + ": error: no \"" + name +
                       "\" channel; expected the truth with every channel (reference --channels all) to "
                       "classify a frame from another renderer with its declared map");
    }
  }
  const int width = truthAll.width, height = truthAll.height;
  if (outside.width != width || outside.height != height) {
    throw InputError(options.rasterName + ": error: the frame is not the truth's size");
  }
  const std::vector<float>&hit = truthAll.get("hit"), &id = truthAll.get("object_id");
  const std::vector<float>*P[3] = {&truthAll.get("P.x"), &truthAll.get("P.y"), &truthAll.get("P.z")};
  const std::vector<float>*N[3] = {&truthAll.get("N.x"), &truthAll.get("N.y"), &truthAll.get("N.z")};
  auto point = [&](size_t i) { return glm::dvec3((*P[0])[i], (*P[1])[i], (*P[2])[i]); };
  auto normal = [&](size_t i) { return glm::dvec3((*N[0])[i], (*N[1])[i], (*N[2])[i]); };
  auto surface = [&](size_t i) { return hit[i] >= 0.5f; };

  outside.add(lp + "in_map");
  outside.add(lp + "m");
  outside.add(lp + "contact_world");  // add() moves the planes: take them after the last one
  std::vector<float>& inMap = outside.get(lp + "in_map");
  std::vector<float>& footprint = outside.get(lp + "m");
  std::vector<float>& contact = outside.get(lp + "contact_world");
  const int size = declared.mapSize;
  const double contactTexels = options.declaredFilterable ? kContactTexelsFilterable : kContactTexels;
  // in_map: inside the layer by kMapEdgeTexels (x/w and y/w within 1 - 2 k / size).
  const double edge = 1.0 - 2.0 * double(kMapEdgeTexels) / double(declared.mapSize);
  const double normalBias = declared.normalBiasWorld ? std::max(0.0, *declared.normalBiasWorld) : 0.0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      inMap[i] = 1.0f;
      footprint[i] = kFootprintCapPx;
      contact[i] = 0.0f;
      if (!surface(i)) continue;
      const glm::dvec3 p = point(i), n = normal(i);
      // The layer: the first that holds the point (the declared order: cascades near to far).
      size_t layer = 0;
      LayerPoint lpP;
      bool found = false;
      for (size_t l = 0; l < declared.lightClipFromWorld.size() && !found; ++l) {
        lpP = projectPoint(declared.lightClipFromWorld[l], p, edge);
        if (lpP.inside) {
          layer = l;
          found = true;
        }
      }
      if (!found) {
        inMap[i] = 0.0f;
        lpP = projectPoint(declared.lightClipFromWorld[0], p);
      }
      const glm::mat4& M = declared.lightClipFromWorld[layer];
      if (!(lpP.clip.w > 0.0)) continue;  // behind the layer: no footprint, no contact
      // One step of a screen axis along the surface: the nearer of the two neighbours on it,
      // projected into the point's tangent plane.
      auto step = [&](int dx, int dy, glm::dvec3* out) {
        double best = -1.0;
        for (int sign : {1, -1}) {
          const int nx = x + sign * dx, ny = y + sign * dy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const size_t j = size_t(ny) * width + nx;
          if (!surface(j) || id[j] != id[i] || glm::dot(normal(j), n) < kSameSurfaceCos) continue;
          glm::dvec3 d = (point(j) - p) * double(sign);
          d -= n * glm::dot(n, d);
          const double len = glm::length(d);
          if (len > 0.0 && (best < 0.0 || len < best)) {
            best = len;
            *out = d;
          }
        }
        return best > 0.0;
      };
      glm::dvec3 dx(0.0), dy(0.0);
      const glm::dvec2 t0 = texel(lpP.clip, size);
      const bool hasDx = step(1, 0, &dx), hasDy = step(0, 1, &dy);
      if (hasDx && hasDy) {
        // Lloyd's m as resolve.frag takes it: J = d(texel)/d(pixel), m = sMax / det J = 1 / sMin.
        const glm::dvec2 jx = texel(projectPoint(M, p + dx).clip, size) - t0;
        const glm::dvec2 jy = texel(projectPoint(M, p + dy).clip, size) - t0;
        const double sumSq = glm::dot(jx, jx) + glm::dot(jy, jy);
        const double detJ = std::fabs(jx.x * jy.y - jy.x * jx.y);
        const double sMax = std::sqrt(0.5 * (sumSq + std::sqrt(std::max(sumSq * sumSq - 4.0 * detJ * detJ, 0.0))));
        const double singular = std::max(double(kFootprintSingularRatio) * sMax, 1.0 / double(kFootprintCapPx)) * sMax;
        footprint[i] = detJ > singular ? float(std::min(sMax / detJ, double(kFootprintCapPx))) : kFootprintCapPx;
      } else if (hasDx || hasDy) {
        // A sliver one pixel wide (an edge-on card, a gap): the one step there is, read as both.
        const glm::dvec2 j = texel(projectPoint(M, p + (hasDx ? dx : dy)).clip, size) - t0;
        const double len = glm::length(j);
        footprint[i] = len > 1e-6 ? float(std::min(1.0 / len, double(kFootprintCapPx))) : kFootprintCapPx;
      }
      // The world size of one texel at the point (its larger side, across the light's rays): the
      // texel coordinates' gradients in world space, u = size (x/w + 1) / 2.
      const glm::dvec4 c = lpP.clip;
      auto row = [&](int r) { return glm::dvec3(M[0][r], M[1][r], M[2][r]); };
      const glm::dvec3 du = (row(0) - (c.x / c.w) * row(3)) * (0.5 * size / c.w);
      const glm::dvec3 dv = (row(1) - (c.y / c.w) * row(3)) * (0.5 * size / c.w);
      const double g = std::min(glm::length(du), glm::length(dv));
      const double texelWorld = g > 0.0 ? 1.0 / g : 0.0;
      contact[i] = float(options.leakBiasFactor * (contactTexels * texelWorld + normalBias));
    }
  }
  outside.meta["boundary_band"] = "texels";
}

}  // namespace shadowlab
