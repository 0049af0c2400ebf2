#pragma once
// The steps of compareFrames (compare.h), public so that each can be tested on its own:
//   evidence  PixelEvidence: what the channels of both frames say at one pixel
//   class     classifyPixel: a pure function from evidence to a PixelClass (precedence below)
//   tallies   countClasses, setClassMetrics: per-class counts and rates of a set of classes
// compareFrames runs the same functions pixel by pixel, reading the evidence channels only where
// the decisions disagree (the frames' evidence planes are most of the memory traffic). The class
// functions are inline: the pass-1 loop calls them for every pixel.
// compare/METRICS.md defines each class and why the precedence is what it is.
#include <cmath>
#include <vector>

#include "shadowlab/compare/compare.h"

namespace shadowlab {

// One pixel's channels. The first group decides whether the pixel is scored and how each renderer
// decides; compareFrames reads the evidence after it only where the two decisions disagree. A
// missing evidence channel proves nothing (its `has` flag false).
struct PixelEvidence {
  bool referenceHit = false, rasterHit = false;  // `hit` >= 0.5
  float referenceObject = 0, rasterObject = 0;   // `object_id`
  float referenceVis = 0, rasterVis = 0;         // `light.L.vis`, raw (clamped to [0, 1] when decided, NaN as 0)

  bool hasInMap = false;
  float inMap = 1;  // raster `light.L.in_map`; < 0.5: outside the map
  bool hasOccluderId = false;
  float occluderId = 0;                                  // raster `light.L.occluder_id`: who wrote the map texel
  bool hasDepths = false;                                // all three below (map depth units)
  float receiverDepth = 0, mapDepth = 0, biasDepth = 0;  // raster `receiver_depth`, `map_depth`, `bias_depth`
  bool hasOccluderDistance = false;                      // both below (world units)
  float referenceOccluderDist = 0, biasWorld = 0;        // reference `occluder_dist`, raster `bias_world`
  // Filterable maps (filter=vsm, evsm2, evsm4, msm): the moments at the lookup.
  bool hasMoments = false;                // both below, and the depths above
  float momentMean = 0, momentBound = 0;  // raster `moment_mean` (map depth units), `moment_bound` (0..1)
  // The disagreement lies within boundaryTexels * m pixels of a reference shadow boundary. Known
  // only after the boundary distance transform (compareFrames' second pass).
  bool withinBoundaryBand = false;
  // A sized light: the reference frame has `light.L.vis_sigma`, the standard error of its `vis` (the
  // visible fraction of the light, estimated by stratified rays). Switches the pixel to soft mode
  // (softError below); without it every test here is the hard light's.
  bool softTruth = false;
  float referenceSigma = 0;  // reference `vis_sigma`; NaN or negative read as 0
  // A frame from another renderer (compare/METRICS.md "Frames from other renderers"): none of the
  // raster's own evidence, so classifyBlindDisagreement decides from the truth's evidence and the
  // planes prepareOutsideComparison (outside_frame.h) made from what the renderer declared.
  bool blind = false;
  bool hasTruthOccluderDistance = false;  // reference `occluder_dist` (-1: nothing occludes)
  float truthOccluderDist = -1;
  bool hasContact = false;  // `contact_world` of the declared map
  float contactWorld = 0;   // a true occluder this close (world units, along the shadow ray) is contact
  bool declaredFilterable = false;  // the renderer declared a filterable map (VSM, EVSM, MSM)
};

// ---- soft truth (sized lights; compare/METRICS.md "Soft shadows") ----------------------------
// k: a difference within k standard errors of the truth's estimate is the truth's own noise.
// Three (a normal variable lies within 3 sigma 99.7 % of the time) keeps the noise of a 64-ray
// reference out of the errors without hiding a penumbra that is wrong by a fifth of the light.
constexpr float kSoftSigmaK = 3.0f;
// Tolerance of a soft-mode pixel against an exact truth: |R - S| <= kSoftTolerance is correct
// (a tenth of the light: about what 8-bit shading makes visible in a grey penumbra).
constexpr float kSoftTolerance = 0.1f;
// "Fully": a visibility within kSoftEpsilon of 1 is fully lit, within it of 0 umbra; between the
// two, partial. Used for the regions of the truth (visRegion, point estimate), for the truth's
// side of the penumbra classes (widened by k sigma) and for the raster's side.
constexpr float kSoftEpsilon = 0.05f;

// clamp to [0, 1], NaN read as 0 (the visibilities every metric reads).
inline float clampVisibility(float v) { return v >= 0.0f ? (v <= 1.0f ? v : 1.0f) : 0.0f; }
inline float sanitizeSigma(float s) { return s >= 0.0f ? s : 0.0f; }  // NaN, negative -> 0

// The region of the truth a compared pixel belongs to, from the clamped reference visibility R:
// lit when R >= 1 - epsilon, umbra when R <= epsilon, penumbra between (every light: a hard light's
// binary truth has no penumbra unless --spp makes its edges fractional).
inline VisRegion visRegion(float referenceVisClamped) {
  if (referenceVisClamped >= 1.0f - kSoftEpsilon) return VisRegion::Lit;
  if (referenceVisClamped <= kSoftEpsilon) return VisRegion::Umbra;
  return VisRegion::Penumbra;
}

// The soft-mode decision of one compared pixel, from R, S (clamped) and sigma (NaN, negative: 0):
// an error when |R - S| > kSoftTolerance + k sigma, whatever the binary decisions say; within the
// uncertainty (correct, counted in `within_uncertainty`) when kSoftTolerance < |R - S| <= that.
enum class SoftDecision : uint8_t { Correct, WithinUncertainty, Error };
inline SoftDecision softDecision(float referenceVisClamped, float rasterVisClamped, float sigma) {
  const float diff = std::fabs(referenceVisClamped - rasterVisClamped);
  if (!(diff > kSoftTolerance)) return SoftDecision::Correct;
  return diff > kSoftTolerance + kSoftSigmaK * sanitizeSigma(sigma) ? SoftDecision::Error
                                                                    : SoftDecision::WithinUncertainty;
}
// The truth's side of the penumbra classes, confident by k sigma: fully lit when R - k sigma >=
// 1 - epsilon, umbra when R + k sigma <= epsilon, partial when epsilon < R - k sigma and
// R + k sigma < 1 - epsilon; a pixel near a threshold (within k sigma of it) is none of the three.
inline bool truthFully(float r, float sigma) {
  return r - kSoftSigmaK * sigma >= 1.0f - kSoftEpsilon || r + kSoftSigmaK * sigma <= kSoftEpsilon;
}
inline bool truthPartial(float r, float sigma) {
  return r - kSoftSigmaK * sigma > kSoftEpsilon && r + kSoftSigmaK * sigma < 1.0f - kSoftEpsilon;
}
// The raster's side (no uncertainty): hard when S <= epsilon or S >= 1 - epsilon, else partial.
inline bool rasterPartial(float s) { return s > kSoftEpsilon && s < 1.0f - kSoftEpsilon; }

// The binary decision: lit when visibility >= 0.5 (NaN read as 0).
inline bool litDecision(float visibility) { return visibility >= 0.5f; }  // the same as clamping first

// Which pixels are scored: NotCompared (neither frame hits), GeometryMismatch (one hits, or the
// objects differ), else Correct, standing for "compared" until the decisions are looked at.
inline PixelClass scoredClass(bool referenceHit, bool rasterHit, float referenceObject, float rasterObject) {
  if (!referenceHit && !rasterHit) return PixelClass::NotCompared;
  if (!(referenceHit && rasterHit) || referenceObject != rasterObject) return PixelClass::GeometryMismatch;
  return PixelClass::Correct;
}

// A compared pixel whose decisions disagree, before the boundary distance is known: coverage or
// acne are final; anything else is an aliasing candidate, carrying whether the leak evidence holds.
struct DisagreementClass {
  PixelClass cls = PixelClass::Other;  // Coverage or Acne when !candidate
  bool candidate = false;
  bool leakEvidence = false;
  bool bleedEvidence = false;
  bool acneEvidence = false;  // blind only: acne is final with the raster's occluder evidence
};
// Light bleeding of a filterable map: the truth is shadowed, and the lookup's moments say the
// footprint's mean depth lies in front of the receiver by more than the bias (a real occluder on
// average, not one the bias let through) while their bound still lights it (>= 0.5): the
// variance that lit it comes from a second occluder depth inside the footprint (compare/METRICS.md).
inline bool bleedEvidence(const PixelEvidence& e) {
  return e.hasMoments && e.hasDepths && e.momentBound >= 0.5f && e.receiverDepth - e.momentMean > e.biasDepth;
}
// Called for a disagreement (hard: the decisions differ; soft: softDecision is Error, the decisions
// may agree). The evidence reads the direction of the error: acne needs the truth lit and the
// raster shadowed (decisions), leak and bleed the raster too lit (hard: the truth shadowed, which in
// a disagreement is the same; soft: S > R).
inline DisagreementClass classifyDisagreement(const PixelEvidence& e, float leakBiasFactor) {
  const bool referenceLit = litDecision(e.referenceVis);
  // Outside the map no other evidence (occluder, depth) is meaningful.
  if (e.hasInMap && !(e.inMap >= 0.5f)) return {PixelClass::Coverage, false, false};
  if (referenceLit && !litDecision(e.rasterVis) && e.hasOccluderId && e.occluderId == e.rasterObject)
    return {PixelClass::Acne, false, false};
  const float r = clampVisibility(e.referenceVis), s = clampVisibility(e.rasterVis);
  if (e.softTruth) {
    const float sigma = sanitizeSigma(e.referenceSigma);
    if (truthPartial(r, sigma) && !rasterPartial(s)) return {PixelClass::PenumbraHard, false, false};
    if (truthFully(r, sigma) && rasterPartial(s)) return {PixelClass::PenumbraWide, false, false};
  }
  const bool rasterTooLit = e.softTruth ? s > r : !referenceLit;
  // (a) another object in the map, let through by the bias; a texel the receiver wrote itself
  // proves no occluder.
  const bool throughMap = e.hasDepths && e.hasOccluderId && e.occluderId != 0.0f && e.occluderId != e.rasterObject &&
                          e.receiverDepth > e.mapDepth && e.receiverDepth <= e.mapDepth + e.biasDepth;
  // (b) the true occluder within the bias distance (with the sampling slack).
  const bool withinBias = e.hasOccluderDistance && e.referenceOccluderDist >= 0.0f &&
                          e.referenceOccluderDist <= leakBiasFactor * e.biasWorld;
  return {PixelClass::Other, true, rasterTooLit && (throughMap || withinBias), rasterTooLit && bleedEvidence(e)};
}

// The blind rule (compare/METRICS.md "Frames from other renderers"): a disagreement of a frame
// without the raster's internals. Coverage (outside every declared layer) and the penumbra classes
// (from the values) are final as in classifyDisagreement; everything else waits for the distance
// to the true shadow boundary. Too dark (the truth lit, the frame shadowed): a map texel holding
// the true occluder's edge reaches about half a texel past it, so within kBlindAcneBandTexels of
// the true boundary it is aliasing and beyond it acne (the truth lit means no surface lies between
// the point and the light, so a shadow away from every true edge is the receiver shadowing itself).
// Too lit, beyond the aliasing band (CompareOptions::boundaryTexels): leak when the true occluder
// is in contact (within contactWorld of the receiver: a bias of the declared map's few texels lets
// it through), else bleed when the renderer declared a filterable map (an occluder lit through by
// the moments' bound), else other. The constants are those that measure best against the full
// rule (bench/blind_agreement_bench.cpp; the matrix is in compare/METRICS.md).
constexpr float kBlindAcneBandTexels = 0.5f;
inline DisagreementClass classifyBlindDisagreement(const PixelEvidence& e) {
  if (e.hasInMap && !(e.inMap >= 0.5f)) return {PixelClass::Coverage, false, false};
  const float r = clampVisibility(e.referenceVis), s = clampVisibility(e.rasterVis);
  if (e.softTruth) {
    const float sigma = sanitizeSigma(e.referenceSigma);
    if (truthPartial(r, sigma) && !rasterPartial(s)) return {PixelClass::PenumbraHard, false, false};
    if (truthFully(r, sigma) && rasterPartial(s)) return {PixelClass::PenumbraWide, false, false};
  }
  const bool referenceLit = litDecision(e.referenceVis);
  DisagreementClass d{PixelClass::Other, true, false, false, false};
  const bool tooLit = e.softTruth ? s > r : !referenceLit;
  if (!tooLit) {
    // Only with a declared map (its in_map plane): without one the band is in pixels, and a texel
    // may span many. Under a sized light only a fully lit truth point shadowed outright: a penumbra
    // drawn too dark is not the receiver shadowing itself.
    d.acneEvidence = e.hasInMap && referenceLit && !litDecision(e.rasterVis) &&
                     (!e.softTruth || (truthFully(r, sanitizeSigma(e.referenceSigma)) && !rasterPartial(s)));
    return d;
  }
  const bool contact = e.hasContact && e.hasTruthOccluderDistance && e.truthOccluderDist >= 0.0f &&
                       e.truthOccluderDist <= e.contactWorld;
  d.leakEvidence = contact;
  d.bleedEvidence = !contact && e.declaredFilterable;
  return d;
}

// A candidate's class once its boundary distance is known: aliasing within the band, beyond it
// bleed (with the bleed evidence), leak (with the leak evidence), acne (blind: with its evidence)
// or other.
inline PixelClass resolveCandidate(bool leakEvidence, bool withinBoundaryBand, bool bleedEvidence = false,
                                   bool acneEvidence = false) {
  // Aliasing before leak: within the band the map's resolution alone explains the error (METRICS.md).
  if (withinBoundaryBand) return PixelClass::Aliasing;
  // Bleed before leak: the moments prove an occluder in front by more than the bias, so the bias
  // did not let it through (a bleeding pixel's true occluder may well lie within the bias's slack).
  if (bleedEvidence) return PixelClass::Bleed;
  if (leakEvidence) return PixelClass::Leak;
  return acneEvidence ? PixelClass::Acne : PixelClass::Other;
}

// The rule a pixel's evidence calls for: the blind one for a frame from another renderer.
inline DisagreementClass classifyAnyDisagreement(const PixelEvidence& e, float leakBiasFactor) {
  return e.blind ? classifyBlindDisagreement(e) : classifyDisagreement(e, leakBiasFactor);
}

// Whether a compared pixel is a disagreement that needs a class: hard, the decisions differ; soft,
// softDecision says Error (which may hold where the decisions agree, and not where they differ).
inline bool isDisagreement(const PixelEvidence& e) {
  if (!e.softTruth) return litDecision(e.referenceVis) != litDecision(e.rasterVis);
  return softDecision(clampVisibility(e.referenceVis), clampVisibility(e.rasterVis), sanitizeSigma(e.referenceSigma)) ==
         SoftDecision::Error;
}

// The class of one pixel; the first that holds, in this order (the precedence):
//   not compared, geometry mismatch, correct (hard: the decisions agree; soft: |R - S| within
//   kSoftTolerance + k sigma), then for a disagreement coverage (outside the map), acne (lit in
//   truth, shadowed, the receiver's own texel in the map), for a sized light penumbra_hard (the
//   truth partial, the raster 0 or 1) and penumbra_wide (the raster partial, the truth fully lit
//   or umbra), then aliasing (within the boundary band), bleed (a filterable map's bound lit a
//   pixel its moments put behind an occluder), leak (the bias let a real occluder through), other.
//   Under a sized light the last four take what is left: a hard raster against a hard truth of
//   the other decision, or a partial raster against a partial truth off by more than the tolerance.
inline PixelClass classifyPixel(const PixelEvidence& e, float leakBiasFactor = CompareOptions{}.leakBiasFactor) {
  const PixelClass scored = scoredClass(e.referenceHit, e.rasterHit, e.referenceObject, e.rasterObject);
  if (scored != PixelClass::Correct) return scored;
  if (!isDisagreement(e)) return PixelClass::Correct;
  const DisagreementClass d = classifyAnyDisagreement(e, leakBiasFactor);
  return d.candidate ? resolveCandidate(d.leakEvidence, e.withinBoundaryBand, d.bleedEvidence, d.acneEvidence)
                     : d.cls;
}

// Tallies: pixels per class (indexed by the class code).
PerPixelClass<uint64_t> countClasses(const std::vector<PixelClass>& classes);

// Fills m's per-class counts and rates, `errors`, `error_rate` and `pixels_compared` (correct plus
// the error classes) from per-class counts; rates are 0 when no pixel is compared.
void setClassMetrics(Metrics& m, const PerPixelClass<uint64_t>& counts);

}  // namespace shadowlab
