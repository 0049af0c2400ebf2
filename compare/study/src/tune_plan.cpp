// `shadowlab tune`: arguments -> a validated TunePlan. Every input error surfaces here, before
// runTune creates a file (the CLI promises "nothing written" on exit 2).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <set>

#include "shadowlab/compare/classes.h"
#include "shadowlab/compare/tune.h"
#include "shadowlab/scenes/adapter_manifest.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/number_text.h"
#include "shadowlab/scenes/technique.h"

namespace shadowlab {
namespace {

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> splitList(const std::string& text, char sep) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    size_t at = text.find(sep, start);
    out.push_back(trim(text.substr(start, at == std::string::npos ? std::string::npos : at - start)));
    if (at == std::string::npos) break;
    start = at + 1;
  }
  return out;
}

std::string joined(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) out += (i ? sep : "") + v[i];
  return out;
}

std::string tunableList() {
  std::vector<std::string> keys;
  for (const auto& k : tunableKeys()) keys.push_back(k.key);
  return joined(keys);
}

const TunableKey* findTunable(const std::string& key) {
  for (const auto& k : tunableKeys())
    if (key == k.key) return &k;
  // A technique file's own keys (technique.<name>, --fixed technique=file.glsl): each value of its
  // --range list tried; the file's declaration checks them.
  if (key.rfind("technique.", 0) == 0 && key != "technique.hash") {
    static std::map<std::string, std::pair<std::string, TunableKey>> interned;  // stable key strings
    auto& slot = interned[key];
    if (slot.first.empty()) slot = {key, TunableKey{nullptr, TuneRole::Categorical, "", ""}};
    slot.second.key = slot.first.c_str();
    return &slot.second;
  }
  // An outside renderer's keys (NAME.KEY, --fixed renderer=NAME): its role is its manifest type's
  // (tunedRendererKey), its values those of its --range.
  if (isRendererMethodKey(key)) {
    static std::map<std::string, std::pair<std::string, TunableKey>> interned;
    auto& slot = interned[key];
    if (slot.first.empty()) slot = {key, TunableKey{nullptr, TuneRole::Categorical, "", ""}};
    slot.second.key = slot.first.c_str();
    return &slot.second;
  }
  return nullptr;
}

// An outside renderer's key as tune searches it: a number (a bias, a normal offset) as a bias, its
// U-curve searched over --range lo:hi[:intervals]; an int, enum or bool as a list of values.
TunableKey tunedRendererKey(const Method& base, const std::string& key) {
  const AdapterManifest* a = rendererManifest(base);
  if (!a)
    throw InputError(formatError("--keys " + key, "",
                                 "\"" + key + "\" without a renderer; expected --fixed renderer=NAME beside it"));
  const size_t dot = key.find('.');
  const AdapterKey* k = key.substr(0, dot) == a->name ? a->find(key.substr(dot + 1)) : nullptr;
  if (!k)
    throw InputError(formatError("--keys " + key, "", "\"" + key + "\" is not a key of " + a->path));
  TunableKey t = *findTunable(key);
  t.role = k->type == AdapterKey::Type::Number ? TuneRole::Bias : TuneRole::Categorical;
  return t;
}

// A finite number from the whole of `text`, else nullopt.
bool parseNumber(const std::string& text, double& out) {
  const std::string t = trim(text);
  if (t.empty()) return false;
  char* end = nullptr;
  out = std::strtod(t.c_str(), &end);
  return end && *end == '\0' && std::isfinite(out);
}

// The canonical text of `value` for `key`, as a row's config writes it (the resolved method's value).
std::string canonicalFor(const Method& base, const std::string& key, const std::string& value,
                         const std::string& origin) {
  Method probe = base;
  applyMethodSetting(probe, key, value, origin);
  const nlohmann::json j = methodToJson(probe);
  return canonicalValueText(j.at(key));
}

// A grid value's text (%.9g), part of configuration names: unchanged, so that names and resume
// keys stay the same. Messages use numberText (number_text.h), the shortest round-trip text.
std::string gridValueText(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

// A technique file's key over lo:hi (float: lo:hi[:intervals], default 4 intervals; int: every
// integer between, at most 64), inside the range the file declares for it.
std::vector<std::string> techniqueRange(const Method& base, const std::string& key, const std::string& range,
                                        const std::function<void(const std::string&)>& fail) {
  if (base.technique.empty()) fail("\"" + key + "\" without a technique; expected --fixed technique=file.glsl");
  const TechniqueFile& t = loadTechniqueFile(base.technique);
  const TechniqueParam* p = t.find(key.substr(std::string("technique.").size()));
  if (!p) fail("\"" + key + "\" is not declared by " + base.technique + "; expected one of its keys");
  const std::string where = t.path + ":" + std::to_string(p->line);
  if (p->type == TechniqueParam::Type::Bool)
    fail("\"" + key + "\" is a bool (" + where + ") and takes a list of values (false,true), not a range lo:hi");
  const bool integral = p->type == TechniqueParam::Type::Int;
  const auto parts = splitList(range, ':');
  double lo = 0, hi = 0, n = 4;
  const bool counted = parts.size() == 3;
  if (parts.size() < 2 || parts.size() > 3 || !parseNumber(parts[0], lo) || !parseNumber(parts[1], hi) ||
      (counted && !parseNumber(parts[2], n)) || (counted && integral))
    fail("got \"" + range + "\"; expected lo:hi" + std::string(integral ? "" : "[:intervals]") +
         " with finite numbers");
  if (!(lo < hi)) fail("empty range " + range + " (lo >= hi); expected lo < hi");
  for (auto [name, v] : {std::pair<const char*, double>{"lo", lo}, {"hi", hi}})
    if (v < p->lo || v > p->hi)
      fail(std::string(name) + " " + numberText(v) + " is outside " + key + "'s declared range " + numberText(p->lo) +
           ".." + numberText(p->hi) + " (" + where + "); expected lo:hi within it");
  std::vector<std::string> raw;
  if (integral) {
    if (std::floor(hi) - std::ceil(lo) >= 64)
      fail("range " + range + " holds more than 64 integers; expected at most 64");
    for (double v = std::ceil(lo); v <= hi; ++v) raw.push_back(gridValueText(v));
    if (raw.empty()) fail("empty range " + range + ": no integer between; expected at least one");
  } else {
    if (counted && (n != std::floor(n) || n < 1 || n > 64))
      fail("got " + parts[2] + " intervals; expected an integer 1..64");
    for (int i = 0; i <= int(n); ++i) raw.push_back(gridValueText(lo + (hi - lo) * i / n));
  }
  return raw;
}

// The candidate values of one key from its range text ("lo:hi[:n]" or "v1,v2,...").
std::vector<std::string> expandRange(const TunableKey& info, const Method& base, const std::string& range,
                                     const std::string& origin) {
  auto fail = [&](const std::string& what) { throw InputError(formatError(origin, "", what)); };
  const std::string key = info.key;
  std::vector<std::string> raw;
  const bool integerKey = key == "map.size" || key == "filter.size" || key == "filter.taps" ||
                          key == "pcss.blocker_taps" || key == "pcss.filter_taps" || key == "dpcf.taps";
  if (range.find(':') != std::string::npos && key.rfind("technique.", 0) == 0) {
    raw = techniqueRange(base, key, range, fail);
  } else if (range.find(':') != std::string::npos) {
    if (info.role == TuneRole::Categorical && !integerKey)
      fail("\"" + key + "\" takes a list of values (v1,v2,...), not a range lo:hi");
    const auto parts = splitList(range, ':');
    double lo = 0, hi = 0, n = 16;
    const bool counted = parts.size() == 3;
    if (parts.size() < 2 || parts.size() > 3 || !parseNumber(parts[0], lo) || !parseNumber(parts[1], hi) ||
        (counted && !parseNumber(parts[2], n)))
      fail("got \"" + range + "\"; expected lo:hi" + std::string(info.role == TuneRole::Bias ? "[:intervals]" : "") +
           " with finite numbers");
    if (!(lo <= hi)) fail("empty range " + range + " (lo > hi); expected lo <= hi");
    if (info.role == TuneRole::Bias) {
      if (counted && (n != std::floor(n) || n < 1 || n > 64))
        fail("got " + parts[2] + " intervals; expected an integer 1..64");
      if (lo == hi) fail("empty range " + range + " (lo = hi); expected lo < hi");
      for (int i = 0; i <= int(n); ++i) raw.push_back(gridValueText(lo + (hi - lo) * i / n));
    } else if (key == "filter.size") {
      if (counted) fail("got \"" + range + "\"; expected lo:hi (the odd sizes between)");
      for (long v = long(std::ceil(lo)); v <= long(std::floor(hi)) && raw.size() < 64; ++v)
        if (v % 2 == 1) raw.push_back(std::to_string(v));
    } else {  // map.size, filter.taps: the powers of two between
      if (counted) fail("got \"" + range + "\"; expected lo:hi (the powers of two between)");
      for (double v = 1; v <= hi && v <= 1e9; v *= 2)
        if (v >= lo) raw.push_back(std::to_string(long(v)));
    }
    if (raw.empty())
      fail("empty range " + range + ": no " + std::string(key == "filter.size" ? "odd number" : "power of two") +
           " between; expected at least one");
  } else {
    raw = splitList(range, ',');
    for (size_t i = 0; i < raw.size(); ++i)
      if (raw[i].empty())
        fail("value " + std::to_string(i + 1) + " is empty; expected a comma-separated list without gaps");
  }
  // Each value through the method parser (ranges and types), in canonical form, distinct.
  std::vector<std::string> values;
  std::set<std::string> seen;
  for (const auto& r : raw) {
    std::string v = canonicalFor(base, key, r, origin);
    if (!seen.insert(v).second) fail("value \"" + v + "\" appears twice; expected distinct values");
    values.push_back(v);
  }
  if (info.role != TuneRole::Categorical || integerKey) {
    std::vector<std::pair<double, std::string>> sorted;
    for (const auto& v : values) sorted.emplace_back(std::strtod(v.c_str(), nullptr), v);
    std::stable_sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    values.clear();
    for (const auto& [d, v] : sorted) values.push_back(v);
  }
  return values;
}

std::string defaultRangeOf(const TunableKey& k) {
  std::vector<std::string> names;
  if (std::string(k.key) == "filter")
    for (const auto& f : filterKinds()) names.push_back(f.key);
  else if (std::string(k.key) == "fit")
    for (const auto& f : fitKinds()) names.push_back(f.key);
  return names.empty() ? std::string(k.defaultRange) : joined(names, ",");
}

}  // namespace

const std::vector<TunableKey>& tunableKeys() {
  // Sorted by key. filter and fit take every kind of kinds.h (defaultRangeOf).
  static const std::vector<TunableKey> keys = {
      {"bias.adaptive", TuneRole::Categorical, "false,true", ""},
      {"bias.compare", TuneRole::Bias, "0:0.004:16", ""},
      {"bias.constant", TuneRole::Bias, "0:200000:16", ""},
      {"bias.normal", TuneRole::Bias, "0:4:16", ""},
      {"bias.slope", TuneRole::Bias, "0:4:16", ""},
      {"dpcf.max_penumbra", TuneRole::Categorical, "8,4,16", "filter=dpcf"},
      {"dpcf.rotate", TuneRole::Categorical, "true,false", "filter=dpcf"},
      {"dpcf.taps", TuneRole::Categorical, "8:32", "filter=dpcf"},
      {"filter", TuneRole::Categorical, "", ""},
      {"filter.size", TuneRole::Categorical, "3:7", "filter=pcf"},
      {"filter.taps", TuneRole::Categorical, "8:32", "filter=poisson"},
      {"fit", TuneRole::Categorical, "", ""},
      {"map.format", TuneRole::Categorical, "d16,d24,d32f", ""},
      {"map.size", TuneRole::Monotone, "256:4096", ""},
      {"pcss.blocker_taps", TuneRole::Categorical, "8:32", "filter=pcss"},
      {"pcss.filter_taps", TuneRole::Categorical, "16:64", "filter=pcss"},
      {"pcss.max_penumbra", TuneRole::Categorical, "16,8,32", "filter=pcss"},
      {"pcss.min_filter", TuneRole::Categorical, "1.5,1,2", "filter=pcss"},
      {"pcss.rotate", TuneRole::Categorical, "true,false", "filter=pcss"},
  };
  return keys;
}

const char* defaultTuneKeys() { return "bias.slope,filter,map.size"; }

double parseTuneNumber(const std::string& flag, const std::string& text) {
  double v = 0;
  const bool rate = flag == "--max-error";
  if (!parseNumber(text, v) || v < 0 || (rate && v > 1) || (!rate && v == 0))
    throw InputError(flag + ": error: got \"" + text + "\"; expected " +
                     (rate ? "a rate from 0 to 1 (e.g. 0.002: 0.2 % of the compared pixels)"
                           : "a time in milliseconds > 0 (the cost model's estimate, compare/TUNE.md)"));
  return v;
}

std::vector<std::string> tuneMaxMetrics() {
  std::vector<std::string> out;  // the error classes' rates (classes.h), then the visibility errors
  for (const auto& c : kPixelClasses)
    if (c.error && c.rateMetric) out.push_back(c.rateMetric);
  out.push_back("mae");
  out.push_back("rmse");
  for (const auto& r : kVisRegions) {
    out.push_back(r.maeMetric);
    out.push_back(r.rmseMetric);
  }
  out.push_back("over_shadowing");
  out.push_back("under_shadowing");
  return out;
}

bool tuneTargetVacuous(const nlohmann::json& metrics, const std::string& key) {
  for (const auto& r : kVisRegions) {
    if (key != r.maeMetric && key != r.rmseMetric) continue;
    auto pixels = metrics.find(r.pixelsMetric);
    return pixels != metrics.end() && pixels->is_number() && pixels->get<double>() == 0.0;
  }
  return false;
}

std::pair<std::string, double> parseTuneMax(const std::string& text) {
  const std::string origin = "--max " + text;
  const size_t eq = text.find('=');
  if (eq == std::string::npos) throw InputError(formatError(origin, "", "no '=' found; expected metric=rate"));
  const std::string key = trim(text.substr(0, eq)), value = trim(text.substr(eq + 1));
  const std::vector<std::string> metrics = tuneMaxMetrics();
  if (std::find(metrics.begin(), metrics.end(), key) == metrics.end())
    throw InputError(formatError(
        origin, "",
        "unknown metric \"" + key + "\"; expected one of " + joined(metrics) + " (error_rate is --max-error)"));
  double v = 0;
  if (!parseNumber(value, v) || v < 0 || v > 1)
    throw InputError(formatError(
        origin, "", "got \"" + value + "\"; expected a number from 0 to 1 (a rate, or a visibility difference)"));
  return {key, v};
}

TunePlan planTune(const TuneSpec& spec) {
  TunePlan plan;
  plan.spec = spec;
  // The target: exactly one of the two.
  const bool hasError = !std::isnan(spec.maxError), hasBudget = !std::isnan(spec.budgetMs);
  if (hasError == hasBudget)
    throw InputError(std::string("--max-error/--budget-ms: error: ") + (hasError ? "both given" : "neither given") +
                     "; expected one of them (the accuracy target, or the time budget)");
  if (hasError && (!std::isfinite(spec.maxError) || spec.maxError < 0 || spec.maxError > 1))
    throw InputError("--max-error: error: got " + numberText(spec.maxError) + "; expected a rate from 0 to 1");
  if (hasBudget && (!std::isfinite(spec.budgetMs) || spec.budgetMs <= 0))
    throw InputError("--budget-ms: error: got " + numberText(spec.budgetMs) + "; expected a time in ms > 0");
  if (hasBudget && !spec.maxRates.empty())
    throw InputError("--max: error: given with --budget-ms; expected --max with --max-error (rates are targets)");
  std::set<std::string> maxKeys;
  for (const auto& [k, v] : spec.maxRates) {
    if (!maxKeys.insert(k).second) throw InputError("--max " + k + ": error: given twice; expected each rate once");
    if (!std::isfinite(v) || v < 0 || v > 1)
      throw InputError("--max " + k + ": error: got " + numberText(v) + "; expected a rate from 0 to 1");
  }

  // The scenes, the base method and the fixed values: planned like a sweep with nothing swept.
  SweepSpec sweep;
  sweep.scenes = spec.scenes;
  sweep.fixed = spec.fixed;
  sweep.methodFile = spec.methodFile;
  sweep.light = spec.light;
  sweep.spp = spec.spp;
  sweep.lightSamples = spec.lightSamples;
  std::set<std::string> fixedKeys;
  for (const auto& f : spec.fixed) fixedKeys.insert(f.key);
  // Keys.
  std::vector<std::string> keys = spec.keys;
  if (keys.empty()) keys = splitList(defaultTuneKeys(), ',');
  std::set<std::string> tuned;
  for (const auto& k : keys) {
    const std::string origin = "--keys " + k;
    if (k.empty()) throw InputError("--keys: error: an empty key; expected a comma-separated list without gaps");
    if (!findTunable(k)) {
      const auto& all = methodKeys();
      const bool methodKey = std::find(all.begin(), all.end(), k) != all.end();
      throw InputError(formatError(
          origin, "",
          (methodKey ? "\"" + k + "\" cannot be tuned (set it with --fixed)" : "unknown key \"" + k + "\"") +
              "; expected one of " + tunableList()));
    }
    if (!tuned.insert(k).second) throw InputError(formatError(origin, "", "\"" + k + "\" given twice"));
    if (fixedKeys.count(k))
      throw InputError(formatError(origin, "", "\"" + k + "\" is both tuned and fixed by --fixed; expected one"));
  }
  const SweepPlan fixedPlan = planSweep(sweep);  // scenes, fixed values, method file, light: InputError
  plan.base = fixedPlan.configs.at(0).method;
  plan.sweep = fixedPlan;

  // Ranges.
  std::map<std::string, std::pair<std::string, std::string>> ranges;  // key -> (text, origin)
  for (const auto& r : spec.ranges) {
    const std::string origin = "--range " + r;
    const size_t eq = r.find('=');
    if (eq == std::string::npos) throw InputError(formatError(origin, "", "no '=' found; expected key=lo:hi"));
    const std::string key = trim(r.substr(0, eq)), text = trim(r.substr(eq + 1));
    if (!tuned.count(key))
      throw InputError(formatError(origin, "",
                                   "\"" + key + "\" is not a tuned key; expected one of --keys (" +
                                       joined(std::vector<std::string>(tuned.begin(), tuned.end())) + ")"));
    if (text.empty()) throw InputError(formatError(origin, "", "empty range; expected lo:hi or v1,v2,..."));
    if (!ranges.emplace(key, std::make_pair(text, origin)).second)
      throw InputError(formatError(origin, "", "a second range for \"" + key + "\"; expected one"));
  }
  std::vector<TunableKey> candidates = tunableKeys();
  for (const auto& k : keys)
    if (k.rfind("technique.", 0) == 0) {
      if (!ranges.count(k))
        throw InputError(formatError(
            "--keys " + k, "",
            "a technique's key has no default range; expected --range " + k + "=lo:hi or " + k + "=v1,v2,..."));
      candidates.push_back(*findTunable(k));
    } else if (isRendererMethodKey(k)) {
      const TunableKey t = tunedRendererKey(plan.base, k);
      if (!ranges.count(k))
        throw InputError(formatError("--keys " + k, "",
                                     "an outside renderer's key has no default range; expected --range " + k +
                                         (t.role == TuneRole::Bias ? "=lo:hi[:intervals]" : "=v1,v2,...")));
      candidates.push_back(t);
    }
  for (const auto& k : candidates) {
    if (!tuned.count(k.key)) continue;
    TuneKey t;
    t.key = k.key;
    t.role = k.role;
    auto found = ranges.find(k.key);
    const std::string range = found != ranges.end() ? found->second.first : defaultRangeOf(k);
    t.origin = found != ranges.end() ? found->second.second : "default range " + range;
    t.values = expandRange(k, plan.base, range, t.origin);
    const std::string only = k.onlyWith;
    if (!only.empty()) {
      t.onlyWithKey = only.substr(0, only.find('='));
      t.onlyWithValue = only.substr(only.find('=') + 1);
      // It must be able to matter: its controlling key tuned over that value, or fixed to it.
      const bool controlTuned = tuned.count(t.onlyWithKey) > 0;
      const std::string baseValue = canonicalValueText(methodToJson(plan.base).at(t.onlyWithKey));
      if (!controlTuned && baseValue != t.onlyWithValue)
        throw InputError(formatError("--keys " + t.key, "",
                                     "\"" + t.key + "\" matters only with " + only + " but " + t.onlyWithKey + " is " +
                                         baseValue + "; expected --fixed " + only + " or " + t.onlyWithKey +
                                         " among --keys"));
    }
    plan.keys.push_back(std::move(t));
  }
  for (const auto& t : plan.keys)
    if (!t.onlyWithKey.empty())
      for (const auto& c : plan.keys)
        if (c.key == t.onlyWithKey && std::find(c.values.begin(), c.values.end(), t.onlyWithValue) == c.values.end())
          throw InputError(formatError(c.origin, "",
                                       "\"" + t.key + "\" is tuned but " + c.key + " never takes " + t.onlyWithValue +
                                           "; expected " + t.onlyWithValue + " among its values"));

  // Cross-field rules on every categorical combination (the biases and sizes are checked one by
  // one above); the dense grid's size on the way.
  std::vector<const TuneKey*> categorical;
  size_t others = 1;
  for (const auto& t : plan.keys) {
    if (t.role == TuneRole::Categorical) categorical.push_back(&t);
    else others *= t.values.size();
  }
  std::vector<size_t> idx(categorical.size(), 0);
  std::set<std::string> combos;
  while (true) {
    Method m = plan.base;
    std::string text;
    for (size_t i = 0; i < categorical.size(); ++i)
      applyMethodSetting(m, categorical[i]->key, categorical[i]->values[idx[i]], categorical[i]->origin);
    // A key that does not matter here (filter.size without pcf) is held at its first value.
    for (size_t i = 0; i < categorical.size(); ++i) {
      const TuneKey& t = *categorical[i];
      std::string v = t.values[idx[i]];
      if (!t.onlyWithKey.empty() && canonicalValueText(methodToJson(m).at(t.onlyWithKey)) != t.onlyWithValue)
        v = t.values[0];
      text += t.key + "=" + v + ",";
    }
    validateMethod(m, "shadowlab tune: configuration " + text);
    combos.insert(text);
    bool done = true;
    for (size_t a = categorical.size(); a-- > 0;) {
      if (++idx[a] < categorical[a]->values.size()) {
        done = false;
        break;
      }
      idx[a] = 0;
    }
    if (done) break;
  }
  plan.gridConfigurations = combos.size() * others;
  return plan;
}

}  // namespace shadowlab
