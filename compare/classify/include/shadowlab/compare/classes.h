#pragma once
// The pixel classes of compare, each defined once, as one X-macro row:
//   X(Enumerator, code, "key", "label", error, "count metric", "rate metric", better, lit RGB, shadowed RGB, "help")
// - code: the value written to files (a classification's bytes); stable, dense from 0.
// - key: the class's name in text (toString, `shadowlab classes`, classes.json).
// - label: the legend's and the charts' words for it.
// - error: an error class: its pixels are compared pixels the renderers disagree on; they make up
//   `errors`, `error_rate` and a cascade's `error_rate`, and each gets a report column and a chart
//   panel.
// - count / rate metric: its names in Metrics::toJson, results.csv, the report, the gate; nullptr
//   where the class has none (the rate's denominator is pixels_compared, compare/METRICS.md).
// - better: which way the gate (compare/gate) reads a move of those metrics; Lower for every class
//   (they count wrong or unscored pixels).
// - colours (0xRRGGBB) in errors.png and its legend; the shadowed one differs only where the
//   picture shows the reference's decision (correct lit / correct shadowed), and the legend then
//   shows both swatches.
// Rows are in legend order (also the order of report columns, charts and CLI summaries).
// The decision between classes (which evidence wins) is code, not data: classifyPixel in
// classify.h, its precedence documented there and in compare/METRICS.md.
//
// Header-only on purpose: the gate (compare/gate) reads the metric names without linking the
// classification library.
#include <array>
#include <cstddef>
#include <cstdint>

#define SHADOWLAB_PIXEL_CLASSES(X)                                                                              \
  X(Correct, 2, "correct", "correct", false, nullptr, nullptr, Lower, 0xBEBEBE, 0x555555,                       \
    "both renderers decide the same (lit or shadowed)")                                                         \
  X(Acne, 3, "acne", "acne", true, "acne", "acne_rate", Lower, 0xEB2323, 0xEB2323,                              \
    "lit in truth, shadowed by the receiver's own texel in the map (bias too small)")                           \
  X(Leak, 4, "leak", "leak", true, "leak", "leak_rate", Lower, 0x1E78FF, 0x1E78FF,                              \
    "shadowed in truth, lit because the bias let the occluder through (peter panning)")                         \
  X(Bleed, 8, "bleed", "bleed", true, "bleed", "bleed_rate", Lower, 0x00C8C8, 0x00C8C8,                         \
    "shadowed in truth, lit by a filterable map's bound: a second occluder depth in the footprint (VSM/MSM)")   \
  X(Aliasing, 5, "aliasing", "aliasing", true, "aliasing", "aliasing_rate", Lower, 0xFFD700, 0xFFD700,          \
    "a disagreement within boundaryTexels map texels of a true shadow boundary (map too coarse)")               \
  X(Coverage, 6, "coverage", "coverage", true, "coverage", "coverage_rate", Lower, 0x28C846, 0x28C846,          \
    "the point lies outside the light's map: the renderer's policy decided, not a depth test")                  \
  X(PenumbraWide, 9, "penumbra_wide", "penumbra too wide", true, "penumbra_wide", "penumbra_wide_rate", Lower,  \
    0xA05AFF, 0xA05AFF, "sized light: the raster is partial where the truth is fully lit or in umbra")          \
  X(PenumbraHard, 10, "penumbra_hard", "penumbra too hard", true, "penumbra_hard", "penumbra_hard_rate", Lower, \
    0xFF8C1E, 0xFF8C1E, "sized light: the truth is partial (penumbra), the raster 0 or 1")                      \
  X(Other, 7, "other", "other", true, "other", "other_rate", Lower, 0xFF00FF, 0xFF00FF,                         \
    "any other disagreement: rare; a large value is a finding to look at in errors.png")                        \
  X(GeometryMismatch, 1, "geometry_mismatch", "geometry mismatch", false, "geometry_mismatch", nullptr, Lower,  \
    0x965F2D, 0x965F2D, "the renderers see different surfaces (or one sees none): counted, not scored")         \
  X(NotCompared, 0, "not_compared", "", false, nullptr, nullptr, Lower, 0x121428, 0x121428, "background in both frames")

namespace shadowlab {

#define SHADOWLAB_PIXEL_CLASS_ENUMERATOR(name, code, ...) name = code,
// Per-pixel class codes (stable: they are written to files).
enum class PixelClass : uint8_t { SHADOWLAB_PIXEL_CLASSES(SHADOWLAB_PIXEL_CLASS_ENUMERATOR) };
#undef SHADOWLAB_PIXEL_CLASS_ENUMERATOR

// Which way a class metric improves.
enum class MetricBetter : uint8_t { Lower, Higher };

// One row, as C++ iterates it.
struct PixelClassInfo {
  PixelClass cls;
  const char* key;
  const char* label;  // "" for a class the legend does not show
  bool error;
  const char* countMetric;  // nullptr: no count metric
  const char* rateMetric;   // nullptr: no rate metric
  MetricBetter better;
  uint32_t rgbLit, rgbShadowed;
  const char* help;
};

#define SHADOWLAB_PIXEL_CLASS_ROW(name, code, key, label, error, count, rate, better, lit, shadowed, help) \
  PixelClassInfo{PixelClass::name, key, label, error, count, rate, MetricBetter::better, lit, shadowed, help},
inline constexpr PixelClassInfo kPixelClasses[] = {SHADOWLAB_PIXEL_CLASSES(SHADOWLAB_PIXEL_CLASS_ROW)};
#undef SHADOWLAB_PIXEL_CLASS_ROW

inline constexpr size_t kPixelClassCount = sizeof(kPixelClasses) / sizeof(kPixelClasses[0]);

// The regions of the truth that the visibility metrics are split by (compare/METRICS.md "Soft
// shadows"): X(Enumerator, "key"), the key giving the metrics `<key>_pixels`, `<key>_mae`,
// `<key>_rmse`. Which region a pixel is in: visRegion (classify.h), from the reference visibility.
#define SHADOWLAB_VIS_REGIONS(X) X(Lit, "lit") X(Penumbra, "penumbra") X(Umbra, "umbra")
#define SHADOWLAB_VIS_REGION_ENUMERATOR(name, key) name,
enum class VisRegion : uint8_t { SHADOWLAB_VIS_REGIONS(SHADOWLAB_VIS_REGION_ENUMERATOR) };
#undef SHADOWLAB_VIS_REGION_ENUMERATOR
struct VisRegionInfo {
  VisRegion region;
  const char* pixelsMetric;  // compared pixels of the region (a count)
  const char* maeMetric;     // mean |R - S| over them; null in JSON when the region is empty
  const char* rmseMetric;    // sqrt(mean (R - S)^2) over them; null when empty
};
#define SHADOWLAB_VIS_REGION_ROW(name, key) VisRegionInfo{VisRegion::name, key "_pixels", key "_mae", key "_rmse"},
inline constexpr VisRegionInfo kVisRegions[] = {SHADOWLAB_VIS_REGIONS(SHADOWLAB_VIS_REGION_ROW)};
#undef SHADOWLAB_VIS_REGION_ROW
inline constexpr size_t kVisRegionCount = sizeof(kVisRegions) / sizeof(kVisRegions[0]);

namespace detail {
// Arrays indexed by a class code (counts, colours) have kPixelClassCount entries: that is safe only
// while the codes are exactly 0 .. kPixelClassCount - 1, each once.
constexpr bool pixelClassCodesAreDense() {
  bool seen[kPixelClassCount] = {};
  for (const PixelClassInfo& c : kPixelClasses) {
    const size_t code = size_t(c.cls);
    if (code >= kPixelClassCount || seen[code]) return false;
    seen[code] = true;
  }
  return true;
}
constexpr std::array<uint8_t, kPixelClassCount> pixelClassRows() {
  std::array<uint8_t, kPixelClassCount> row{};
  for (size_t r = 0; r < kPixelClassCount; ++r) row[size_t(kPixelClasses[r].cls)] = uint8_t(r);
  return row;
}
inline constexpr std::array<uint8_t, kPixelClassCount> kPixelClassRow = pixelClassRows();
}  // namespace detail
static_assert(detail::pixelClassCodesAreDense(), "pixel class codes must be 0 .. kPixelClassCount - 1, each once");
static_assert(kPixelClassCount <= 255, "a class code is one byte");

// A value indexed by the class code: std::array sized by the table, so adding a row resizes every
// tally, and the static_assert above guarantees every code has its slot.
template <class T>
using PerPixelClass = std::array<T, kPixelClassCount>;

constexpr size_t classIndex(PixelClass c) { return size_t(c); }
// The row of a class; `c` must be a code of the table (every PixelClass value is).
constexpr const PixelClassInfo& classInfo(PixelClass c) { return kPixelClasses[detail::kPixelClassRow[size_t(c)]]; }
constexpr bool isErrorClass(PixelClass c) { return classInfo(c).error; }

}  // namespace shadowlab
