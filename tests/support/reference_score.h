#pragma once
// Scoring a raster frame against the reference the way compare/METRICS.md does, for the
// raster_*reference* tests (which link raster and reference, not compare): the pixels both
// renderers see on the same object are the compared pixels, error_rate is the share of them
// whose lit/shadowed decision (vis >= 0.5) differs, m_p95 the nearest-rank 95th percentile of
// light.L.m over them; the same definitions as compare's error_rate and m_p95.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "shadowlab/scenes/frame.h"

namespace shadowlab::testing {

struct Score {
  size_t both = 0;                // pixels where both renderers see the same object
  size_t wrong = 0;               // ... and disagree on lit (vis >= 0.5) vs shadowed
  size_t refLit = 0;              // ... the reference says lit
  size_t litShadowed = 0;         // ... lit in the reference, shadowed by the raster: acne-like
  size_t refShadow = 0;           // ... the reference says shadowed
  size_t shadowLit = 0;           // ... shadowed in the reference, lit by the raster: leak-like
  size_t refShadowRasShadow = 0;  // ... shadowed in both
  double errorRate = 0;
  double mP95 = 0;  // 95th percentile (nearest rank) of light.L.m over `both`, pixels per texel
};

inline Score score(const Frame& ref, const Frame& ras, const std::string& light) {
  Score s;
  const auto& rh = ref.get("hit");
  const auto& ro = ref.get("object_id");
  const auto& rv = ref.get("light." + light + ".vis");
  const auto& ah = ras.get("hit");
  const auto& ao = ras.get("object_id");
  const auto& av = ras.get("light." + light + ".vis");
  const auto& am = ras.get("light." + light + ".m");
  std::vector<float> m;
  for (size_t i = 0; i < ref.pixelCount(); ++i) {
    if (rh[i] < 0.5f || ah[i] < 0.5f || ro[i] != ao[i]) continue;
    ++s.both;
    bool refLit = rv[i] >= 0.5f, rasLit = av[i] >= 0.5f;
    s.wrong += refLit != rasLit;
    s.refLit += refLit;
    s.litShadowed += refLit && !rasLit;
    s.refShadow += !refLit;
    s.shadowLit += !refLit && rasLit;
    s.refShadowRasShadow += !refLit && !rasLit;
    m.push_back(am[i]);
  }
  s.errorRate = s.both ? double(s.wrong) / double(s.both) : 0.0;
  if (!m.empty()) {
    size_t rank = size_t(std::ceil(0.95 * double(m.size()))) - 1;
    std::nth_element(m.begin(), m.begin() + std::ptrdiff_t(rank), m.end());
    s.mP95 = m[rank];
  }
  return s;
}

}  // namespace shadowlab::testing
