#pragma once
// A shadow-mapping method: every parameter a sweep can vary, as runtime data.
// Method files are flat JSON objects whose keys are the same dotted keys that --set and
// --grid take (documented with defaults in raster/METHODS.md), e.g.
//   { "name": "pcf5", "map.size": 2048, "bias.slope": 1.5, "filter": "pcf", "filter.size": 5 }
// Comments are allowed. Unknown keys, wrong types and out-of-range values are InputErrors.
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/scenes/kinds.h"

namespace shadowlab {

struct AdapterManifest;

enum class DepthFormat { D16, D24, D32F };
enum class CullMode { Back, Front, None };
// The codes are kinds.h's: the shader switches on the same numbers.
enum class Fit { SHADOWLAB_FITS(SHADOWLAB_ENUMERATOR) };
enum class Filter { SHADOWLAB_FILTERS(SHADOWLAB_ENUMERATOR) };

// Every fit / filter, in code order (kinds.h's rows).
const std::vector<KindInfo<Fit>>& fitKinds();
const std::vector<KindInfo<Filter>>& filterKinds();

struct Method {
  std::string name = "default";
  int mapSize = 2048;                        // map.size: texels per side, 16..16384 (and the device limit)
  DepthFormat mapFormat = DepthFormat::D24;  // map.format: d16 | d24 | d32f
  CullMode cull = CullMode::None;  // cull: back | front | none (shadow pass; none: open quads cast from both sides)
  Fit fit = Fit::Sphere;           // fit: kinds.h's SHADOWLAB_FITS
  // Cascaded shadow maps (fit=cascades, directional lights): the view depth range is split by the
  // practical scheme into cascadeCount slices, one map layer (map.size squared) each.
  int cascadeCount = 4;           // cascades.count: 1..8 slices
  float cascadeLambda = 0.75f;    // cascades.lambda: 0 uniform .. 1 logarithmic splits
  float cascadeBlend = 0.0f;      // cascades.blend: blend band, fraction of a cascade's depth range, 0..0.5
  bool cascadeStabilize = false;  // cascades.stabilize: constant-size crops snapped to whole texels
  // Sample distribution shadow maps (fit=sdsm, directional lights; raster/METHODS.md): the cascades'
  // splits over the view depth range of what the camera sees, each crop the box of its samples.
  // Its own split scheme: the range starts at the nearest visible point, where logarithmic splits
  // measure best (raster/METHODS.md "Sample distribution shadow maps"); cascades.count and
  // cascades.blend are shared with fit=cascades.
  float sdsmLambda = 1.0f;  // sdsm.lambda: 0 uniform .. 1 logarithmic splits
  bool sdsmSnap = false;    // sdsm.snap: power-of-two texel sizes, crops snapped to whole texels
  // Light-space perspective shadow maps (fit=lispsm, directional lights): the warp's projection
  // center lies lispsmNScale * n_opt before the body's near face (larger: closer to uniform).
  float lispsmNScale = 1.0f;  // lispsm.n_scale: > 0, <= 1e6
  // Perspective shadow maps (fit=psm, directional lights): the virtual camera slides back, beyond
  // what keeps every caster in front of it, by psmSlideBack times the visible depth range.
  float psmSlideBack = 0.0f;       // psm.slide_back: 0..1000
  // Trapezoidal shadow maps (fit=tsm, directional lights; raster/METHODS.md): the 80 % rule maps
  // the end of the focus region (tsmFocusDistance of the view depth range, from its near end) to
  // the map line tsmFocus (0.8: the paper's 80 % line).
  float tsmFocus = 0.8f;           // tsm.focus: (0, 1)
  float tsmFocusDistance = 0.5f;   // tsm.focus_distance: (0, 1]
  float biasConstant = 0.0f;       // bias.constant: Vulkan depthBiasConstantFactor (units of r)
  float biasSlope = 1.5f;          // bias.slope: Vulkan depthBiasSlopeFactor
  float biasClamp = 0.0f;          // bias.clamp: Vulkan depthBiasClamp (0 = no clamp)
  float biasCompare = 0.0005f;     // bias.compare: added in the comparison, normalized depth
  float biasNormal = 0.0f;         // bias.normal: normal-offset of the lookup, in map texels
  bool biasReceiverPlane = false;  // bias.receiver_plane: receiver-plane depth bias per tap
  // Adaptive depth bias (Dou et al. 2014; raster/METHODS.md "Adaptive depth bias"): each tap is
  // compared against the depth where the light's ray through its texel centre meets the receiver's
  // tangent plane, less a scene-scale epsilon; replaces bias.compare in the comparison.
  bool biasAdaptive = false;           // bias.adaptive
  float biasAdaptiveEpsilon = 0.001f;  // bias.adaptive_epsilon: world units along the light ray, 0..1e3
  Filter filter = Filter::None;        // filter: kinds.h's SHADOWLAB_FILTERS
  int filterSize = 3;                  // filter.size: pcf grid N (odd, 3..15)
  int filterTaps = 16;                 // filter.taps: poisson taps (1..64)
  float filterRadius = 1.5f;           // filter.radius: poisson radius in texels (> 0, <= 32)
  // Filterable maps (filter=vsm, evsm2, evsm4, msm; raster/METHODS.md "Filterable maps"): a
  // moments pass after the depth pass, pre-filtered by a separable Gaussian.
  int filterBlur = 2;              // filter.blur: the Gaussian's radius in texels, 0..16 (0: none; sigma = radius / 2)
  float vsmMinVariance = 1e-6f;    // vsm.min_variance: variance floor, normalized depth squared (0..1)
  float vsmBleedReduction = 0.0f;  // vsm.bleed_reduction: linstep cut of the bound, 0..0.99 (0: none)
  float evsmExponentPos = 40.0f;   // evsm.exponent_pos: positive warp exponent, > 0 (clamped to 42, 32F)
  float evsmExponentNeg = 5.0f;    // evsm.exponent_neg: negative warp exponent, > 0 (clamped to 42, 32F)
  float msmMomentBias = 3e-5f;     // msm.moment_bias: moments pulled towards (0.5, ...) by this much, 0..1
  // Soft shadows from the scene light's size (Light::radius, angularDiameterDeg; raster/METHODS.md
  // "Soft filters"). filter=pcss: a blocker search, the penumbra width from the light's size and the
  // blockers' mean depth, then PCF over that width. filter=dpcf: one kernel whose comparisons are
  // blended from a hardened curve towards plain PCF by the penumbra ratio.
  int pcssBlockerTaps = 16;    // pcss.blocker_taps: Poisson taps of the blocker search, 1..64
  int pcssFilterTaps = 32;     // pcss.filter_taps: Poisson taps of the PCF over the penumbra, 1..64
  float pcssMinFilter = 1.5f;  // pcss.min_filter: the smallest kernel radius, texels (> 0, <= 32; a hard light's)
  float pcssMaxPenumbra =
      16.0f;               // pcss.max_penumbra: the largest search and kernel radius, texels (>= min_filter, <= 64)
  bool pcssRotate = true;  // pcss.rotate: rotate the taps per pixel by interleaved-gradient noise
  int dpcfTaps = 16;       // dpcf.taps: Poisson taps of the one kernel, 1..64
  float dpcfMaxPenumbra = 8.0f;       // dpcf.max_penumbra: the largest kernel radius, texels (1..64)
  bool dpcfRotate = true;             // dpcf.rotate: rotate the taps per pixel by interleaved-gradient noise
  bool projectorReverseGuard = true;  // projector.reverse_guard: only project where w >= 0
  // technique: a GLSL file whose shadowVisibility() replaces the filter (filter stays none;
  // technique.h, raster/METHODS.md "Your own technique"); empty: the built-in filters. Its declared
  // keys technique.<name> set here (the others take the file's defaults), and technique.hash as a
  // method JSON pins it ("stem@hash": an edited file is refused rather than taken for the old one).
  std::string technique;
  std::map<std::string, double> techniqueParams;
  std::string techniqueHash;
  // renderer: an outside renderer's adapter (adapter_manifest.h, adapters/README.md) that renders
  // this method's frames instead of the built-in rasterizer: a bundled adapter's name or a path to
  // its adapter.json, as given; empty: the built-in rasterizer. Its keys NAME.KEY, as given (a
  // value from the command line stays text until the manifest types it; adapterKeyValues).
  std::string renderer;
  struct RendererValue {
    nlohmann::json value;
    bool fromText = false;
  };
  std::map<std::string, RendererValue> rendererParams;
  // renderer= came from the command line (--set, --grid, --fixed), not from a file: an adapter that
  // is not bundled runs only then (adapter_session.h, checkAdapterMayRun). Not part of the method's
  // JSON or name.
  bool rendererFromCommandLine = false;
};

// A key NAME.KEY of an outside renderer's adapter: a dotted key whose first part is no built-in
// key's group (map, bias, technique, ...). A method keeps it as given; validateMethod types it
// against the manifest of renderer=, whatever the key order.
bool isRendererMethodKey(const std::string& key);
// renderer= set: the adapter's manifest (loaded and cached), else null.
const AdapterManifest* rendererManifest(const Method& m);
// Every key of the method's adapter (by its manifest name, without the NAME. prefix) with its
// typed value: the method's where given, else the manifest's default. Empty without a renderer.
nlohmann::json adapterKeyValues(const Method& m);

// The fits with one map layer per slice of the view depth (cascades.count of them): cascades, sdsm.
bool isCascadedFit(Fit f);

// The filters that read a moments map rather than comparing depths (vsm, evsm2, evsm4, msm).
bool isMomentFilter(Filter f);
// The filter whose maps the rasterizer renders: the method's, or for a technique file with a
// moments line (technique.h) that filterable map's (its moments pass, its evidence channels).
Filter effectiveFilter(const Method& m);
// The moments a filter stores per texel: 2 (vsm, evsm2) or 4 (evsm4, msm); 0 for the others.
int momentCount(Filter f);

// All keys, in documentation order ("name" excluded).
const std::vector<std::string>& methodKeys();

// Parses a method file (throws InputError naming the file and the JSON pointer / line:col).
Method loadMethodFile(const std::string& path);
// Applies one key=value (value as text, e.g. "pcf", "4096", "true"). `origin` names where it came
// from for the error message (e.g. "--set" or "sweep.json: /grid/map.size/2").
void applyMethodSetting(Method& m, const std::string& key, const std::string& value, const std::string& origin);
// Applies a JSON value (number, string or bool) for one key; same validation.
void applyMethodJson(Method& m, const std::string& key, const nlohmann::json& value, const std::string& origin);
// Flat JSON with every key (and "name"); round-trips through applyMethodJson.
nlohmann::json methodToJson(const Method& m);
// Checks cross-field rules (e.g. odd pcf size); throws InputError prefixed by origin.
void validateMethod(const Method& m, const std::string& origin);

std::string toString(DepthFormat f);
std::string toString(CullMode c);
std::string toString(Fit f);
std::string toString(Filter f);

}  // namespace shadowlab
