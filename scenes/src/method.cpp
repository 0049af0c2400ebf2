// Method parameters: one table of keys drives files, --set and --grid, so the three can never
// disagree on names, types or ranges.
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/method_keys.h"

#include <cerrno>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <functional>

#include "json_util.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/technique.h"
#include "shadowlab/scenes/adapter_manifest.h"

namespace shadowlab {

const std::vector<KindInfo<Fit>>& fitKinds() {
#define SHADOWLAB_ROW(name, code, key, help) {Fit::name, key, help},
  static const std::vector<KindInfo<Fit>> kinds = {SHADOWLAB_FITS(SHADOWLAB_ROW)};
#undef SHADOWLAB_ROW
  return kinds;
}

const std::vector<KindInfo<Filter>>& filterKinds() {
#define SHADOWLAB_ROW(name, code, key, help) {Filter::name, key, help},
  static const std::vector<KindInfo<Filter>> kinds = {SHADOWLAB_FILTERS(SHADOWLAB_ROW)};
#undef SHADOWLAB_ROW
  return kinds;
}

namespace {

// Every error from one key: "<file>: <place>: error: got X; expected Y".
[[noreturn]] void fail(const std::string& file, const std::string& place, const std::string& got,
                       const std::string& expected) {
  throw InputError(formatError(file, place, "got " + got + "; expected " + expected));
}

struct Where {
  std::string file;
  std::string place;
};

// A value in either form: JSON (files, grids) or text (--set). Each key's parser asks for the
// kind it needs and the conversion reports "got ..." in the form the user wrote.
struct Value {
  const nlohmann::json* json = nullptr;
  const std::string* text = nullptr;

  // Text comes from the command line: describe() quotes it safely whatever its bytes.
  std::string got() const { return detail::describe(json ? *json : nlohmann::json(*text)); }

  bool asInt(long long& out) const {
    if (json) {
      if (json->is_number_integer()) {
        out = json->get<long long>();
        return true;
      }
      if (json->is_number_float()) {
        double d = json->get<double>();
        if (std::isfinite(d) && std::floor(d) == d && std::fabs(d) < 1e15) {
          out = static_cast<long long>(d);
          return true;
        }
      }
      return false;
    }
    if (text->empty()) return false;
    errno = 0;
    char* end = nullptr;
    long long v = std::strtoll(text->c_str(), &end, 10);
    if (errno != 0 || end != text->c_str() + text->size()) return false;
    out = v;
    return true;
  }

  bool asDouble(double& out) const {
    if (json) {
      if (!json->is_number()) return false;
      out = json->get<double>();
      return std::isfinite(out);
    }
    if (text->empty()) return false;
    errno = 0;
    char* end = nullptr;
    double v = std::strtod(text->c_str(), &end);
    // strtod accepts "nan", "inf" and hex floats: only plain finite decimals pass.
    if (errno != 0 || end != text->c_str() + text->size() || !std::isfinite(v)) return false;
    for (char c : *text)
      if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'))
        return false;
    out = v;
    return true;
  }

  bool asBool(bool& out) const {
    if (json) {
      if (json->is_boolean()) {
        out = json->get<bool>();
        return true;
      }
      if (json->is_number_integer() && (json->get<long long>() == 0 || json->get<long long>() == 1)) {
        out = json->get<long long>() == 1;
        return true;
      }
      return false;
    }
    if (*text == "true" || *text == "1") {
      out = true;
      return true;
    }
    if (*text == "false" || *text == "0") {
      out = false;
      return true;
    }
    return false;
  }

  bool asString(std::string& out) const {
    if (json) {
      if (!json->is_string()) return false;
      out = json->get<std::string>();
      return true;
    }
    out = *text;
    return true;
  }
};

// `why`, when given, says where a limit comes from: " (" + why + ")" follows the range.
constexpr const char* kMapSizeWhy = "16384: the largest 2D image every Vulkan device must support, lavapipe's limit";
constexpr const char* kCascadeWhy = "the resolve shader's 8 light layers, resolve_abi.h";

int intIn(const Value& v, const Where& w, long long lo, long long hi, const char* why = nullptr) {
  long long x = 0;
  std::string expected = "an integer " + std::to_string(lo) + ".." + std::to_string(hi) +
                         (why ? std::string(" (") + why + ")" : std::string());
  if (!v.asInt(x) || x < lo || x > hi) fail(w.file, w.place, v.got(), expected);
  return int(x);
}

float floatIn(const Value& v, const Where& w, double lo, double hi, bool loOpen, const std::string& expected) {
  double x = 0;
  if (!v.asDouble(x) || x > hi || x < lo || (loOpen && x == lo)) fail(w.file, w.place, v.got(), expected);
  return float(x);
}

bool boolOf(const Value& v, const Where& w) {
  bool b = false;
  if (!v.asBool(b)) fail(w.file, w.place, v.got(), "true, false, 1 or 0");
  return b;
}

template <class E>
E enumOf(const Value& v, const Where& w, const std::vector<std::pair<const char*, E>>& choices) {
  std::string s;
  std::string names;
  for (const auto& c : choices) names += (names.empty() ? "" : ", ") + std::string(c.first);
  if (v.asString(s))
    for (const auto& c : choices)
      if (s == c.first) return c.second;
  fail(w.file, w.place, v.got(), "one of " + names);
}

const std::vector<std::pair<const char*, DepthFormat>> kFormats = {
    {"d16", DepthFormat::D16}, {"d24", DepthFormat::D24}, {"d32f", DepthFormat::D32F}};
const std::vector<std::pair<const char*, CullMode>> kCulls = {
    {"back", CullMode::Back}, {"front", CullMode::Front}, {"none", CullMode::None}};
// The choice tables of enumOf, from kinds.h's rows (fits, filters) or listed here (formats, culls).
template <class E>
std::vector<std::pair<const char*, E>> choicesOf(const std::vector<KindInfo<E>>& kinds) {
  std::vector<std::pair<const char*, E>> out;
  for (const KindInfo<E>& k : kinds) out.emplace_back(k.key, k.kind);
  return out;
}
const std::vector<std::pair<const char*, Fit>> kFits = choicesOf(fitKinds());
const std::vector<std::pair<const char*, Filter>> kFilters = choicesOf(filterKinds());

// Depth-bias factors are free in Vulkan (negative ones are legal and a sweep may probe them);
// the bound only keeps a typo like 1e30 from overflowing the shader's arithmetic.
constexpr double kBiasLimit = 1e6;

// lispsm.n_scale multiplies a distance: 0 would put the warp's projection center on the body
// (a singular warp), and beyond 1e6 the warp is gone long before (fit=tight in all but rounding).
constexpr double kNScaleLimit = 1e6;
const char* const kNScaleExpected = "a number > 0 and <= 1e6 (1: the optimal n of Wimmer et al.)";

// psm.slide_back is in units of the visible body's view-depth range: at 1000 the warp is long gone.
constexpr double kSlideBackLimit = 1e3;
const char* const kSlideBackExpected = "a number 0..1000 (units of the visible view-depth range; 0: the paper's PSM)";
// fit=tsm's 80 % rule: the target line strictly inside the map (0: q on the top line, 1: no warp
// can reach it), the focus region's end a share of the view depth range past its near end.
const char* const kTsmFocusExpected =
    "a number > 0 and < 1 (the map line the focus region ends on; 0.8: the 80 % rule)";
const char* const kTsmFocusDistanceExpected = "a number > 0 and <= 1 (share of the view depth range)";

// EVSM's warp exponents: the 32F moments clamp them to 42 (raster/METHODS.md); beyond 100 is a typo.
const char* const kExponentExpected = "a number > 0 and <= 100 (clamped to 42, what 32-bit moments hold)";

// The soft filters' keys (pcss.*, dpcf.*): the Poisson disc has 64 points (resolve_abi.h kMaxTaps).
constexpr const char* kTapsWhy = "the Poisson disc's 64 points, resolve_abi.h kMaxTaps";
const char* const kMinFilterExpected = "a number > 0 and <= 32 (map texels)";
const char* const kMaxPenumbraExpected = "a number > 0 and <= 64 (map texels, at least pcss.min_filter)";
const char* const kDpcfMaxPenumbraExpected = "a number 1..64 (map texels)";

// technique=path: a file the method names, read and checked at once (technique.h's errors name it).
std::string techniqueOf(const Value& v, const Where& w) {
  std::string path;
  if (!v.asString(path) || path.empty()) fail(w.file, w.place, v.got(), "a path to a GLSL technique file");
  loadTechniqueFile(path);
  return path;
}

// technique.<name>: the value as a number (true/false as 1/0); the file's declaration checks it
// in crossCheck, whatever order the keys came in.
void applyTechniqueKey(Method& m, const std::string& key, const Value& v, const Where& w) {
  const std::string name = key.substr(std::string("technique.").size());
  if (name == "hash") {
    std::string id;
    if (!v.asString(id) || id.empty()) fail(w.file, w.place, v.got(), "a technique id stem@hash");
    m.techniqueHash = id;
    return;
  }
  double x = 0;
  bool b = false;
  if (v.asDouble(x)) m.techniqueParams[name] = x;
  else if (v.asBool(b)) m.techniqueParams[name] = b ? 1 : 0;
  else fail(w.file, w.place, v.got(), "a number, true or false (a key the technique file declares)");
}

// The technique's cross-checks: keys it declares, in their ranges; the pinned hash; no filter.
void checkTechnique(const Method& m, const std::string& file, const std::string& prefix) {
  auto bad = [&](const std::string& key, const std::string& what) {
    throw InputError(formatError(file, prefix + key, what));
  };
  if (m.technique.empty()) {
    if (!m.techniqueParams.empty())
      bad("technique." + m.techniqueParams.begin()->first, "set without a technique; expected technique=file.glsl");
    if (!m.techniqueHash.empty()) bad("technique.hash", "set without a technique; expected technique=file.glsl");
    return;
  }
  const TechniqueFile& t = loadTechniqueFile(m.technique);
  if (m.filter != Filter::None)
    bad("filter", "got " + toString(m.filter) + " beside technique=" + m.technique +
                      "; expected none (the technique is the filter)");
  if (!m.techniqueHash.empty() && m.techniqueHash != t.id())
    bad("technique.hash", "got " + m.techniqueHash + ", but " + m.technique + " is now " + t.id() +
                              "; expected the file the method was measured with (edited since?)");
  for (const auto& [name, value] : m.techniqueParams) {
    const TechniqueParam* p = t.find(name);
    if (!p) {
      std::string declared;
      for (const TechniqueParam& d : t.params) declared += (declared.empty() ? "" : ", ") + ("technique." + d.name);
      bad("technique." + name, "not declared by " + m.technique + "; expected one of its keys: " +
                                   (declared.empty() ? std::string("(it declares none)") : declared));
    }
    const bool integral = std::floor(value) == value;
    auto num = [](double x) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.9g", x);
      return std::string(buf);
    };
    if (value < p->lo || value > p->hi || (p->type != TechniqueParam::Type::Float && !integral))
      bad("technique." + name, "got " + num(value) + "; expected " +
                                   (p->type == TechniqueParam::Type::Bool
                                        ? std::string("true or false")
                                        : (p->type == TechniqueParam::Type::Int ? "an integer " : "a number ") +
                                              num(p->lo) + ".." + num(p->hi)) +
                                   " (" + m.technique + ":" + std::to_string(p->line) + ")");
  }
}

// renderer=NAME|path: the adapter's manifest is read and checked at once (its errors name it).
std::string rendererOf(const Value& v, const Where& w) {
  std::string given;
  if (!v.asString(given) || given.empty())
    fail(w.file, w.place, v.got(), "a bundled adapter's name or a path to an adapter.json (adapters/README.md)");
  loadAdapterManifest(resolveAdapterPath(given));
  return given;
}

void applyRendererKey(Method& m, const std::string& key, const Value& v) {
  Method::RendererValue value;
  if (v.json) {
    value.value = *v.json;
  } else {
    value.value = *v.text;
    value.fromText = true;
  }
  m.rendererParams[key] = std::move(value);
}

using Setter = std::function<void(Method&, const Value&, const Where&)>;

// One method key: its name, one line of help (`shadowlab methods`) and its parser. The default is
// Method{}'s and the range the parser's own "expected ..." (methodKeyTable()).
struct SetterRow {
  std::string key;
  const char* help;
  Setter set;
};

const std::vector<SetterRow>& setters() {
  static const std::vector<SetterRow> table = {
      {"map.size", "texels per side of each map layer",
       [](Method& m, const Value& v, const Where& w) { m.mapSize = intIn(v, w, 16, 16384, kMapSizeWhy); }},
      {"map.format", "the map's depth format",
       [](Method& m, const Value& v, const Where& w) { m.mapFormat = enumOf(v, w, kFormats); }},
      {"cull", "which faces the shadow pass culls (none: open quads cast from both sides)",
       [](Method& m, const Value& v, const Where& w) { m.cull = enumOf(v, w, kCulls); }},
      {"fit", "how a directional light's map is fitted (kinds.h's fits)",
       [](Method& m, const Value& v, const Where& w) { m.fit = enumOf(v, w, kFits); }},
      {"cascades.count", "fit=cascades: slices of the view depth, one map layer each",
       [](Method& m, const Value& v, const Where& w) { m.cascadeCount = intIn(v, w, 1, 8, kCascadeWhy); }},
      {"cascades.lambda", "fit=cascades: split scheme, 0 uniform .. 1 logarithmic",
       [](Method& m, const Value& v, const Where& w) {
         m.cascadeLambda = floatIn(v, w, 0.0, 1.0, false, "a number 0..1 (0 uniform, 1 logarithmic splits)");
       }},
      {"cascades.blend", "fit=cascades: blend band between cascades, fraction of a cascade's depth range",
       [](Method& m, const Value& v, const Where& w) {
         m.cascadeBlend = floatIn(v, w, 0.0, 0.5, false, "a number 0..0.5 (fraction of a cascade's depth range)");
       }},
      {"cascades.stabilize", "fit=cascades: constant-size crops snapped to whole texels",
       [](Method& m, const Value& v, const Where& w) { m.cascadeStabilize = boolOf(v, w); }},
      {"sdsm.lambda", "fit=sdsm: split scheme over the visible depth range, 0 uniform .. 1 logarithmic",
       [](Method& m, const Value& v, const Where& w) {
         m.sdsmLambda = floatIn(v, w, 0.0, 1.0, false, "a number 0..1 (0 uniform, 1 logarithmic splits)");
       }},
      {"sdsm.snap", "fit=sdsm: each slice's crop snapped to whole texels of a power-of-two size (less shimmer)",
       [](Method& m, const Value& v, const Where& w) { m.sdsmSnap = boolOf(v, w); }},
      {"lispsm.n_scale", "fit=lispsm: the warp's projection center, times the optimal n (larger: closer to uniform)",
       [](Method& m, const Value& v, const Where& w) {
         m.lispsmNScale = floatIn(v, w, 0.0, kNScaleLimit, true, kNScaleExpected);
       }},
      {"psm.slide_back", "fit=psm: how far the virtual camera slides back, times the visible depth range",
       [](Method& m, const Value& v, const Where& w) {
         m.psmSlideBack = floatIn(v, w, 0.0, kSlideBackLimit, false, kSlideBackExpected);
       }},
      {"tsm.focus", "fit=tsm: the map line the focus region ends on (the 80 % rule)",
       [](Method& m, const Value& v, const Where& w) {
         m.tsmFocus = floatIn(v, w, 0.0, 1.0, true, kTsmFocusExpected);
         if (!(m.tsmFocus < 1.0f)) fail(w.file, w.place, v.got(), kTsmFocusExpected);  // open at 1 too
       }},
      {"tsm.focus_distance", "fit=tsm: where the focus region ends, share of the view depth range",
       [](Method& m, const Value& v, const Where& w) {
         m.tsmFocusDistance = floatIn(v, w, 0.0, 1.0, true, kTsmFocusDistanceExpected);
       }},
      {"bias.constant", "Vulkan depthBiasConstantFactor (units of the format's resolution r)",
       [](Method& m, const Value& v, const Where& w) {
         m.biasConstant = floatIn(v, w, -kBiasLimit, kBiasLimit, false, "a finite number -1e6..1e6 (units of r)");
       }},
      {"bias.slope", "Vulkan depthBiasSlopeFactor",
       [](Method& m, const Value& v, const Where& w) {
         m.biasSlope = floatIn(v, w, -kBiasLimit, kBiasLimit, false, "a finite number -1e6..1e6");
       }},
      {"bias.clamp", "Vulkan depthBiasClamp (0: no clamp)",
       [](Method& m, const Value& v, const Where& w) {
         m.biasClamp = floatIn(v, w, -1.0, 1.0, false, "a number -1..1 (normalized depth; 0 = no clamp)");
       }},
      {"bias.compare", "added to the receiver's depth in the comparison (normalized depth)",
       [](Method& m, const Value& v, const Where& w) {
         m.biasCompare = floatIn(v, w, -1.0, 1.0, false, "a number -1..1 (normalized depth)");
       }},
      {"bias.normal", "normal offset of the lookup position, in map texels",
       [](Method& m, const Value& v, const Where& w) {
         m.biasNormal = floatIn(v, w, 0.0, 64.0, false, "a number 0..64 (map texels)");
       }},
      {"bias.receiver_plane", "receiver-plane depth bias per filter tap",
       [](Method& m, const Value& v, const Where& w) { m.biasReceiverPlane = boolOf(v, w); }},
      {"bias.adaptive", "adaptive depth bias (Dou et al. 2014): compare against the receiver's tangent plane",
       [](Method& m, const Value& v, const Where& w) { m.biasAdaptive = boolOf(v, w); }},
      {"bias.adaptive_epsilon", "bias.adaptive: the margin, world units along the light ray",
       [](Method& m, const Value& v, const Where& w) {
         m.biasAdaptiveEpsilon = floatIn(v, w, 0.0, 1e3, false, "a number 0..1000 (world units along the light ray)");
       }},
      {"filter", "how the map comparisons are combined into visibility (kinds.h's filters)",
       [](Method& m, const Value& v, const Where& w) { m.filter = enumOf(v, w, kFilters); }},
      {"filter.size", "filter=pcf: the odd grid size N (N x N comparisons)",
       [](Method& m, const Value& v, const Where& w) { m.filterSize = intIn(v, w, 3, 15); }},
      {"filter.taps", "filter=poisson: taps on the disc",
       [](Method& m, const Value& v, const Where& w) { m.filterTaps = intIn(v, w, 1, 64); }},
      {"filter.radius", "filter=poisson: the disc's radius in map texels",
       [](Method& m, const Value& v, const Where& w) {
         m.filterRadius = floatIn(v, w, 0.0, 32.0, true, "a number > 0 and <= 32 (map texels)");
       }},
      {"filter.blur", "filterable maps: the moments' Gaussian radius in texels (0: none)",
       [](Method& m, const Value& v, const Where& w) { m.filterBlur = intIn(v, w, 0, 16); }},
      {"vsm.min_variance", "vsm, evsm: variance floor (normalized depth squared)",
       [](Method& m, const Value& v, const Where& w) {
         m.vsmMinVariance = floatIn(v, w, 0.0, 1.0, false, "a number 0..1 (normalized depth squared)");
       }},
      {"vsm.bleed_reduction", "vsm, evsm: light-bleeding cut of Chebyshev's bound (0: none)",
       [](Method& m, const Value& v, const Where& w) {
         m.vsmBleedReduction = floatIn(v, w, 0.0, 0.99, false, "a number 0..0.99 (0: no cut)");
       }},
      {"evsm.exponent_pos", "evsm2, evsm4: positive warp exponent (clamped to 42)",
       [](Method& m, const Value& v, const Where& w) {
         m.evsmExponentPos = floatIn(v, w, 0.0, 100.0, true, kExponentExpected);
       }},
      {"evsm.exponent_neg", "evsm4: negative warp exponent (clamped to 42)",
       [](Method& m, const Value& v, const Where& w) {
         m.evsmExponentNeg = floatIn(v, w, 0.0, 100.0, true, kExponentExpected);
       }},
      {"msm.moment_bias", "msm: moments pulled towards the centre by this much",
       [](Method& m, const Value& v, const Where& w) {
         m.msmMomentBias = floatIn(v, w, 0.0, 1.0, false, "a number 0..1 (3e-5: 32-bit moments)");
       }},
      {"pcss.blocker_taps", "filter=pcss: Poisson taps of the blocker search",
       [](Method& m, const Value& v, const Where& w) { m.pcssBlockerTaps = intIn(v, w, 1, 64, kTapsWhy); }},
      {"pcss.filter_taps", "filter=pcss: Poisson taps of the PCF over the penumbra",
       [](Method& m, const Value& v, const Where& w) { m.pcssFilterTaps = intIn(v, w, 1, 64, kTapsWhy); }},
      {"pcss.min_filter", "filter=pcss: the smallest kernel radius in map texels (a hard light's kernel)",
       [](Method& m, const Value& v, const Where& w) {
         m.pcssMinFilter = floatIn(v, w, 0.0, 32.0, true, kMinFilterExpected);
       }},
      {"pcss.max_penumbra", "filter=pcss: the largest blocker-search and kernel radius in map texels",
       [](Method& m, const Value& v, const Where& w) {
         m.pcssMaxPenumbra = floatIn(v, w, 0.0, 64.0, true, kMaxPenumbraExpected);
       }},
      {"pcss.rotate", "filter=pcss: rotate the Poisson taps per pixel (interleaved-gradient noise)",
       [](Method& m, const Value& v, const Where& w) { m.pcssRotate = boolOf(v, w); }},
      {"dpcf.taps", "filter=dpcf: Poisson taps of the one kernel (blocker search and filter)",
       [](Method& m, const Value& v, const Where& w) { m.dpcfTaps = intIn(v, w, 1, 64, kTapsWhy); }},
      {"dpcf.max_penumbra", "filter=dpcf: the largest kernel radius in map texels",
       [](Method& m, const Value& v, const Where& w) {
         m.dpcfMaxPenumbra = floatIn(v, w, 1.0, 64.0, false, kDpcfMaxPenumbraExpected);
       }},
      {"dpcf.rotate", "filter=dpcf: rotate the Poisson taps per pixel (interleaved-gradient noise)",
       [](Method& m, const Value& v, const Where& w) { m.dpcfRotate = boolOf(v, w); }},
      {"projector.reverse_guard", "projectors project only where w >= 0 (not behind the projector)",
       [](Method& m, const Value& v, const Where& w) { m.projectorReverseGuard = boolOf(v, w); }},
      {"technique", "a GLSL file defining float shadowVisibility(ShadowQuery q) (filter=none; its keys: technique.*)",
       [](Method& m, const Value& v, const Where& w) { m.technique = techniqueOf(v, w); }},
      {"renderer",
       "an outside renderer's adapter, bundled (three) or adapter.json (its keys: NAME.*; adapters/README.md)",
       [](Method& m, const Value& v, const Where& w) {
         m.renderer = rendererOf(v, w);
         m.rendererFromCommandLine = w.file.rfind("--", 0) == 0;  // "--set ...", "--grid ...", "--fixed ..."
       }},
  };
  return table;
}

}  // namespace

bool isRendererMethodKey(const std::string& key) {
  const size_t dot = key.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == key.size()) return false;
  const std::string group = key.substr(0, dot);
  if (group == "technique" || group == "renderer") return false;
  for (const SetterRow& row : setters())
    if (row.key.compare(0, dot + 1, group + ".") == 0) return false;
  for (char c : group)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_')) return false;
  return true;
}

namespace {

std::string keyList() {
  std::string s = "name";
  for (const auto& k : methodKeys()) s += ", " + k;
  return s;
}

void apply(Method& m, const std::string& key, const Value& v, const Where& w) {
  if (key == "name") {
    std::string s;
    if (!v.asString(s) || s.empty()) fail(w.file, w.place, v.got(), "a non-empty string");
    m.name = s;
    return;
  }
  if (key.rfind("technique.", 0) == 0) return applyTechniqueKey(m, key, v, w);
  for (const SetterRow& row : setters())
    if (row.key == key) {
      row.set(m, v, w);
      return;
    }
  if (isRendererMethodKey(key)) return applyRendererKey(m, key, v);
  std::vector<std::string> all = methodKeys();
  all.push_back("name");
  throw InputError(formatError(
      w.file, w.place,
      "unknown method key \"" + key + "\"" + detail::didYouMean(key, all) + "; expected one of " + keyList()));
}

// An outside renderer's keys: NAME.KEY of its manifest, each in its range; no technique beside it.
void checkRenderer(const Method& m, const std::string& file, const std::string& prefix) {
  auto bad = [&](const std::string& key, const std::string& what) {
    throw InputError(formatError(file, prefix + key, what));
  };
  if (m.renderer.empty()) {
    if (m.rendererParams.empty()) return;
    const std::string& key = m.rendererParams.begin()->first;
    std::vector<std::string> all = methodKeys();
    all.push_back("name");
    bad(key, "unknown method key \"" + key + "\"" + detail::didYouMean(key, all) + "; expected one of " + keyList() +
                 " (or an outside renderer's NAME.KEY beside renderer=NAME)");
  }
  const AdapterManifest& a = *rendererManifest(m);
  if (!m.technique.empty())
    bad("technique", "set beside renderer=" + m.renderer +
                         "; expected one of the two (a technique runs in the built-in rasterizer)");
  std::string declared;
  std::vector<std::string> full;
  for (const AdapterKey& k : a.keys) {
    full.push_back(a.name + "." + k.name);
    declared += (declared.empty() ? "" : ", ") + full.back();
  }
  for (const auto& [key, given] : m.rendererParams) {
    const size_t dot = key.find('.');
    const std::string group = key.substr(0, dot), name = key.substr(dot + 1);
    if (group != a.name)
      bad(key, "not a key of renderer=" + m.renderer + " (" + a.path + ")" + detail::didYouMean(key, full) +
                   "; expected one of its keys: " + (declared.empty() ? std::string("(it declares none)") : declared));
    const AdapterKey* k = a.find(name);
    if (!k)
      bad(key, "not declared by " + a.path + "; expected one of its keys: " +
                   (declared.empty() ? std::string("(it declares none)") : declared) + detail::didYouMean(key, full));
    if (k->accept(given.value, given.fromText).is_null())
      bad(key, "got " + detail::describe(given.value) + "; expected " + k->expected() + " (" + a.path + ")");
  }
}

// Cross-field and range rules on a whole Method (a hand-built Method skips the setters).
// `prefix` is "/" in files, so places read as JSON pointers there and as keys elsewhere.
void crossCheck(const Method& m, const std::string& file, const std::string& prefix) {
  auto bad = [&](const std::string& key, const std::string& got, const std::string& expected) {
    throw InputError(formatError(file, prefix + key, "got " + got + "; expected " + expected));
  };
  // A PCF grid is centered on the lookup texel: an even size has no center.
  if (m.filterSize % 2 == 0 || m.filterSize < 3 || m.filterSize > 15)
    bad("filter.size", std::to_string(m.filterSize), "an odd integer 3..15");
  if (m.mapSize < 16 || m.mapSize > 16384) bad("map.size", std::to_string(m.mapSize), "an integer 16..16384");
  if (m.filterTaps < 1 || m.filterTaps > 64) bad("filter.taps", std::to_string(m.filterTaps), "an integer 1..64");
  if (!(m.filterRadius > 0.0f && m.filterRadius <= 32.0f))
    bad("filter.radius", jsonFloat(m.filterRadius).dump(), "a number > 0 and <= 32 (map texels)");
  for (auto [key, v] : {std::pair<const char*, float>{"bias.constant", m.biasConstant},
                        {"bias.slope", m.biasSlope},
                        {"bias.clamp", m.biasClamp},
                        {"bias.compare", m.biasCompare},
                        {"bias.normal", m.biasNormal}})
    if (!std::isfinite(v)) bad(key, jsonFloat(v).dump(), "a finite number");
  if (!(m.biasAdaptiveEpsilon >= 0.0f && m.biasAdaptiveEpsilon <= 1e3f))
    bad("bias.adaptive_epsilon", jsonFloat(m.biasAdaptiveEpsilon).dump(), "a number 0..1000");
  if (m.cascadeCount < 1 || m.cascadeCount > 8)
    bad("cascades.count", std::to_string(m.cascadeCount), "an integer 1..8");
  if (!(m.cascadeLambda >= 0.0f && m.cascadeLambda <= 1.0f))
    bad("cascades.lambda", jsonFloat(m.cascadeLambda).dump(), "a number 0..1");
  if (!(m.sdsmLambda >= 0.0f && m.sdsmLambda <= 1.0f))
    bad("sdsm.lambda", jsonFloat(m.sdsmLambda).dump(), "a number 0..1");
  if (!(m.cascadeBlend >= 0.0f && m.cascadeBlend <= 0.5f))
    bad("cascades.blend", jsonFloat(m.cascadeBlend).dump(), "a number 0..0.5");
  if (!(m.lispsmNScale > 0.0f && m.lispsmNScale <= kNScaleLimit))
    bad("lispsm.n_scale", jsonFloat(m.lispsmNScale).dump(), kNScaleExpected);
  if (!(m.psmSlideBack >= 0.0f && m.psmSlideBack <= kSlideBackLimit))
    bad("psm.slide_back", jsonFloat(m.psmSlideBack).dump(), kSlideBackExpected);
  if (!(m.tsmFocus > 0.0f && m.tsmFocus < 1.0f)) bad("tsm.focus", jsonFloat(m.tsmFocus).dump(), kTsmFocusExpected);
  if (!(m.tsmFocusDistance > 0.0f && m.tsmFocusDistance <= 1.0f))
    bad("tsm.focus_distance", jsonFloat(m.tsmFocusDistance).dump(), kTsmFocusDistanceExpected);
  if (m.filterBlur < 0 || m.filterBlur > 16) bad("filter.blur", std::to_string(m.filterBlur), "an integer 0..16");
  if (!(m.vsmMinVariance >= 0.0f && m.vsmMinVariance <= 1.0f))
    bad("vsm.min_variance", jsonFloat(m.vsmMinVariance).dump(), "a number 0..1");
  if (!(m.vsmBleedReduction >= 0.0f && m.vsmBleedReduction <= 0.99f))
    bad("vsm.bleed_reduction", jsonFloat(m.vsmBleedReduction).dump(), "a number 0..0.99");
  for (auto [key, v] : {std::pair<const char*, float>{"evsm.exponent_pos", m.evsmExponentPos},
                        {"evsm.exponent_neg", m.evsmExponentNeg}})
    if (!(v > 0.0f && v <= 100.0f)) bad(key, jsonFloat(v).dump(), kExponentExpected);
  if (!(m.msmMomentBias >= 0.0f && m.msmMomentBias <= 1.0f))
    bad("msm.moment_bias", jsonFloat(m.msmMomentBias).dump(), "a number 0..1");
  for (auto [key, v] : {std::pair<const char*, int>{"pcss.blocker_taps", m.pcssBlockerTaps},
                        {"pcss.filter_taps", m.pcssFilterTaps},
                        {"dpcf.taps", m.dpcfTaps}})
    if (v < 1 || v > 64) bad(key, std::to_string(v), "an integer 1..64 (" + std::string(kTapsWhy) + ")");
  if (!(m.pcssMinFilter > 0.0f && m.pcssMinFilter <= 32.0f))
    bad("pcss.min_filter", jsonFloat(m.pcssMinFilter).dump(), kMinFilterExpected);
  if (!(m.pcssMaxPenumbra > 0.0f && m.pcssMaxPenumbra <= 64.0f))
    bad("pcss.max_penumbra", jsonFloat(m.pcssMaxPenumbra).dump(), kMaxPenumbraExpected);
  // The kernel's radius is clamped to [min_filter, max_penumbra]: an empty interval has no kernel.
  if (m.pcssMaxPenumbra < m.pcssMinFilter)
    bad("pcss.max_penumbra", jsonFloat(m.pcssMaxPenumbra).dump(),
        "a number >= pcss.min_filter (" + jsonFloat(m.pcssMinFilter).dump() + ")");
  if (!(m.dpcfMaxPenumbra >= 1.0f && m.dpcfMaxPenumbra <= 64.0f))
    bad("dpcf.max_penumbra", jsonFloat(m.dpcfMaxPenumbra).dump(), kDpcfMaxPenumbraExpected);
  if (m.name.empty()) bad("name", "\"\"", "a non-empty string");
  checkTechnique(m, file, prefix);
  checkRenderer(m, file, prefix);
}

}  // namespace

const std::vector<std::string>& methodKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k;
    for (const SetterRow& row : setters()) k.push_back(row.key);
    return k;
  }();
  return keys;
}

const std::vector<MethodKeyInfo>& methodKeyTable() {
  static const std::vector<MethodKeyInfo> table = [] {
    const nlohmann::json defaults = methodToJson(Method{});
    // The parser's own words for what it expects: every key refuses null, and its error message
    // ends in "got null; expected <range>".
    const nlohmann::json null;
    auto rangeOf = [&](const std::string& key) {
      Method m;
      const std::string marker = "; expected ";
      try {
        apply(m, key, Value{&null, nullptr}, Where{"", ""});
      } catch (const InputError& e) {
        const std::string message = e.what();
        const size_t at = message.find(marker);
        if (at != std::string::npos) return message.substr(at + marker.size());
      }
      return std::string();  // a key that takes null: tests/app_cli_test.cpp fails on it
    };
    auto typeOf = [](const nlohmann::json& value, const std::string& range) -> std::string {
      if (value.is_boolean()) return "boolean";
      if (value.is_number_integer()) return "integer";
      if (value.is_number()) return "number";
      return range.rfind("one of ", 0) == 0 ? "choice" : "string";
    };
    std::vector<MethodKeyInfo> rows;
    rows.push_back({"name", "string", defaults["name"], rangeOf("name"),
                    "the method's name in results (default: a method file's name)"});
    for (const SetterRow& row : setters()) {
      const std::string range = rangeOf(row.key);
      // A key methodToJson writes only when set (technique) has no default: null, "none" when listed.
      const auto it = defaults.find(row.key);
      const nlohmann::json value = it == defaults.end() ? nlohmann::json() : *it;
      rows.push_back({row.key, it == defaults.end() ? "path" : typeOf(value, range), value, range, row.help});
    }
    return rows;
  }();
  return table;
}

Method loadMethodFile(const std::string& path) {
  nlohmann::json doc = readJsonFile(path);
  if (!doc.is_object()) fail(path, "", detail::describe(doc), "a JSON object of method keys");
  Method m;
  m.name.clear();
  for (const auto& [key, value] : doc.items()) {
    Value v{&value, nullptr};
    apply(m, key, v, Where{path, detail::childPointer("", key)});
  }
  // An unnamed file is named after itself, so results stay distinguishable.
  if (m.name.empty()) {
    std::string stem = path.substr(path.find_last_of('/') + 1);
    if (stem.size() > 5 && stem.compare(stem.size() - 5, 5, ".json") == 0) stem.resize(stem.size() - 5);
    m.name = stem;
  }
  crossCheck(m, path, "/");
  return m;
}

void applyMethodSetting(Method& m, const std::string& key, const std::string& value, const std::string& origin) {
  Value v{nullptr, &value};
  apply(m, key, v, Where{origin, key});
}

void applyMethodJson(Method& m, const std::string& key, const nlohmann::json& value, const std::string& origin) {
  Value v{&value, nullptr};
  apply(m, key, v, Where{origin, key});
}

// Floats through jsonFloat: the shortest text that reads back to the same float (json_reader.h).
nlohmann::json methodToJson(const Method& m) {
  nlohmann::json j = nlohmann::json::object();
  j["name"] = m.name;
  j["map.size"] = m.mapSize;
  j["map.format"] = toString(m.mapFormat);
  j["cull"] = toString(m.cull);
  j["fit"] = toString(m.fit);
  j["cascades.count"] = m.cascadeCount;
  j["cascades.lambda"] = jsonFloat(m.cascadeLambda);
  j["cascades.blend"] = jsonFloat(m.cascadeBlend);
  j["cascades.stabilize"] = m.cascadeStabilize;
  j["sdsm.lambda"] = jsonFloat(m.sdsmLambda);
  j["sdsm.snap"] = m.sdsmSnap;
  j["lispsm.n_scale"] = jsonFloat(m.lispsmNScale);
  j["psm.slide_back"] = jsonFloat(m.psmSlideBack);
  j["tsm.focus"] = jsonFloat(m.tsmFocus);
  j["tsm.focus_distance"] = jsonFloat(m.tsmFocusDistance);
  j["bias.constant"] = jsonFloat(m.biasConstant);
  j["bias.slope"] = jsonFloat(m.biasSlope);
  j["bias.clamp"] = jsonFloat(m.biasClamp);
  j["bias.compare"] = jsonFloat(m.biasCompare);
  j["bias.normal"] = jsonFloat(m.biasNormal);
  j["bias.receiver_plane"] = m.biasReceiverPlane;
  j["bias.adaptive"] = m.biasAdaptive;
  j["bias.adaptive_epsilon"] = jsonFloat(m.biasAdaptiveEpsilon);
  j["filter"] = toString(m.filter);
  j["filter.size"] = m.filterSize;
  j["filter.taps"] = m.filterTaps;
  j["filter.radius"] = jsonFloat(m.filterRadius);
  j["filter.blur"] = m.filterBlur;
  j["vsm.min_variance"] = jsonFloat(m.vsmMinVariance);
  j["vsm.bleed_reduction"] = jsonFloat(m.vsmBleedReduction);
  j["evsm.exponent_pos"] = jsonFloat(m.evsmExponentPos);
  j["evsm.exponent_neg"] = jsonFloat(m.evsmExponentNeg);
  j["msm.moment_bias"] = jsonFloat(m.msmMomentBias);
  j["pcss.blocker_taps"] = m.pcssBlockerTaps;
  j["pcss.filter_taps"] = m.pcssFilterTaps;
  j["pcss.min_filter"] = jsonFloat(m.pcssMinFilter);
  j["pcss.max_penumbra"] = jsonFloat(m.pcssMaxPenumbra);
  j["pcss.rotate"] = m.pcssRotate;
  j["dpcf.taps"] = m.dpcfTaps;
  j["dpcf.max_penumbra"] = jsonFloat(m.dpcfMaxPenumbra);
  j["dpcf.rotate"] = m.dpcfRotate;
  j["projector.reverse_guard"] = m.projectorReverseGuard;
  if (!m.technique.empty()) {  // only then: other methods' results keep their columns
    const TechniqueFile& t = loadTechniqueFile(m.technique);
    j["technique"] = m.technique;
    j["technique.hash"] = t.id();
    for (const TechniqueParam& p : t.params) {
      auto it = m.techniqueParams.find(p.name);
      const double v = it == m.techniqueParams.end() ? p.defaultValue : it->second;
      auto& out = j["technique." + p.name];
      if (p.type == TechniqueParam::Type::Bool) out = v != 0;
      else if (p.type == TechniqueParam::Type::Int) out = int(v);
      else out = jsonFloat(float(v));  // the shortest text, as every method float
    }
  }
  if (!m.renderer.empty()) {  // only then, as technique
    j["renderer"] = m.renderer;
    const AdapterManifest& a = *rendererManifest(m);
    const nlohmann::json values = adapterKeyValues(m);
    for (const AdapterKey& k : a.keys) j[a.name + "." + k.name] = values[k.name];
  }
  return j;
}

const AdapterManifest* rendererManifest(const Method& m) {
  return m.renderer.empty() ? nullptr : &loadAdapterManifest(resolveAdapterPath(m.renderer));
}

nlohmann::json adapterKeyValues(const Method& m) {
  nlohmann::json out = nlohmann::json::object();
  const AdapterManifest* a = rendererManifest(m);
  if (!a) return out;
  for (const AdapterKey& k : a->keys) {
    nlohmann::json value = k.defaultValue;
    if (auto it = m.rendererParams.find(a->name + "." + k.name); it != m.rendererParams.end()) {
      nlohmann::json typed = k.accept(it->second.value, it->second.fromText);
      if (!typed.is_null()) value = std::move(typed);  // an unchecked Method keeps the default
    }
    out[k.name] = std::move(value);
  }
  return out;
}

void validateMethod(const Method& m, const std::string& origin) { crossCheck(m, origin, ""); }

bool isCascadedFit(Fit f) { return f == Fit::Cascades || f == Fit::Sdsm; }

bool isMomentFilter(Filter f) { return momentCount(f) > 0; }

Filter effectiveFilter(const Method& m) {
  if (m.technique.empty()) return m.filter;
  const KindInfo<Filter>* k = findKind(filterKinds(), loadTechniqueFile(m.technique).moments);
  return k ? k->kind : m.filter;
}

int momentCount(Filter f) {
  switch (f) {
    case Filter::Vsm:
    case Filter::Evsm2: return 2;
    case Filter::Evsm4:
    case Filter::Msm: return 4;
    default: return 0;
  }
}

std::string toString(DepthFormat f) {
  for (const auto& c : kFormats)
    if (c.second == f) return c.first;
  return "?";
}
std::string toString(CullMode c) {
  for (const auto& x : kCulls)
    if (x.second == c) return x.first;
  return "?";
}
std::string toString(Fit f) { return kindKey(fitKinds(), f); }
std::string toString(Filter f) { return kindKey(filterKinds(), f); }

}  // namespace shadowlab
