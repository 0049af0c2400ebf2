// Per-pixel classification of shadow errors and the metrics built on it.
// The definitions (numerator, denominator, exclusions, sources) are in compare/METRICS.md; this
// file is their implementation and must stay in step with it.
//
// Speed: a 1920x1080 pair is ~2M pixels; the main pass reads 7 float planes (~58 MB) and only
// touches the evidence channels at disagreeing pixels, so it is memory-bound. Work is split into
// fixed blocks of rows whose partial sums are reduced in block order: the result is bit-identical
// for any number of threads.
//
// The steps (classify.h): evidence (readChannels, PixelEvidence) -> the class of one pixel
// (classifyPixel and its parts, pure) -> tallies (counts, rates, m statistics, cascades, projector).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "shadowlab/compare/classify.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/number_text.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab {

const char* toString(PixelClass c) { return size_t(c) < kPixelClassCount ? classInfo(c).key : "unknown"; }

nlohmann::json Metrics::toJson() const {
  // A ratio with no pixel under it is undefined: null, never the 0 or 1 an empty tally holds
  // (compare/METRICS.md "Nothing compared"); a gate must not read "nothing seen" as "perfect".
  const bool none = nothingCompared();
  auto ratio = [none](double v) { return none ? nlohmann::json(nullptr) : nlohmann::json(v); };
  nlohmann::json j;
  j["pixels_compared"] = pixelsCompared;
  if (none) j["nothing_compared"] = true;
  j["errors"] = errors;
  j["error_rate"] = ratio(errorRate);
  for (const PixelClassInfo& c : kPixelClasses) {
    if (c.countMetric) j[c.countMetric] = count(c.cls);
    if (c.rateMetric) j[c.rateMetric] = ratio(rate(c.cls));
  }
  j["shadow_iou"] = ratio(shadowIou);
  j["mae"] = ratio(mae);
  j["rmse"] = ratio(rmse);
  for (const VisRegionInfo& r : kVisRegions) {
    const size_t k = size_t(r.region);
    j[r.pixelsMetric] = regionPixels[k];
    const bool empty = regionPixels[k] == 0;  // a mean over no pixel: null, as a rate of nothing compared
    j[r.maeMetric] = empty ? nlohmann::json(nullptr) : nlohmann::json(regionMae[k]);
    j[r.rmseMetric] = empty ? nlohmann::json(nullptr) : nlohmann::json(regionRmse[k]);
  }
  j["over_shadowing"] = ratio(overShadowing);
  j["under_shadowing"] = ratio(underShadowing);
  j["within_uncertainty"] = withinUncertainty;
  const bool noFootprint = footprintUndefined();
  j["m_median"] = noFootprint ? nlohmann::json(nullptr) : nlohmann::json(mMedian);
  j["m_p95"] = noFootprint ? nlohmann::json(nullptr) : nlohmann::json(mP95);
  j["m_max"] = noFootprint ? nlohmann::json(nullptr) : nlohmann::json(mMax);
  j["m_capped"] = mCapped;
  if (!lightCompared) j["light_compared"] = false;
  if (hasProjector) {
    j["projector_coverage_iou"] = ratio(projectorCoverageIou);
    j["reverse_projection_pixels"] = reverseProjectionPixels;
    j["projector_color_mae"] = ratio(projectorColorMae);
  }
  if (!cascades.empty()) {
    nlohmann::json list = nlohmann::json::array();
    for (const CascadeMetrics& c : cascades)
      list.push_back({{"index", c.index}, {"pixels", c.pixels}, {"error_rate", c.errorRate}, {"m_p95", c.mP95}});
    j["cascades"] = list;
  }
  return j;
}

std::string nothingComparedMessage(const Metrics& m) {
  if (!m.nothingCompared()) return "";
  const uint64_t mismatch = m.count(PixelClass::GeometryMismatch);
  const uint64_t background = m.count(PixelClass::NotCompared);
  std::string why;
  if (mismatch == 0)
    why = "the camera sees no surface (all " + std::to_string(background) +
          " pixels are background in both frames: sky, or only zero-area triangles)";
  else
    why = "no pixel shows the same surface in both frames (" + std::to_string(mismatch) + " geometry mismatch, " +
          std::to_string(background) + " background)";
  return "nothing to compare: " + why +
         "; metrics.json says \"nothing_compared\": true and its rates are null; expected a camera that sees a "
         "surface both renderers agree on";
}

std::string footprintCapNote(const Metrics& m) {
  if (m.mCapped == 0 || m.nothingCompared()) return "";
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "note: %llu of %llu compared pixels have the texel footprint m at its cap %.0f (a surface edge-on to "
                "the light, e.g. a point light lying in it): counted in m_capped, left out of m_median, m_p95, "
                "m_max%s",
                (unsigned long long)m.mCapped, (unsigned long long)m.pixelsCompared, double(kFootprintCapPx),
                m.footprintUndefined() ? " (which are null: no pixel left)" : "");
  return buf;
}

std::string projectorSummary(const Metrics& m) {
  if (!m.hasProjector) return "";
  char buf[160];
  std::snprintf(buf, sizeof buf, "projector: coverage_iou %.4f, reverse_projection_pixels %llu, color_mae %.4f",
                m.projectorCoverageIou, (unsigned long long)m.reverseProjectionPixels, m.projectorColorMae);
  return (m.lightCompared ? "" : "no light (projector-only scene); ") + std::string(buf);
}

std::string errorClassSummary(const Metrics& m, bool rates) {
  std::string out;
  for (const PixelClassInfo& c : kPixelClasses) {
    if (!c.error) continue;
    char value[32];
    if (rates) std::snprintf(value, sizeof value, "%.4f", m.rate(c.cls));
    else std::snprintf(value, sizeof value, "%llu", (unsigned long long)m.count(c.cls));
    out += (out.empty() ? "" : ", ") + std::string(c.key) + " " + value;
  }
  return out;
}

nlohmann::json pixelClassesJson() {
  nlohmann::json list = nlohmann::json::array();
  for (const PixelClassInfo& c : kPixelClasses) {
    char color[8];
    std::snprintf(color, sizeof color, "#%06x", unsigned(c.rgbLit));
    auto nameOrNull = [](const char* s) { return s ? nlohmann::json(s) : nlohmann::json(nullptr); };
    list.push_back({{"code", int(c.cls)},
                    {"key", c.key},
                    {"label", c.label},
                    {"error", c.error},
                    {"count_metric", nameOrNull(c.countMetric)},
                    {"rate_metric", nameOrNull(c.rateMetric)},
                    {"color", color},
                    {"help", c.help}});
  }
  return list;
}

namespace {

// Internal per-pixel codes for "disagreement not explained by coverage or acne": resolved to
// Aliasing, or beyond the boundary band to Leak (kCandidateLeak: the leak evidence holds) or
// Other, once the boundary distances are known. Never leave this file.
// kCandidateBleed: the bleed evidence holds (it wins over the leak evidence beyond the band).
// kCandidateAcne: the blind rule's acne evidence holds (frames from other renderers).
constexpr uint8_t kCandidate = 255, kCandidateLeak = 254, kCandidateBleed = 253, kCandidateAcne = 252;
constexpr uint8_t kFirstCandidate = kCandidateAcne;  // codes >= this are unresolved candidates
uint8_t candidateCode(const DisagreementClass& d) {
  return d.bleedEvidence ? kCandidateBleed
         : d.leakEvidence ? kCandidateLeak
         : d.acneEvidence ? kCandidateAcne
                          : kCandidate;
}
PixelClass resolveCandidateCode(uint8_t code, bool withinBand) {
  return resolveCandidate(code == kCandidateLeak, withinBand, code == kCandidateBleed, code == kCandidateAcne);
}
// Reference decision per pixel, for the boundary distance transform.
constexpr uint8_t kDecisionNone = 0, kDecisionLit = 1, kDecisionShadowed = 2;
constexpr int kBlockRows = 16;

std::string both(const CompareOptions& o) { return o.referenceName + " and " + o.rasterName; }

std::string channelList(const Frame& f, const std::string& prefix, const std::string& suffix) {
  std::string out;
  for (const auto& n : f.names) {
    if (n.size() > prefix.size() + suffix.size() && n.compare(0, prefix.size(), prefix) == 0 &&
        n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0) {
      if (!out.empty()) out += ", ";
      out += n.substr(prefix.size(), n.size() - prefix.size() - suffix.size());
    }
  }
  return out.empty() ? "none" : out;
}

const float* optionalPlane(const Frame& f, const std::string& name) {
  return f.has(name) ? f.get(name).data() : nullptr;
}

const float* requiredPlane(const Frame& f, const std::string& name, const std::string& frameName,
                           const std::string& expected) {
  if (!f.has(name)) {
    throw InputError(frameName + ": error: no channel \"" + name + "\"; expected " + expected);
  }
  const auto& plane = f.get(name);
  if (plane.size() != f.pixelCount()) {
    throw InputError(frameName + ": error: channel \"" + name + "\" holds " + std::to_string(plane.size()) +
                     " values; expected " + std::to_string(f.pixelCount()) + " (width x height)");
  }
  return plane.data();
}

std::string metaString(const Frame& f, const char* key) {
  auto it = f.meta.find(key);
  if (it != f.meta.end() && it->is_string()) return it->get<std::string>();
  return "";
}

std::string firstName(const Frame& f, const char* key) {
  auto it = f.meta.find(key);
  if (it != f.meta.end() && it->is_array() && !it->empty() && (*it)[0].is_string()) return (*it)[0].get<std::string>();
  return "";
}

float clamp01(float v) { return v >= 0.0f ? (v <= 1.0f ? v : 1.0f) : 0.0f; }  // NaN -> 0

// Footprint m as a histogram key: non-negative floats order like their bit patterns.
float sanitizeM(float m) {
  if (!(m >= 0.0f)) return 0.0f;  // NaN, negative
  return std::min(m, std::numeric_limits<float>::max());
}
uint32_t floatBits(float v) {
  uint32_t b;
  std::memcpy(&b, &v, 4);
  return b;
}

// A buffer reused across calls on the same thread (a sweep compares hundreds of frames): saves
// the page faults of fresh multi-megabyte allocations. A thread waiting inside a TBB loop may run
// another task that calls compareFrames again, so a buffer already lent out is never shared: that
// nested call gets its own.
template <typename T>
class Scratch {
 public:
  explicit Scratch(size_t n) {
    Slot& slot = slot_();
    if (!slot.busy) {
      slot.busy = true;
      lent_ = &slot;
      slot.buffer.resize(n);
      data_ = slot.buffer.data();
    } else {
      own_.resize(n);
      data_ = own_.data();
    }
  }
  ~Scratch() {
    if (lent_) lent_->busy = false;
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  T* data() { return data_; }

 private:
  struct Slot {
    std::vector<T> buffer;
    bool busy = false;
  };
  static Slot& slot_() {
    thread_local Slot slot;
    return slot;
  }
  Slot* lent_ = nullptr;
  std::vector<T> own_;
  T* data_ = nullptr;
};

// The per-region and signed visibility sums of a block of rows (Metrics: regionMae, regionRmse,
// overShadowing, underShadowing, withinUncertainty). Both paths add a pixel's terms in pixel order;
// the context path skips the pixels whose clamped visibilities are equal, whose terms are +0.0.
struct VisibilitySums {
  std::array<uint64_t, kVisRegionCount> pixels{};
  std::array<double, kVisRegionCount> sumAbs{}, sumSq{};
  double over = 0, under = 0;
  uint64_t withinUncertainty = 0;
  // Pixel terms: d = R - S of the clamped visibilities (the same double as mae's).
  void addDifference(float referenceVisClamped, double d) {
    const size_t r = size_t(visRegion(referenceVisClamped));
    sumAbs[r] += std::fabs(d);
    sumSq[r] += d * d;
    over += d > 0.0 ? d : 0.0;
    under += d < 0.0 ? -d : 0.0;
  }
  void add(const VisibilitySums& o) {
    for (size_t r = 0; r < kVisRegionCount; ++r) {
      pixels[r] += o.pixels[r];
      sumAbs[r] += o.sumAbs[r];
      sumSq[r] += o.sumSq[r];
    }
    over += o.over;
    under += o.under;
    withinUncertainty += o.withinUncertainty;
  }
  // Into out (regionPixels given: the context keeps them), `compared` the pixels compared.
  void setMetrics(Metrics& out, const std::array<uint64_t, kVisRegionCount>& regionPixels, uint64_t compared) const {
    out.regionPixels = regionPixels;
    for (size_t r = 0; r < kVisRegionCount; ++r) {
      const double n = double(regionPixels[r]);
      out.regionMae[r] = regionPixels[r] ? sumAbs[r] / n : 0.0;
      out.regionRmse[r] = regionPixels[r] ? std::sqrt(sumSq[r] / n) : 0.0;
    }
    out.overShadowing = compared ? over / double(compared) : 0.0;
    out.underShadowing = compared ? under / double(compared) : 0.0;
    out.withinUncertainty = withinUncertainty;
  }
};

// compareFrames' pass-1 sums over one block of rows.
struct BlockSums {
  uint64_t compared = 0;
  PerPixelClass<uint64_t> counts{};  // final classes only: candidates are counted by pass 2
  uint64_t refShadow = 0, rasShadow = 0, bothShadow = 0;
  double sumAbs = 0, sumSq = 0;
  VisibilitySums vis;
  float mMax = 0, mMin = std::numeric_limits<float>::max();  // over m below the cap
  uint64_t mCapped = 0;
  uint64_t candidates = 0;
  float candidateLimitPx = 0;  // largest m (pixels per texel) over the candidates
  uint64_t projRef = 0, projRas = 0, projBoth = 0, reverse = 0;
  double projColorAbs = 0;
};

// ---- step 1: evidence ----------------------------------------------------------------------
// The channels compareFrames reads, as planes of width x height values; nullptr where an optional
// channel is missing. Plain pointers, so the pass-1 loop can hold a copy in registers.
struct Channels {
  const float *refHit = nullptr, *refObj = nullptr, *refVis = nullptr;
  // A sized light's truth: the standard error of refVis (soft mode, classify.h); nullptr: hard.
  const float* refSigma = nullptr;
  const float *rasHit = nullptr, *rasObj = nullptr, *rasVis = nullptr;
  // Evidence (optional: a reference compared with itself has none; see METRICS.md).
  const float *refOccDist = nullptr, *inMap = nullptr, *occId = nullptr, *recvDepth = nullptr, *mapDepth = nullptr,
              *biasDepth = nullptr, *biasWorld = nullptr;
  const float *momentMean = nullptr, *momentBound = nullptr;  // filterable maps only
  const float* m = nullptr;                                   // texel footprint, pixels per map texel
  // A frame from another renderer (CompareOptions::blind or meta kind "outside"): the blind rule,
  // with the declared map's contact distance (outside_frame.h prepareOutsideComparison).
  bool blind = false, declaredFilterable = false;
  const float* contact = nullptr;
  const float* cascade = nullptr;                             // only for cascaded frames (readChannels says why)
  int cascadeCount = 0;  // from the method, so that an empty cascade is still listed
  // Without a light (a projector-only scene), both decisions read this plane of ones: lit
  // everywhere, so no pixel can disagree about a shadow.
  std::vector<float> noLightVis;
  // The first projector, when both frames have its coverage.
  const float *refCov = nullptr, *rasCov = nullptr, *rasReverse = nullptr;
  const float* refRgb[3] = {nullptr, nullptr, nullptr};
  const float* rasRgb[3] = {nullptr, nullptr, nullptr};
  bool hasProjector = false, hasColor = false;

  // Pixel i's channels; compareFrames reads them only where the decisions disagree.
  PixelEvidence evidence(size_t i) const {
    PixelEvidence e;
    e.referenceHit = refHit[i] >= 0.5f;
    e.rasterHit = rasHit[i] >= 0.5f;
    e.referenceObject = refObj[i];
    e.rasterObject = rasObj[i];
    e.referenceVis = refVis[i];
    e.rasterVis = rasVis[i];
    e.softTruth = refSigma != nullptr;
    if (refSigma) e.referenceSigma = refSigma[i];
    e.hasInMap = inMap != nullptr;
    if (inMap) e.inMap = inMap[i];
    e.hasOccluderId = occId != nullptr;
    if (occId) e.occluderId = occId[i];
    e.hasDepths = recvDepth && mapDepth && biasDepth;
    if (e.hasDepths) {
      e.receiverDepth = recvDepth[i];
      e.mapDepth = mapDepth[i];
      e.biasDepth = biasDepth[i];
    }
    e.hasMoments = momentMean && momentBound;
    if (e.hasMoments) {
      e.momentMean = momentMean[i];
      e.momentBound = momentBound[i];
    }
    e.hasOccluderDistance = refOccDist && biasWorld;
    if (e.hasOccluderDistance) {
      e.referenceOccluderDist = refOccDist[i];
      e.biasWorld = biasWorld[i];
    }
    if (blind) {
      e.blind = true;
      e.declaredFilterable = declaredFilterable;
      e.hasTruthOccluderDistance = refOccDist != nullptr;
      if (refOccDist) e.truthOccluderDist = refOccDist[i];
      e.hasContact = contact != nullptr;
      if (contact) e.contactWorld = contact[i];
    }
    return e;
  }
};

// Validates everything before any work (throws InputError) and finds the channels.
Channels readChannels(const Frame& reference, const Frame& raster, const CompareOptions& options) {
  if (reference.width != raster.width || reference.height != raster.height) {
    throw InputError(both(options) + ": error: frame sizes differ: " + std::to_string(reference.width) + "x" +
                     std::to_string(reference.height) + " vs " + std::to_string(raster.width) + "x" +
                     std::to_string(raster.height) + "; expected the same camera resolution");
  }
  if (reference.width < 0 || reference.height < 0) {
    throw InputError(both(options) + ": error: negative frame size");
  }
  for (const char* key : {"scene_hash", "camera_hash"}) {
    std::string a = metaString(reference, key), b = metaString(raster, key);
    if (!a.empty() && !b.empty() && a != b) {
      throw InputError(both(options) + ": error: " + key + " differs: " + a + " vs " + b +
                       "; expected frames of the same scene and camera");
    }
  }
  if (!(options.boundaryTexels >= 0.0f && std::isfinite(options.boundaryTexels))) {
    throw InputError("compare: error: boundaryTexels is " + numberText(options.boundaryTexels) +
                     "; expected a finite number >= 0");
  }
  const std::string light = resolveCompareLight(reference, raster, options);
  const std::string lp = "light." + light + ".";
  const std::string expectLight = "a light named \"" + light + "\" (lights in this frame: ";
  Channels ch;
  ch.refHit = requiredPlane(reference, "hit", options.referenceName, "a renderer's output frame");
  ch.refObj = requiredPlane(reference, "object_id", options.referenceName, "a renderer's output frame");
  ch.rasHit = requiredPlane(raster, "hit", options.rasterName, "a renderer's output frame");
  ch.rasObj = requiredPlane(raster, "object_id", options.rasterName, "a renderer's output frame");
  if (light.empty()) {
    ch.noLightVis.assign(reference.pixelCount(), 1.0f);
    ch.refVis = ch.rasVis = ch.noLightVis.data();
  } else {
    ch.refVis = requiredPlane(reference, lp + "vis", options.referenceName,
                              expectLight + channelList(reference, "light.", ".vis") + ")");
    ch.rasVis = requiredPlane(raster, lp + "vis", options.rasterName,
                              expectLight + channelList(raster, "light.", ".vis") + ")");
  }
  // Evidence: optional, so that any two frames can be compared (a reference with itself has none).
  // Without it the corresponding classes cannot be proven; see METRICS.md.
  auto optional = [&](const Frame& f, const std::string& name) -> const float* {
    const float* p = optionalPlane(f, name);
    if (p && f.get(name).size() != f.pixelCount()) requiredPlane(f, name, "", "");  // throws
    return p;
  };
  if (!light.empty()) {  // the light's evidence; a projector-only frame has none
    ch.refSigma = optional(reference, lp + "vis_sigma");
    ch.refOccDist = optional(reference, lp + "occluder_dist");
    ch.inMap = optional(raster, lp + "in_map");
    ch.occId = optional(raster, lp + "occluder_id");
    ch.recvDepth = optional(raster, lp + "receiver_depth");
    ch.mapDepth = optional(raster, lp + "map_depth");
    ch.biasDepth = optional(raster, lp + "bias_depth");
    ch.biasWorld = optional(raster, lp + "bias_world");
    ch.m = optional(raster, lp + "m");
    ch.momentMean = optional(raster, lp + "moment_mean");
    ch.momentBound = optional(raster, lp + "moment_bound");
    ch.blind = options.blind || metaString(raster, "kind") == "outside";
    ch.declaredFilterable = ch.blind && options.declaredFilterable;
    if (ch.blind) ch.contact = optional(raster, lp + "contact_world");
    // Per-cascade metrics: only for cascaded frames, so every other row keeps its keys (the channel
    // is 0 everywhere for the other fits). Frames built in code without metadata count as cascaded.
    ch.cascade = optional(raster, lp + "cascade");
    if (ch.cascade) {
      auto method = raster.meta.find("method");
      if (method != raster.meta.end() && method->is_object()) {
        auto fit = method->find("fit");
        if (fit != method->end() && fit->is_string()) {
          const KindInfo<Fit>* kind = findKind(fitKinds(), fit->get<std::string>());
          if (!kind || !isCascadedFit(kind->kind)) ch.cascade = nullptr;
        }
        auto count = method->find("cascades.count");
        if (count != method->end() && count->is_number_integer()) ch.cascadeCount = std::clamp(count->get<int>(), 0, 8);
      }
    }
  }

  std::string projector = firstName(reference, "projectors");
  if (projector.empty()) projector = firstName(raster, "projectors");
  if (projector.empty()) {
    // Frames without metadata: the first projector channel of the reference.
    for (const auto& n : reference.names) {
      if (n.size() > 14 && n.compare(0, 5, "proj.") == 0 && n.compare(n.size() - 9, 9, ".coverage") == 0) {
        projector = n.substr(5, n.size() - 14);
        break;
      }
    }
  }
  const std::string pp = "proj." + projector + ".";
  ch.refCov = projector.empty() ? nullptr : optional(reference, pp + "coverage");
  ch.rasCov = projector.empty() ? nullptr : optional(raster, pp + "coverage");
  ch.hasProjector = ch.refCov && ch.rasCov;
  ch.rasReverse = ch.hasProjector ? optional(raster, pp + "reverse") : nullptr;
  ch.hasColor = ch.hasProjector;
  for (int c = 0; c < 3 && ch.hasProjector; ++c) {
    const std::string name = pp + "RGB"[c];
    ch.refRgb[c] = optional(reference, name);
    ch.rasRgb[c] = optional(raster, name);
    ch.hasColor = ch.hasColor && ch.refRgb[c] && ch.rasRgb[c];
  }
  return ch;
}

}  // namespace

// ---- step 2: the class of one pixel: in classify.h (inline: pass 1 calls it for every pixel) --

// ---- step 3: tallies ---------------------------------------------------------------------------

PerPixelClass<uint64_t> countClasses(const std::vector<PixelClass>& classes) {
  PerPixelClass<uint64_t> counts{};
  for (PixelClass k : classes) {
    if (size_t(k) >= kPixelClassCount) {
      throw InputError("classification: error: pixel class code " + std::to_string(int(k)) +
                       " is not in the class table; expected 0.." + std::to_string(kPixelClassCount - 1));
    }
    ++counts[classIndex(k)];
  }
  return counts;
}

void setClassMetrics(Metrics& m, const PerPixelClass<uint64_t>& counts) {
  m.classCounts = counts;
  uint64_t compared = counts[classIndex(PixelClass::Correct)], errors = 0;
  for (const PixelClassInfo& c : kPixelClasses) {
    if (!c.error) continue;
    errors += counts[classIndex(c.cls)];
    compared += counts[classIndex(c.cls)];
  }
  m.pixelsCompared = compared;
  m.errors = errors;
  const double denom = double(compared);
  auto rate = [&](uint64_t count) { return compared ? double(count) / denom : 0.0; };
  m.errorRate = rate(errors);
  for (size_t k = 0; k < kPixelClassCount; ++k) m.classRates[k] = rate(counts[k]);
}

namespace {

// Whether pixel x of row d (rows du above, dd below: d itself at the image's edge) is a boundary
// pixel: compared, with a compared 4-neighbour of the other decision. Decisions are 1 (lit) and 2
// (shadowed), 0 for not compared: two pixels hold different decisions, both compared, exactly
// when their xor is 3.
inline bool isBoundary(const uint8_t* d, const uint8_t* du, const uint8_t* dd, int x, int width) {
  const uint8_t c = d[x];
  return (c ^ du[x]) == 3 || (c ^ dd[x]) == 3 || (x > 0 && (c ^ d[x - 1]) == 3) ||
         (x + 1 < width && (c ^ d[x + 1]) == 3);
}

// One row's lower envelope of the parabolas (x - q)^2 + g[q]^2, q in [q0, q1) (Felzenszwalb &
// Huttenlocher 2012): v[k] the k-th parabola's q, z[k]..z[k + 1] where it is the lowest. Both
// distance transforms below (pass 2's, bounded to the candidates' reach, and CompareContext's
// whole image) walk it left to right.
template <typename T>
void lowerEnvelope(const T* g, int q0, int q1, int* v, double* z) {
  auto f = [&](int q) { return double(g[q]) * double(g[q]); };
  auto intersect = [&](int q, int p) { return ((f(q) + double(q) * q) - (f(p) + double(p) * p)) / (2.0 * (q - p)); };
  int k = 0;
  v[0] = q0;
  z[0] = -std::numeric_limits<double>::infinity();
  z[1] = std::numeric_limits<double>::infinity();
  for (int q = q0 + 1; q < q1; ++q) {
    double sq = intersect(q, v[k]);
    while (sq <= z[k]) {  // z[0] = -inf stops this at k = 0
      --k;
      sq = intersect(q, v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = sq;
    z[k + 1] = std::numeric_limits<double>::infinity();
  }
}

// Pass 2: aliasing = remaining disagreements near a reference shadow boundary; resolves every
// candidate of `klass` and adds its class to `counts`.
// Boundary pixels: compared pixels with a 4-neighbour compared pixel of the other reference
// decision. Their exact Euclidean distance transform (Meijster et al. 2000: column scans, then
// per row the lower envelope of parabolas of Felzenszwalb & Huttenlocher 2012), in pixels.
// Only distances up to the largest candidate limit (boundaryTexels * m) matter, which bounds the
// rows and columns the transform has to visit; larger distances may come out overestimated, but
// only beyond every limit, so no class changes.
void resolveCandidates(uint8_t* klass, const uint8_t* decision, const float* mPlane, int width, int height,
                       float boundaryTexels, PerPixelClass<uint64_t>& total) {
  const size_t n = size_t(width) * size_t(height);
  // Per row: the reach (largest limit in pixels, rounded up) of its candidates whose limit is
  // shorter than the image diagonal; a candidate with a longer limit (m is huge near the
  // horizon) is within it of any boundary pixel, so it needs no distance at all, only whether
  // a boundary exists anywhere.
  const double diagonalPx = std::sqrt(double(width) * width + double(height) * height);
  auto limitPx = [&](size_t i) {
    const double texels = klass[i] == kCandidateAcne ? double(kBlindAcneBandTexels) : double(boundaryTexels);
    return texels * (mPlane ? double(sanitizeM(mPlane[i])) : 1.0);
  };
  std::vector<int> rowReach(size_t(height), -1);  // -1: no candidate that needs a distance
  std::vector<uint8_t> rowHasCandidate(size_t(height), 0), rowHasBoundary(size_t(height), 0);
  tbb::parallel_for(0, height, [&](int y) {
    const uint8_t* krow = klass + size_t(y) * width;
    const uint8_t* d = decision + size_t(y) * width;
    const uint8_t* dd = y + 1 < height ? d + width : d;
    uint8_t any = 0, boundary = 0;
    int reachRow = -1;
    for (int x = 0; x < width; ++x) {
      boundary |= ((d[x] ^ dd[x]) == 3) | (x + 1 < width && (d[x] ^ d[x + 1]) == 3);
      if (krow[x] < kFirstCandidate) continue;
      any = 1;
      const double limit = limitPx(size_t(y) * width + x);
      if (limit < diagonalPx) reachRow = std::max(reachRow, int(std::ceil(limit)));
    }
    rowHasCandidate[size_t(y)] = any;
    rowHasBoundary[size_t(y)] = boundary;
    rowReach[size_t(y)] = reachRow;
  });
  const bool anyBoundary = std::find(rowHasBoundary.begin(), rowHasBoundary.end(), 1) != rowHasBoundary.end();
  int reach = 0;                           // the largest row reach: caps g
  std::vector<std::pair<int, int>> bands;  // [y0, y1) row intervals to scan
  for (int y = 0; y < height; ++y) {
    const int r = rowReach[size_t(y)];
    if (r < 0) continue;
    reach = std::max(reach, r + 1);
    const int y0 = std::max(0, y - r - 1), y1 = std::min(height, y + r + 2);
    if (!bands.empty() && y0 <= bands.back().second) bands.back().second = std::max(bands.back().second, y1);
    else bands.emplace_back(y0, y1);
  }
  // g = vertical distance to the nearest boundary pixel within the band, capped at `far`.
  const uint16_t far = uint16_t(std::min(reach + 1, 65535));
  Scratch<uint16_t> gScratch(n);
  uint16_t* g = gScratch.data();
  constexpr int kStrip = 512;
  const int strips = (width + kStrip - 1) / kStrip;
  tbb::parallel_for(0, int(bands.size()) * strips, [&](int job) {
    const auto [y0, y1] = bands[size_t(job / strips)];
    const int x0 = (job % strips) * kStrip, x1 = std::min(width, x0 + kStrip);
    for (int y = y0; y < y1; ++y) {
      const uint8_t* d = decision + size_t(y) * width;
      const uint8_t* du = y > 0 ? d - width : d;  // out of the image: itself, never "different"
      const uint8_t* dd = y + 1 < height ? d + width : d;
      uint16_t* row = g + size_t(y) * width;
      const uint16_t* above = y > y0 ? row - width : nullptr;
      for (int x = x0; x < x1; ++x) {
        const bool boundary = isBoundary(d, du, dd, x, width);
        const uint16_t up = above ? uint16_t(std::min<int>(far, above[x] + 1)) : far;
        row[x] = boundary ? uint16_t(0) : up;
      }
    }
    for (int y = y1 - 2; y >= y0; --y) {
      uint16_t* row = g + size_t(y) * width;
      const uint16_t* below = row + width;
      for (int x = x0; x < x1; ++x) row[x] = uint16_t(std::min<int>(row[x], below[x] + 1));  // <= far
    }
  });
  std::vector<PerPixelClass<uint64_t>> rowCounts(size_t(height), PerPixelClass<uint64_t>{});
  struct RowScratch {
    std::vector<int> v;
    std::vector<double> z;
  };
  tbb::enumerable_thread_specific<RowScratch> scratch;
  tbb::parallel_for(0, height, [&](int y) {
    if (!rowHasCandidate[size_t(y)]) return;
    uint8_t* krow = klass + size_t(y) * width;
    PerPixelClass<uint64_t>& counts = rowCounts[size_t(y)];
    auto resolve = [&](int x, bool withinLimit) {
      const PixelClass c = resolveCandidateCode(krow[x], withinLimit);
      krow[x] = uint8_t(c);
      ++counts[classIndex(c)];
    };
    const int r = rowReach[size_t(y)];
    int xFirst = width, xLast = -1;
    for (int x = 0; x < width; ++x) {
      if (krow[x] < kFirstCandidate) continue;
      if (limitPx(size_t(y) * width + x) >= diagonalPx) {
        resolve(x, anyBoundary);
      } else {
        xFirst = std::min(xFirst, x);
        xLast = x;
      }
    }
    if (r < 0 || xLast < 0) return;
    // Columns farther than the reach from every candidate cannot bring a distance under a limit.
    const int q0 = std::max(0, xFirst - r - 1), q1 = std::min(width, xLast + r + 2);
    const uint16_t* grow = g + size_t(y) * width;
    RowScratch& rs = scratch.local();
    rs.v.resize(size_t(q1 - q0));
    rs.z.resize(size_t(q1 - q0) + 1);
    int* v = rs.v.data();
    double* z = rs.z.data();
    auto f = [&](int q) { return double(grow[q]) * double(grow[q]); };
    lowerEnvelope(grow, q0, q1, v, z);
    int k = 0;
    for (int x = xFirst; x <= xLast; ++x) {
      while (z[k + 1] < x) ++k;
      if (krow[x] < kFirstCandidate) continue;  // not a candidate, or resolved above
      const int p = v[k];
      const double dist2 = double(x - p) * double(x - p) + f(p);
      const double limit = limitPx(size_t(y) * width + x);
      resolve(x, dist2 <= limit * limit);
    }
  });
  for (const auto& rc : rowCounts)
    for (size_t k = 0; k < kPixelClassCount; ++k) total[k] += rc[k];
}

// Per-cascade metrics; after pass 2, so `klass` holds every pixel's final class. Cascade indices
// come from a float channel: anything not an integer 0..7 (NaN included) is read as the nearest
// valid index.
std::vector<CascadeMetrics> cascadeMetrics(const uint8_t* klass, const uint8_t* decision, const Channels& ch,
                                           size_t n) {
  constexpr int kMaxCascades = 8;
  int cascadeCount = ch.cascadeCount;
  std::vector<uint64_t> pixels(kMaxCascades, 0), errors(kMaxCascades, 0);
  std::vector<std::vector<float>> mValues(kMaxCascades);
  for (size_t i = 0; i < n; ++i) {
    if (decision[i] == kDecisionNone) continue;  // not compared
    const float v = ch.cascade[i];
    const int k = v >= 0.0f ? (v < float(kMaxCascades - 1) ? int(v + 0.5f) : kMaxCascades - 1) : 0;
    ++pixels[size_t(k)];
    errors[size_t(k)] += isErrorClass(PixelClass(klass[i]));
    if (ch.m && sanitizeM(ch.m[i]) < kFootprintCapPx) mValues[size_t(k)].push_back(sanitizeM(ch.m[i]));
    cascadeCount = std::max(cascadeCount, k + 1);
  }
  std::vector<CascadeMetrics> out;
  for (int k = 0; k < cascadeCount; ++k) {
    CascadeMetrics c;
    c.index = k;
    c.pixels = pixels[size_t(k)];
    c.errors = errors[size_t(k)];
    c.errorRate = c.pixels ? double(c.errors) / double(c.pixels) : 0.0;
    std::vector<float>& m = mValues[size_t(k)];
    if (!m.empty()) {  // nearest rank, as m_p95: sorted index ceil(0.95 N) - 1
      const size_t rank = size_t(std::ceil(0.95 * double(m.size()))) - 1;
      std::nth_element(m.begin(), m.begin() + std::ptrdiff_t(rank), m.end());
      c.mP95 = double(m[rank]);
    }
    out.push_back(c);
  }
  return out;
}

// m quantiles, exact, in linear time: a histogram of the 16 high bits of the float (non-negative
// floats order like their bit patterns), made in pass 1, finds the bins that hold the ranks, then
// a selection among the values of those bins. Nearest rank: the value at sorted index
// ceil(p * N) - 1, N = `compared`: the compared pixels below the footprint cap. Sets out.mMedian and
// out.mP95.
void setFootprintQuantiles(Metrics& out, const std::vector<uint64_t>& high, uint64_t compared,
                           const std::vector<BlockSums>& sums, const uint8_t* decision, const float* mPlane, int width,
                           size_t n) {
  const double ps[2] = {0.5, 0.95};
  uint64_t rank[2];
  uint32_t bin[2];
  for (int q = 0; q < 2; ++q) {
    rank[q] = uint64_t(std::ceil(ps[q] * double(compared)));
    rank[q] = rank[q] > 0 ? rank[q] - 1 : 0;
    uint32_t b = 0;
    for (; b < 65535; ++b) {
      if (high[b] > rank[q]) break;
      rank[q] -= high[b];
    }
    bin[q] = b;  // rank[q] is now the rank within that bin
  }
  // Second level: the values of those two bins (a small share of the pixels), then the k-th
  // smallest of each. The k-th smallest of a multiset does not depend on the order the threads
  // appended the values in: deterministic.
  tbb::enumerable_thread_specific<std::array<std::vector<float>, 2>> inBins;
  tbb::parallel_for(0, int(sums.size()), [&](int b) {
    // m is smooth over the image: many blocks hold no value of either bin.
    const uint32_t lo = floatBits(sums[size_t(b)].mMin) >> 16, hi = floatBits(sums[size_t(b)].mMax) >> 16;
    if (sums[size_t(b)].compared == 0 || ((bin[0] < lo || bin[0] > hi) && (bin[1] < lo || bin[1] > hi))) return;
    auto& values = inBins.local();
    const size_t begin = size_t(b) * kBlockRows * width;
    const size_t end = std::min(n, size_t(b + 1) * kBlockRows * width);
    for (size_t i = begin; i < end; ++i) {
      if (decision[i] == kDecisionNone) continue;
      const float m = sanitizeM(mPlane[i]);
      if (m >= kFootprintCapPx) continue;  // capped: not in the statistics
      const uint32_t key = floatBits(m) >> 16;
      if (key == bin[0]) values[0].push_back(m);
      if (key == bin[1]) values[1].push_back(m);
    }
  });
  double value[2];
  for (int q = 0; q < 2; ++q) {
    std::vector<float> all;
    for (auto& v : inBins) all.insert(all.end(), v[size_t(q)].begin(), v[size_t(q)].end());
    if (rank[q] >= all.size()) throw DriverError("compare: m quantile bin holds fewer values than counted");
    std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(rank[q]), all.end());
    value[q] = double(all[size_t(rank[q])]);
  }
  out.mMedian = value[0];
  out.mP95 = value[1];
}

}  // namespace

std::string resolveCompareLight(const Frame& reference, const Frame& raster, const CompareOptions& options) {
  if (!options.light.empty()) return options.light;
  std::string l = metaString(raster, "light");
  if (!l.empty()) return l;
  l = firstName(raster, "lights");
  if (!l.empty()) return l;
  l = firstName(reference, "lights");
  if (!l.empty()) return l;
  // Frames without metadata (built in code): the first light channel of the reference.
  for (const auto& n : reference.names) {
    if (n.size() > 10 && n.compare(0, 6, "light.") == 0 && n.compare(n.size() - 4, 4, ".vis") == 0) {
      return n.substr(6, n.size() - 10);
    }
  }
  // A projector-only scene (projective texturing): "" = no light; the projectors are compared.
  if (!firstName(reference, "projectors").empty()) return "";
  for (const auto& n : reference.names)
    if (n.compare(0, 5, "proj.") == 0) return "";
  throw InputError(both(options) +
                   ": error: nothing to compare: no \"light.NAME.vis\" channel, no light named in "
                   "the metadata and no projector; expected a frame rendered with at least one light or projector");
}

Metrics compareFrames(const Frame& reference, const Frame& raster, const CompareOptions& options,
                      Classification* classification) {
  // ---- step 1: evidence (validate everything before any work) --------------------------------
  const Channels channels = readChannels(reference, raster, options);

  // ---- pass 1: per pixel, step 2 where the local evidence decides, step 3's sums -------------
  const int width = reference.width, height = reference.height;
  const size_t n = reference.pixelCount();
  Classification local;
  Classification& cls = classification ? *classification : local;
  cls.width = width;
  cls.height = height;
  cls.classes.resize(n);
  cls.referenceLit.resize(n);
  Scratch<uint8_t> decisionScratch(n);
  uint8_t* decision = decisionScratch.data();
  uint8_t* klass = reinterpret_cast<uint8_t*>(cls.classes.data());
  uint8_t* refLit = cls.referenceLit.data();
  const float leakFactor = options.leakBiasFactor;

  const int blocks = (height + kBlockRows - 1) / kBlockRows;
  std::vector<BlockSums> sums(size_t(std::max(blocks, 0)));
  tbb::enumerable_thread_specific<std::vector<uint32_t>> mHistLocal(
      [&] { return std::vector<uint32_t>(channels.m ? 65536 : 0, 0); });

  tbb::parallel_for(0, blocks, [&](int b) {
    BlockSums s;
    // Local copies: the byte stores below may alias anything, and pointers reached through the
    // lambda's captures would be reloaded after every one of them.
    const Channels ch = channels;
    const float* const refHit_ = ch.refHit;
    const float* const rasHit_ = ch.rasHit;
    const float* const refObj_ = ch.refObj;
    const float* const rasObj_ = ch.rasObj;
    const float* const refVis_ = ch.refVis;
    const float* const rasVis_ = ch.rasVis;
    const float* const mPlane_ = ch.m;
    const float* const refSigma_ = ch.refSigma;
    uint8_t* const klass_ = klass;
    uint8_t* const refLit_ = refLit;
    uint8_t* const decision_ = decision;
    uint32_t* hist = mPlane_ ? mHistLocal.local().data() : nullptr;
    // m is smooth over the image, so neighbours share a histogram bin: count runs in a register
    // instead of incrementing the same memory counter back to back (a store-to-load chain).
    uint32_t runBin = 0, runLength = 0;
    const size_t begin = size_t(b) * kBlockRows * width;
    const size_t end = std::min(n, size_t(b + 1) * kBlockRows * width);
    for (size_t i = begin; i < end; ++i) {
      const bool hr = refHit_[i] >= 0.5f, hs = rasHit_[i] >= 0.5f;
      refLit_[i] = 0;
      decision_[i] = kDecisionNone;
      const PixelClass scored = scoredClass(hr, hs, refObj_[i], rasObj_[i]);
      if (scored != PixelClass::Correct) {  // not compared, geometry mismatch
        klass_[i] = uint8_t(scored);
        ++s.counts[classIndex(scored)];
        continue;
      }
      ++s.compared;
      const float rv = clamp01(refVis_[i]), sv = clamp01(rasVis_[i]);
      const bool rLit = litDecision(refVis_[i]), sLit = litDecision(rasVis_[i]);
      refLit_[i] = rLit;
      decision_[i] = rLit ? kDecisionLit : kDecisionShadowed;
      const double d = double(rv) - double(sv);
      s.sumAbs += std::fabs(d);
      s.sumSq += d * d;
      ++s.vis.pixels[size_t(visRegion(rv))];
      s.vis.addDifference(rv, d);
      s.refShadow += !rLit;
      s.rasShadow += !sLit;
      s.bothShadow += !rLit && !sLit;
      float m = 0.0f;
      if (mPlane_) {
        m = sanitizeM(mPlane_[i]);
        if (m >= kFootprintCapPx) {
          ++s.mCapped;  // no footprint to describe: out of the statistics (still the aliasing limit)
        } else {
          s.mMax = std::max(s.mMax, m);
          s.mMin = std::min(s.mMin, m);
          const uint32_t bin = floatBits(m) >> 16;
          if (bin != runBin) {
            hist[runBin] += runLength;
            runBin = bin;
            runLength = 0;
          }
          ++runLength;
        }
      }
      if (ch.hasProjector) {
        const float rc = clamp01(ch.refCov[i]), sc = clamp01(ch.rasCov[i]);
        const bool rIn = rc >= 0.5f, sIn = sc >= 0.5f;
        s.projRef += rIn;
        s.projRas += sIn;
        s.projBoth += rIn && sIn;
        if (ch.rasReverse && ch.rasReverse[i] >= 0.5f && sc > 0.0f) ++s.reverse;
        if (ch.hasColor) {
          double err = 0;
          for (int c = 0; c < 3; ++c) err += std::fabs(double(ch.refRgb[c][i]) - double(ch.rasRgb[c][i]));
          s.projColorAbs += std::isfinite(err) ? err / 3.0 : 1.0;
        }
      }
      PixelClass c = PixelClass::Correct;
      bool disagreement = rLit != sLit;
      if (refSigma_) {  // a sized light: soft mode (classify.h softDecision)
        const SoftDecision sd = softDecision(rv, sv, sanitizeSigma(refSigma_[i]));
        s.vis.withinUncertainty += sd == SoftDecision::WithinUncertainty;
        disagreement = sd == SoftDecision::Error;
      }
      if (disagreement) {
        const DisagreementClass dc = classifyAnyDisagreement(ch.evidence(i), leakFactor);
        if (dc.candidate) {
          // Aliasing or, beyond the boundary band, leak (with its evidence) or other: pass 2.
          klass_[i] = candidateCode(dc);
          ++s.candidates;
          s.candidateLimitPx = std::max(s.candidateLimitPx, mPlane_ ? m : 1.0f);
          continue;
        }
        c = dc.cls;
      }
      ++s.counts[classIndex(c)];
      klass_[i] = uint8_t(c);
    }
    if (hist) hist[runBin] += runLength;
    sums[size_t(b)] = s;
  });

  BlockSums t;
  for (const auto& s : sums) {
    t.compared += s.compared;
    for (size_t k = 0; k < kPixelClassCount; ++k) t.counts[k] += s.counts[k];
    t.refShadow += s.refShadow;
    t.rasShadow += s.rasShadow;
    t.bothShadow += s.bothShadow;
    t.sumAbs += s.sumAbs;
    t.sumSq += s.sumSq;
    t.vis.add(s.vis);
    t.mMax = std::max(t.mMax, s.mMax);
    t.mCapped += s.mCapped;
    t.candidates += s.candidates;
    t.candidateLimitPx = std::max(t.candidateLimitPx, s.candidateLimitPx);
    t.projRef += s.projRef;
    t.projRas += s.projRas;
    t.projBoth += s.projBoth;
    t.reverse += s.reverse;
    t.projColorAbs += s.projColorAbs;
  }

  // ---- pass 2: the boundary distance resolves the candidates (step 2's last decision) -------
  if (t.candidates > 0) resolveCandidates(klass, decision, channels.m, width, height, options.boundaryTexels, t.counts);

  // ---- step 3: tallies into metrics ----------------------------------------------------------
  Metrics out;
  setClassMetrics(out, t.counts);
  if (out.pixelsCompared != t.compared) {
    throw DriverError("compare: " + std::to_string(out.pixelsCompared) + " pixels classified as compared, " +
                      std::to_string(t.compared) + " counted; expected the same");
  }
  if (channels.cascade) out.cascades = cascadeMetrics(klass, decision, channels, n);
  const double denom = double(t.compared);
  const uint64_t shadowUnion = t.refShadow + t.rasShadow - t.bothShadow;
  out.shadowIou = shadowUnion ? double(t.bothShadow) / double(shadowUnion) : 1.0;
  out.mae = t.compared ? t.sumAbs / denom : 0.0;
  out.rmse = t.compared ? std::sqrt(t.sumSq / denom) : 0.0;
  t.vis.setMetrics(out, t.vis.pixels, t.compared);
  out.mCapped = t.mCapped;
  if (channels.m && t.compared > t.mCapped) {
    std::vector<uint64_t> high(65536, 0);
    for (const auto& h : mHistLocal)
      for (size_t k = 0; k < h.size(); ++k) high[k] += h[k];
    setFootprintQuantiles(out, high, t.compared - t.mCapped, sums, decision, channels.m, width, n);
    out.mMax = t.mMax;
  }
  out.hasProjector = channels.hasProjector;
  out.lightCompared = channels.noLightVis.empty();
  if (channels.hasProjector) {
    const uint64_t u = t.projRef + t.projRas - t.projBoth;
    out.projectorCoverageIou = u ? double(t.projBoth) / double(u) : 1.0;
    out.reverseProjectionPixels = t.reverse;
    out.projectorColorMae = t.compared && channels.hasColor ? t.projColorAbs / denom : 0.0;
  }
  return out;
}

// ---- a group's constant planes (compare.h, CompareContext) ----------------------------------

struct CompareContext::Data {
  int width = 0, height = 0;
  std::string group, light;
  CompareOptions options;
  // The reference the context was built from: its `vis` plane (identity, not contents).
  const float* referenceVis = nullptr;
  // Which optional planes the raster frames of the group carry (readChannels), so that a frame
  // with others takes the full path.
  bool hasM = false, hasCascade = false;
  int cascadeCount = 0;
  static constexpr uint8_t kFractional = 4;
  // What depends on the reference, the light and the geometry (the hit and object planes of both
  // frames) alone, not on the group's m and cascades: shared by the contexts of every group of one
  // camera (the constructor's `sameGeometry`).
  struct Pixels {
    // Per pixel: kDecisionNone (not compared), kDecisionLit, kDecisionShadowed, plus kFractional
    // where the clamped reference vis is neither 0 nor 1 (a frame reads referenceVisClamped only
    // there: 5 bytes per pixel in all with the raster vis); clamp01 of the reference vis (0 where
    // not compared); the class before the decisions (not compared, geometry mismatch, Correct for
    // compared pixels); whether the reference decides lit.
    std::vector<uint8_t> decision;
    std::vector<float> referenceVisClamped;
    std::vector<uint8_t> scoredClass;
    std::vector<uint8_t> referenceLit;
    // Exact squared distance (pixels^2) from each pixel to the nearest boundary pixel (pass 2's
    // definition), clamped to UINT32_MAX (only compared with limits under the image diagonal).
    std::vector<uint32_t> boundaryDist2;
    bool anyBoundary = false;
    PerPixelClass<uint64_t> scoredCounts{};  // not compared and geometry mismatch
    uint64_t compared = 0, referenceShadow = 0;
  };
  std::shared_ptr<const Pixels> pixels;
  // Compared pixels per region of the truth (they depend on the reference and the scored pixels).
  std::array<uint64_t, kVisRegionCount> regionPixels{};
  // The group's own: m's statistics and the cascades.
  double mMedian = 0, mP95 = 0, mMax = 0;
  uint64_t mCapped = 0;
  std::vector<CascadeMetrics> cascades;  // pixels and m_p95; errors 0
};

namespace {

// Boundary pixels as pass 2 defines them (resolveCandidates) and the exact squared Euclidean
// distance transform to them (Meijster et al.: column scans, then per row the lower envelope of
// parabolas, as resolveCandidates does within its bands), over the whole image.
void boundaryDistances(const uint8_t* decision, int width, int height, std::vector<uint32_t>& out, bool* anyBoundary) {
  const size_t n = size_t(width) * size_t(height);
  // Vertical distance to the nearest boundary pixel of the column; `none` when the column has none
  // (larger than any distance in the image, so the envelope treats it as infinite).
  const uint32_t none = uint32_t(width) + uint32_t(height) + 1;
  std::vector<uint32_t> g(n);
  std::vector<uint8_t> columnHasBoundary(size_t(std::max(width, 0)), 0);
  constexpr int kStrip = 256;
  const int strips = (width + kStrip - 1) / kStrip;
  tbb::parallel_for(0, strips, [&](int job) {
    const int x0 = job * kStrip, x1 = std::min(width, x0 + kStrip);
    for (int y = 0; y < height; ++y) {
      const uint8_t* d = decision + size_t(y) * width;
      const uint8_t* du = y > 0 ? d - width : d;
      const uint8_t* dd = y + 1 < height ? d + width : d;
      uint32_t* row = g.data() + size_t(y) * width;
      const uint32_t* above = y > 0 ? row - width : nullptr;
      for (int x = x0; x < x1; ++x) {
        const bool boundary = isBoundary(d, du, dd, x, width);
        columnHasBoundary[size_t(x)] |= boundary;
        row[x] = boundary ? 0u : above ? std::min(none, above[x] + 1) : none;
      }
    }
    for (int y = height - 2; y >= 0; --y) {
      uint32_t* row = g.data() + size_t(y) * width;
      const uint32_t* below = row + width;
      for (int x = x0; x < x1; ++x) row[x] = std::min(row[x], below[x] + 1);
    }
  });
  *anyBoundary = std::find(columnHasBoundary.begin(), columnHasBoundary.end(), 1) != columnHasBoundary.end();
  out.assign(n, std::numeric_limits<uint32_t>::max());
  if (!*anyBoundary) return;
  struct RowScratch {
    std::vector<int> v;
    std::vector<double> z;
  };
  tbb::enumerable_thread_specific<RowScratch> scratch;
  tbb::parallel_for(0, height, [&](int y) {
    const uint32_t* grow = g.data() + size_t(y) * width;
    RowScratch& rs = scratch.local();
    rs.v.resize(size_t(width));
    rs.z.resize(size_t(width) + 1);
    int* v = rs.v.data();
    double* z = rs.z.data();
    auto f = [&](int q) { return double(grow[q]) * double(grow[q]); };
    lowerEnvelope(grow, 0, width, v, z);
    int k = 0;
    uint32_t* orow = out.data() + size_t(y) * width;
    for (int x = 0; x < width; ++x) {
      while (z[k + 1] < x) ++k;
      const int p = v[k];
      const double dist2 = double(x - p) * double(x - p) + f(p);
      orow[x] = dist2 < 4294967295.0 ? uint32_t(dist2) : std::numeric_limits<uint32_t>::max();
    }
  });
}

// The channels of these frames when `data` applies to them (CompareContext::appliesTo), else false.
bool contextChannels(const CompareContext::Data* data, const Frame& reference, const Frame& raster, Channels* out) {
  if (!data || data->group.empty()) return false;
  if (raster.width != data->width || raster.height != data->height || reference.width != data->width ||
      reference.height != data->height)
    return false;
  if (metaString(raster, "evidence_group") != data->group) return false;
  const std::string lp = "light." + data->light + ".vis";
  if (!reference.has(lp) || reference.get(lp).data() != data->referenceVis) return false;
  if (resolveCompareLight(reference, raster, data->options) != data->light) return false;
  Channels ch = readChannels(reference, raster, data->options);  // validates as the full path does
  if (ch.hasProjector || !ch.noLightVis.empty() || (ch.m != nullptr) != data->hasM ||
      (ch.cascade != nullptr) != data->hasCascade || ch.cascadeCount != data->cascadeCount)
    return false;
  *out = std::move(ch);
  return true;
}

// The per-frame sums of the context path over one block of rows (the same blocks as pass 1).
struct ContextBlockSums {
  PerPixelClass<uint64_t> counts{};  // the disagreeing pixels' final classes
  uint64_t disagreements = 0, rasShadow = 0, bothShadow = 0;
  double sumAbs = 0, sumSq = 0;
  VisibilitySums vis;
  std::array<uint64_t, 8> cascadeErrors{};
};

}  // namespace

namespace {

// A final class's scored class (scoredClass in classify.h): not compared and geometry mismatch
// stay, every compared pixel's is Correct.
bool isCompared(PixelClass c) { return c != PixelClass::NotCompared && c != PixelClass::GeometryMismatch; }
uint8_t scoredOf(PixelClass c) { return uint8_t(isCompared(c) ? PixelClass::Correct : c); }

// Whether `scored` (a context's scoredClass) is the scored class of every pixel of `classes` (a
// full classification): then both pairs of frames compare the same pixels.
bool sameScoredClasses(const std::vector<uint8_t>& scored, const std::vector<PixelClass>& classes) {
  if (scored.size() != classes.size()) return false;
  uint8_t differ = 0;
  for (size_t i = 0; i < scored.size(); ++i) differ |= uint8_t(scored[i] ^ scoredOf(classes[i]));
  return differ == 0;
}

}  // namespace

CompareContext::CompareContext(const Frame& reference, const Frame& raster, const CompareOptions& options,
                               const CompareContext* sameGeometry, Metrics* metrics)
    : options_(options) {
  const Channels ch = readChannels(reference, raster, options);  // throws as compareFrames does
  const std::string group = metaString(raster, "evidence_group");
  const int width = reference.width, height = reference.height;
  const double diagonal2 = double(width) * width + double(height) * height;
  // Without a group, with projectors or without a light the full path runs every time; so does a
  // frame whose squared diagonal does not fit the distances' 32 bits.
  if (group.empty() || ch.hasProjector || !ch.noLightVis.empty() || !(diagonal2 < 4.0e9)) {
    if (metrics) *metrics = compareFrames(reference, raster, options);
    return;
  }
  auto d = std::make_shared<Data>();
  d->width = width;
  d->height = height;
  d->group = group;
  d->options = options;
  d->light = resolveCompareLight(reference, raster, options);
  d->referenceVis = ch.refVis;
  d->hasM = ch.m != nullptr;
  d->hasCascade = ch.cascade != nullptr;
  d->cascadeCount = ch.cascadeCount;
  // The constant parts come from the full path itself: the same classes, m statistics, cascades.
  Classification cls;
  const Metrics full = compareFrames(reference, raster, options, &cls);
  if (metrics) *metrics = full;
  const Data* same = sameGeometry ? sameGeometry->data_.get() : nullptr;
  if (same && same->width == width && same->height == height && same->referenceVis == ch.refVis &&
      sameScoredClasses(same->pixels->scoredClass, cls.classes)) {
    // The same reference vis plane (of the same light, then) and this frame scores the same
    // pixels: the same decisions and boundary distances (they depend on nothing else).
    d->pixels = same->pixels;
  } else {
    const size_t n = reference.pixelCount();
    auto px = std::make_shared<Data::Pixels>();
    px->decision.resize(n);
    px->referenceVisClamped.assign(n, 0.0f);
    px->scoredClass.resize(n);
    px->referenceLit = std::move(cls.referenceLit);
    for (size_t i = 0; i < n; ++i) {
      const PixelClass c = cls.classes[i];
      px->scoredClass[i] = scoredOf(c);
      if (!isCompared(c)) {
        ++px->scoredCounts[classIndex(c)];
        px->decision[i] = kDecisionNone;
        continue;
      }
      ++px->compared;
      px->decision[i] = px->referenceLit[i] ? kDecisionLit : kDecisionShadowed;
      px->referenceShadow += !px->referenceLit[i];
      px->referenceVisClamped[i] = clamp01(ch.refVis[i]);
    }
    boundaryDistances(px->decision.data(), width, height, px->boundaryDist2, &px->anyBoundary);
    for (size_t i = 0; i < n; ++i) {
      const float rv = px->referenceVisClamped[i];
      if (px->decision[i] != kDecisionNone && rv != (px->decision[i] == kDecisionLit ? 1.0f : 0.0f))
        px->decision[i] |= Data::kFractional;
    }
    d->pixels = std::move(px);
  }
  if (d->pixels->compared != full.pixelsCompared)
    throw DriverError("compare: context counts differ from compareFrames");
  d->regionPixels = full.regionPixels;
  d->mMedian = full.mMedian;
  d->mP95 = full.mP95;
  d->mMax = full.mMax;
  d->mCapped = full.mCapped;
  d->cascades = full.cascades;
  for (CascadeMetrics& c : d->cascades) c.errors = 0, c.errorRate = 0;
  data_ = std::move(d);
}

bool CompareContext::sharesPixelsWith(const CompareContext& other) const {
  return data_ && other.data_ && data_->pixels == other.data_->pixels;
}

bool CompareContext::appliesTo(const Frame& reference, const Frame& raster) const {
  Channels ch;
  return contextChannels(data_.get(), reference, raster, &ch);
}

const std::string& CompareContext::group() const {
  static const std::string kNone;
  return data_ ? data_->group : kNone;
}

const CompareOptions& CompareContext::options() const { return options_; }

Metrics compareFrames(const CompareContext& context, const Frame& reference, const Frame& raster,
                      Classification* classification) {
  const CompareContext::Data* data = context.data_.get();
  Channels channels;
  if (!contextChannels(data, reference, raster, &channels))
    return compareFrames(reference, raster, context.options(), classification);
  const CompareContext::Data& d = *data;
  const CompareContext::Data::Pixels& px = *d.pixels;
  const int width = d.width, height = d.height;
  const size_t n = size_t(width) * size_t(height);
  if (classification) {
    classification->width = width;
    classification->height = height;
    classification->classes.resize(n);
    classification->referenceLit = px.referenceLit;
  }
  uint8_t* klass = classification ? reinterpret_cast<uint8_t*>(classification->classes.data()) : nullptr;
  const float leakFactor = d.options.leakBiasFactor;
  const double diagonalPx = std::sqrt(double(width) * width + double(height) * height);
  const int blocks = (height + kBlockRows - 1) / kBlockRows;
  std::vector<ContextBlockSums> sums(size_t(std::max(blocks, 0)));
  // The same blocks and, within each, the same order of the double sums as pass 1 (mae and rmse
  // to the bit); the pixels not compared are skipped as pass 1 skips them.
  tbb::parallel_for(0, blocks, [&](int b) {
    ContextBlockSums s;
    const Channels& ch = channels;
    const float* const rasVis = ch.rasVis;
    const float* const refV = px.referenceVisClamped.data();
    const uint8_t* const decision = px.decision.data();
    const size_t begin = size_t(b) * kBlockRows * width;
    const size_t end = std::min(n, size_t(b + 1) * kBlockRows * width);
    if (klass) std::memcpy(klass + begin, px.scoredClass.data() + begin, end - begin);
    // Runs of kRun pixels: first the counts over the run, branch-free (the compiler vectorizes
    // it: 2x faster on a 1080p frame, bench/compare_frames_bench.cpp BM_CompareFramesContext),
    // with whether any pixel of it needs more; then, only in such a run, its pixels in order. A
    // pixel needs more where the clamped visibilities may differ: a fractional reference, or a
    // raster value other than the reference's 0 or 1 (fractional pixels and disagreements, rare;
    // also values outside 0..1 and NaN, which the exact path below clamps and may skip).
    // Elsewhere pass 1 adds exactly 0.0 to sums that are >= +0.0: no bit changes, so skipping
    // those pixels keeps mae and rmse to the bit.
    constexpr size_t kRun = 64;
    for (size_t r = begin; r < end; r += kRun) {
      const size_t rEnd = std::min(end, r + kRun);
      int rasShadow = 0, bothShadow = 0, more = 0;
      for (size_t i = r; i < rEnd; ++i) {
        const int code = decision[i], dec = code & 3;
        const float v = rasVis[i];
        const int sShadow = !litDecision(v);
        const int compared = dec != kDecisionNone;
        rasShadow += compared & sShadow;
        bothShadow += (dec == kDecisionShadowed) & sShadow;
        const float plain = dec == kDecisionLit ? 1.0f : 0.0f;
        more |= compared & (((code & CompareContext::Data::kFractional) != 0) | (v != plain));
      }
      s.rasShadow += uint64_t(rasShadow);
      s.bothShadow += uint64_t(bothShadow);
      if (!more) continue;
      for (size_t i = r; i < rEnd; ++i) {
        const uint8_t code = decision[i], dec = code & 3;
        const float v = rasVis[i];
        const bool sLit = litDecision(v);
        const bool rLit = dec == kDecisionLit;
        const float sv = clamp01(v);
        const float rv = code & CompareContext::Data::kFractional ? refV[i] : rLit ? 1.0f : 0.0f;
        if (dec == kDecisionNone || rv == sv) continue;  // equal clamped values: equal decisions
        const double diff = double(rv) - double(sv);
        s.sumAbs += std::fabs(diff);
        s.sumSq += diff * diff;
        s.vis.addDifference(rv, diff);
        bool disagreement = rLit != sLit;
        if (ch.refSigma) {  // a sized light: soft mode, as pass 1
          const SoftDecision sd = softDecision(rv, sv, sanitizeSigma(ch.refSigma[i]));
          s.vis.withinUncertainty += sd == SoftDecision::WithinUncertainty;
          disagreement = sd == SoftDecision::Error;
        }
        if (!disagreement) continue;
        // A disagreement: step 2 on its evidence, and pass 2's decision from the kept distances.
        ++s.disagreements;
        const DisagreementClass dc = classifyAnyDisagreement(ch.evidence(i), leakFactor);
        PixelClass c = dc.cls;
        if (dc.candidate) {
          const double texels = dc.acneEvidence ? double(kBlindAcneBandTexels) : double(d.options.boundaryTexels);
          const double limit = texels * (ch.m ? double(sanitizeM(ch.m[i])) : 1.0);
          const bool within = limit >= diagonalPx ? px.anyBoundary : double(px.boundaryDist2[i]) <= limit * limit;
          c = resolveCandidate(dc.leakEvidence, within, dc.bleedEvidence, dc.acneEvidence);
        }
        ++s.counts[classIndex(c)];
        if (klass) klass[i] = uint8_t(c);
        if (ch.cascade && isErrorClass(c)) {
          const float v = ch.cascade[i];
          const int k = v >= 0.0f ? (v < 7.0f ? int(v + 0.5f) : 7) : 0;  // as cascadeMetrics reads it
          ++s.cascadeErrors[size_t(k)];
        }
      }
    }
    sums[size_t(b)] = s;
  });
  ContextBlockSums t;
  PerPixelClass<uint64_t> counts = px.scoredCounts;
  for (const auto& s : sums) {
    for (size_t k = 0; k < kPixelClassCount; ++k) counts[k] += s.counts[k];
    t.disagreements += s.disagreements;
    t.rasShadow += s.rasShadow;
    t.bothShadow += s.bothShadow;
    t.sumAbs += s.sumAbs;
    t.sumSq += s.sumSq;
    t.vis.add(s.vis);
    for (size_t k = 0; k < t.cascadeErrors.size(); ++k) t.cascadeErrors[k] += s.cascadeErrors[k];
  }
  counts[classIndex(PixelClass::Correct)] += px.compared - t.disagreements;
  Metrics out;
  setClassMetrics(out, counts);
  if (out.pixelsCompared != px.compared) {
    throw DriverError("compare: " + std::to_string(out.pixelsCompared) + " pixels classified as compared, " +
                      std::to_string(px.compared) + " counted; expected the same");
  }
  out.cascades = d.cascades;
  for (CascadeMetrics& c : out.cascades) {
    c.errors = t.cascadeErrors[size_t(c.index)];
    c.errorRate = c.pixels ? double(c.errors) / double(c.pixels) : 0.0;
  }
  const double denom = double(px.compared);
  const uint64_t shadowUnion = px.referenceShadow + t.rasShadow - t.bothShadow;
  out.shadowIou = shadowUnion ? double(t.bothShadow) / double(shadowUnion) : 1.0;
  out.mae = px.compared ? t.sumAbs / denom : 0.0;
  out.rmse = px.compared ? std::sqrt(t.sumSq / denom) : 0.0;
  t.vis.setMetrics(out, d.regionPixels, px.compared);
  out.mMedian = d.mMedian;
  out.mP95 = d.mP95;
  out.mMax = d.mMax;
  out.mCapped = d.mCapped;
  return out;
}

}  // namespace shadowlab
