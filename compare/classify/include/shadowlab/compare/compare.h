#pragma once
// Per-pixel classification of shadow errors and the metrics built on it. Documented in
// compare/METRICS.md (numerator, denominator, exclusions, sources). compare reads only Frames.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/classes.h"
#include "shadowlab/scenes/frame.h"

namespace shadowlab {

const char* toString(PixelClass c);  // the class's key (classes.h)

// The texel footprint the rasterizer writes where the visible plane is edge-on to the light (its
// Jacobian is singular: a point light lying in the plane, a directional light along it):
// raster/shaders/resolve.frag caps `light.L.m` at this value. Such pixels are counted in
// `m_capped` and left out of the m statistics (compare/METRICS.md). Singular: sMin / sMax of the
// Jacobian below kFootprintSingularRatio (float rounding leaves an edge-on plane's at 1e-7 .. 1e-6),
// or m past the cap. raster/include/shadowlab/raster/resolve_abi.h holds the same two values.
constexpr float kFootprintCapPx = 1e6f;
constexpr float kFootprintSingularRatio = 1e-5f;

struct CompareOptions {
  std::string light;            // empty: the light the raster frame rendered (meta "light")
  float boundaryTexels = 2.0f;  // aliasing: within this many map texels of a reference boundary
  // leak: the reference occluder counts as "within the bias" when its distance along the shadow
  // ray is at most leakBiasFactor * bias_world (the slack covers the map's half-texel sampling
  // offset; METRICS.md explains the value).
  float leakBiasFactor = 1.5f;
  // How the two inputs are named in error messages (the CLI passes the file paths).
  std::string referenceName = "reference frame";
  std::string rasterName = "raster frame";
  // A frame from another renderer: classified by the blind rule (classify.h
  // classifyBlindDisagreement, compare/METRICS.md "Frames from other renderers"), also implied by
  // the compared frame's meta "kind": "outside". prepareOutsideComparison (outside_frame.h) sets it.
  bool blind = false;
  bool declaredFilterable = false;  // blind: the renderer declared a filterable map (bleed evidence)
};

// Metrics of the compared pixels whose raster lookup used one cascade (raster `light.L.cascade`).
struct CascadeMetrics {
  int index = 0;         // cascade, 0-based
  uint64_t pixels = 0;   // compared pixels of this cascade (the denominator)
  uint64_t errors = 0;   // of them, pixels of an error class
  double errorRate = 0;  // errors / pixels, 0 when pixels = 0
  double mP95 = 0;       // nearest-rank 95th percentile of m over these pixels, 0 when none
};

struct Metrics {
  uint64_t pixelsCompared = 0;
  // Per class (classes.h), indexed by the class code: pixels of the class over the whole frame, and
  // their share of pixelsCompared (0 when none are compared). Metrics::toJson writes the classes'
  // count and rate metrics from these; the classes without a metric (correct, not compared) are
  // filled all the same.
  PerPixelClass<uint64_t> classCounts{};
  PerPixelClass<double> classRates{};
  static_assert(std::tuple_size<decltype(classCounts)>::value == kPixelClassCount &&
                    std::tuple_size<decltype(classRates)>::value == kPixelClassCount,
                "one count and one rate per row of the class table");
  uint64_t errors = 0;  // the sum over the error classes
  double errorRate = 0;
  uint64_t count(PixelClass c) const { return classCounts[classIndex(c)]; }
  double rate(PixelClass c) const { return classRates[classIndex(c)]; }
  double shadowIou = 1;
  double mae = 0, rmse = 0;
  // Visibility error per region of the truth (classes.h kVisRegions, visRegion in classify.h),
  // every light: compared pixels of the region, mean |R - S| and sqrt(mean (R - S)^2) over them
  // (0 in memory, null in JSON, when the region is empty).
  std::array<uint64_t, kVisRegionCount> regionPixels{};
  std::array<double, kVisRegionCount> regionMae{}, regionRmse{};
  // Signed visibility error over the compared pixels: mean max(R - S, 0) (the raster darker than
  // the truth) and mean max(S - R, 0) (lighter); they sum to mae up to rounding.
  double overShadowing = 0, underShadowing = 0;
  // Sized lights only (the reference has `vis_sigma`; 0 otherwise): compared pixels whose
  // difference exceeds kSoftTolerance but lies within kSoftTolerance + k sigma (classify.h), so
  // correct only because of the truth's own uncertainty.
  uint64_t withinUncertainty = 0;
  // Over the compared pixels whose m is below kFootprintCapPx; 0 without an m channel.
  double mMedian = 0, mP95 = 0, mMax = 0;
  // Compared pixels whose m reached kFootprintCapPx (or is +inf): not in mMedian, mP95, mMax.
  uint64_t mCapped = 0;
  // No compared pixel (the camera sees no surface, or the two frames see different surfaces at
  // every pixel): the rates, IoUs, mae, rmse and m statistics are 0 / 0, written as null
  // (compare/METRICS.md "Nothing compared"); in memory they keep the values of an empty tally.
  bool nothingCompared() const { return pixelsCompared == 0; }
  // Every compared pixel's m hit the cap: the m statistics have no value to describe (null in JSON).
  bool footprintUndefined() const { return nothingCompared() || mCapped == pixelsCompared; }
  // projectors (first projector, when the scene has one; otherwise 0 / absent in JSON)
  bool hasProjector = false;
  // false for frames of a scene with projectors and no light (projective texturing studies): no
  // shadow decision to score, every compared pixel counts as correct for the light's classes and
  // the projector metrics carry the comparison. In JSON as "light_compared": false, absent otherwise.
  bool lightCompared = true;
  double projectorCoverageIou = 1;
  uint64_t reverseProjectionPixels = 0;
  double projectorColorMae = 0;
  // Per cascade (index 0..): present when the raster frame has `light.L.cascade` and was not
  // rendered with a non-cascaded fit (meta method "fit"); empty otherwise (absent in JSON).
  std::vector<CascadeMetrics> cascades;

  nlohmann::json toJson() const;  // stable keys: pixels_compared, geometry_mismatch, error_rate, ...
};

// One line for stderr when `m` has nothing compared ("nothing to compare: ..." with the reason read
// from the counts), "" otherwise.
std::string nothingComparedMessage(const Metrics& m);
// One line for stdout when some compared pixels hit the footprint cap, "" otherwise.
std::string footprintCapNote(const Metrics& m);

struct Classification {
  int width = 0, height = 0;
  std::vector<PixelClass> classes;  // width*height
  // 1 where the reference decides "lit" (visibility >= 0.5), 0 elsewhere; width*height. Lets the
  // pictures shade correct pixels as lit or shadowed.
  std::vector<uint8_t> referenceLit;
};

// The light compareFrames would use for these frames and options (see CompareOptions::light).
std::string resolveCompareLight(const Frame& reference, const Frame& raster, const CompareOptions& options);

// RGB color of each class in errors.png (and the legend): the table's colour (classes.h).
void classColor(PixelClass c, bool referenceLit, uint8_t rgb[3]);

// The error classes for a one-line summary, in table order: "acne 37, leak 11, ..." (counts) or
// "acne 0.0123, leak 0.0004, ..." (rates, 4 decimals).
std::string errorClassSummary(const Metrics& m, bool rates);
// The projector's line of a summary ("" without one): "projector: coverage_iou 0.9859,
// reverse_projection_pixels 0, color_mae 0.0014", prefixed "no light (projector-only scene); "
// when the frames had no light to compare.
std::string projectorSummary(const Metrics& m);

// The class table as JSON, for the chart script and `shadowlab classes --json`: a list, in legend
// order, of {code, key, label, error, count_metric, rate_metric, color ("#rrggbb"), help}, the
// metric names null where the class has none.
nlohmann::json pixelClassesJson();

// Throws InputError on mismatched sizes, scene hashes or missing channels.
Metrics compareFrames(const Frame& reference, const Frame& raster, const CompareOptions& options = {},
                      Classification* classification = nullptr);

// What compareFrames computes from the planes that do not change between the configurations of
// one evidence-on-demand group (raster.h: frames rendered with a selector carry meta
// "evidence_group", the same for every configuration sharing the light's layers: map size, fit,
// light; only biases and filters differ): per pixel the scored class (not compared, geometry
// mismatch), the reference decision and clamped visibility, the exact squared distance to the
// nearest reference shadow boundary (pass 2's distance transform); per frame the compared count,
// the reference's shadow count, the m statistics and each cascade's pixels and m_p95.
// compareFrames(context, reference, raster) then reads the raster `vis` of every pixel and the
// evidence only where the decisions disagree (compare/METRICS.md "Comparing a group": ~4x less
// memory traffic at 1080p) and returns the same Metrics bit for bit.
//
// The guard: the context applies only to the reference it was built from (same frame object and
// plane) and to a raster frame of the same size, light, options and non-empty evidence_group, with
// the same optional planes (m, cascade); anything else (a frame without the key, projectors, a
// projector-only scene, another group) goes through the full compareFrames. The group key is the
// rasterizer's promise that hit, object_id, m and cascade are the same planes: a frame whose key
// was copied onto other planes is the caller's fault and is not detected.
class CompareContext;
// The same Metrics (and classification) as compareFrames(reference, raster, context.options()),
// from the context's planes where it applies to these frames, by the full path otherwise.
Metrics compareFrames(const CompareContext& context, const Frame& reference, const Frame& raster,
                      Classification* classification = nullptr);

class CompareContext {
 public:
  CompareContext() = default;  // applies to nothing
  // Throws what compareFrames(reference, raster, options) throws. Costs about two full
  // compareFrames (the classification and the distance transform). `metrics` (optional) receives
  // compareFrames(reference, raster, options), which the constructor computes anyway.
  // `sameGeometry` (optional): a context of another group, for example another map size, of the
  // same camera. Where it was made from the same reference plane and light and `raster` scores
  // the same pixels (the same hit and object planes, checked), the new context shares its
  // per-pixel decisions and boundary distances and costs about one compareFrames.
  CompareContext(const Frame& reference, const Frame& raster, const CompareOptions& options = {},
                 const CompareContext* sameGeometry = nullptr, Metrics* metrics = nullptr);
  // Whether compareFrames(*this, reference, raster) takes the fast path for these frames.
  bool appliesTo(const Frame& reference, const Frame& raster) const;
  const std::string& group() const;  // "" when the context applies to nothing
  // Whether the two contexts share their per-pixel decisions (`sameGeometry` above).
  bool sharesPixelsWith(const CompareContext& other) const;
  const CompareOptions& options() const;

  struct Data;

 private:
  CompareOptions options_;  // also where the context applies to nothing: the full path's
  std::shared_ptr<const Data> data_;
  friend Metrics compareFrames(const CompareContext&, const Frame&, const Frame&, Classification*);
};

// Pictures (8-bit RGB, width*height*3): each class in its own color with a legend drawn in;
// the triptych is reference | raster | errors side by side.
// `outlines` (optional, e.g. the reference frame): object silhouettes (where `hit` or `object_id`
// changes between neighbours) are drawn darker over correct pixels so the geometry is readable.
std::vector<uint8_t> errorsPicture(const Classification& c, int* outWidth, int* outHeight,
                                   const Frame* outlines = nullptr);
void writeErrorsPng(const std::string& path, const Classification& c, const Frame* outlines = nullptr);
void writeTriptychPng(const std::string& path, const Frame& reference, const Frame& raster, const Classification& c);

}  // namespace shadowlab
