// Sweep specification -> validated plan. Everything that can be wrong with the user's input is
// found here, before runSweep creates a single file (the CLI promises "nothing written" on exit 2).
#include <algorithm>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "shadowlab/compare/sweep.h"
#include "shadowlab/compare/compare.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"

namespace shadowlab {
namespace {

using ojson = nlohmann::ordered_json;

// A grid larger than this is almost certainly a typo (e.g. a pasted list); refuse it rather than
// start a run of days.
constexpr size_t kMaxConfigurations = 100000;

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string joinKeys(const std::vector<std::string>& keys) {
  std::string out;
  for (size_t i = 0; i < keys.size(); ++i) out += (i ? ", " : "") + keys[i];
  return out;
}

// The first ',' at or after `from` outside [...], {...} and "..." (npos when none): a JSON array
// or object in a --grid list is one value.
size_t topLevelComma(const std::string& text, size_t from) {
  int depth = 0;
  bool quoted = false;
  for (size_t i = from; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '\\') ++i;
      else if (c == '"') quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    } else if (c == ',' && depth == 0) {
      return i;
    }
  }
  return std::string::npos;
}

bool isMethodKey(const std::string& key) {
  if (key.rfind("technique.", 0) == 0) return true;  // a technique file's own keys (checked per configuration)
  if (isRendererMethodKey(key)) return true;          // an outside renderer's keys (checked per configuration)
  const auto& keys = methodKeys();
  return std::find(keys.begin(), keys.end(), key) != keys.end();
}

bool isSceneKey(const std::string& key) { return key.rfind(kSceneKeyPrefix, 0) == 0; }

std::string scenePointerOf(const std::string& key) { return key.substr(std::string(kSceneKeyPrefix).size()); }

void checkKey(const std::string& key, const std::string& origin) {
  if (isMethodKey(key)) return;
  if (key == kSceneFailureKey) return;
  if (isSceneKey(key)) {
    std::string pointer = scenePointerOf(key);
    try {
      if (pointer.empty() || pointer[0] != '/') throw std::invalid_argument("must start with '/'");
      nlohmann::json::json_pointer p(pointer);
      (void)p;
      return;
    } catch (const std::exception&) {
      throw InputError(formatError(origin, "",
                                   "scene key \"" + key +
                                       "\" has no valid JSON pointer; expected scene:/path/to/value, "
                                       "e.g. scene:/lights/0/elevation_deg, or scene:failure"));
    }
  }
  throw InputError(formatError(origin, "",
                               "unknown key \"" + key + "\"; expected one of " + joinKeys(methodKeys()) +
                                   ", scene:/json/pointer or scene:failure"));
}

void applyValue(Method& m, const std::string& key, const nlohmann::json& value, const std::string& origin) {
  // Command-line values arrive as text, sweep-file values typed: each goes through the parser
  // meant for it so that "256" and 256 are checked by the same rules.
  if (value.is_string()) applyMethodSetting(m, key, value.get<std::string>(), origin);
  else applyMethodJson(m, key, value, origin);
}

std::string methodValueText(const Method& m, const std::string& key) {
  nlohmann::json j = methodToJson(m);
  // A technique's key its file does not declare (a grid over files that declare different keys):
  // the method's check names the file.
  if (!j.contains(key) && key.rfind("technique.", 0) == 0) validateMethod(m, "shadowlab sweep: configuration");
  // An outside renderer's key: checked against its manifest before its value is named.
  if (isRendererMethodKey(key)) validateMethod(m, "shadowlab sweep: configuration");
  if (!j.contains(key)) throw DriverError("methodToJson has no key \"" + key + "\"");
  return canonicalValueText(j.at(key));
}

std::string dirOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

}  // namespace

nlohmann::json sceneValueFromText(const nlohmann::json& v) {
  if (!v.is_string()) return v;
  const std::string text = v.get<std::string>();
  try {
    auto parsed = nlohmann::json::parse(text);
    if (!parsed.is_null()) return parsed;  // "null" stays text: no scene value is null
  } catch (const std::exception&) {
  }
  return v;
}

std::string SweepJob::key() const {
  ResultRow row;
  row.scene = sceneName;
  row.config = config;
  row.light = light;
  return row.key();
}

SweepAxis parseGridArgument(const std::string& text) {
  const std::string origin = "--grid " + text;
  size_t eq = text.find('=');
  if (eq == std::string::npos)
    throw InputError(formatError(origin, "", "no '=' found; expected key=v1,v2,... (e.g. map.size=512,1024)"));
  SweepAxis axis;
  axis.key = trim(text.substr(0, eq));
  axis.origin = origin;
  if (axis.key.empty()) throw InputError(formatError(origin, "", "empty key; expected key=v1,v2,..."));
  std::string list = text.substr(eq + 1);
  if (trim(list).empty())
    throw InputError(formatError(origin, "", "empty list of values for \"" + axis.key + "\"; expected key=v1,v2,..."));
  size_t start = 0;
  int index = 0;
  while (true) {
    size_t comma = topLevelComma(list, start);
    std::string item = trim(list.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    ++index;
    if (item.empty())
      throw InputError(formatError(origin, "",
                                   "value " + std::to_string(index) + " of \"" + axis.key +
                                       "\" is empty; expected a comma-separated list without gaps"));
    axis.values.push_back(item);
    axis.valueOrigins.push_back(origin);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return axis;
}

SweepSetting parseSetArgument(const std::string& text) {
  const std::string origin = "--set " + text;
  size_t eq = text.find('=');
  if (eq == std::string::npos) throw InputError(formatError(origin, "", "no '=' found; expected key=value"));
  SweepSetting s;
  s.key = trim(text.substr(0, eq));
  s.value = trim(text.substr(eq + 1));
  s.origin = origin;
  if (s.key.empty()) throw InputError(formatError(origin, "", "empty key; expected key=value"));
  if (s.value.get<std::string>().empty())
    throw InputError(formatError(origin, "", "empty value for \"" + s.key + "\"; expected key=value"));
  return s;
}

void loadSweepFile(const std::string& path, SweepSpec& spec) {
  // Ordered: the grid's axes keep the order the user wrote them in.
  ojson doc = parseOrderedJsonText(readFile(path), path);
  auto fail = [&](const std::string& pointer, const std::string& what) {
    throw InputError(formatError(path, pointer, what));
  };
  if (!doc.is_object())
    fail("", "got " + jsonTypeName(doc) + "; expected an object { \"scenes\", \"grid\", \"set\", ... }");
  const std::string baseDir = dirOf(path);
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    const std::string& k = it.key();
    const ojson& v = it.value();
    const std::string ptr = "/" + jsonPointerToken(k);
    if (k == "scenes") {
      if (v.is_string()) {
        spec.scenes.push_back(v.get<std::string>());
        spec.sceneOrigins[spec.scenes.back()] = path + ": " + ptr;
        continue;
      }
      if (!v.is_array()) fail(ptr, "got " + jsonTypeName(v) + "; expected an array of scene names or paths");
      if (v.empty()) fail(ptr, "empty list; expected at least one scene (leave \"scenes\" out for all bundled scenes)");
      for (size_t i = 0; i < v.size(); ++i) {
        if (!v[i].is_string() || v[i].get<std::string>().empty())
          fail(ptr + "/" + std::to_string(i), "got " + jsonTypeName(v[i]) + "; expected a scene name or path");
        std::string s = v[i].get<std::string>();
        // Paths are relative to the sweep file; bare names are bundled scenes.
        bool isPath = s.find('/') != std::string::npos || (s.size() > 5 && s.substr(s.size() - 5) == ".json");
        if (isPath && s[0] != '/') s = baseDir + s;
        spec.scenes.push_back(s);
        spec.sceneOrigins[s] = path + ": " + ptr + "/" + std::to_string(i);
      }
    } else if (k == "grid") {
      // One grid object, or an array of them: a union of grids, each block expanded on its own.
      auto readGrid = [&](const ojson& object, const std::string& objectPtr, int block) {
        for (auto g = object.begin(); g != object.end(); ++g) {
          const std::string gptr = objectPtr + "/" + jsonPointerToken(g.key());
          if (g.key() == "scenes") {
            if (block < 0)
              fail(gptr, "\"scenes\" inside a single grid object; expected it in a grid of a union (an array of "
                         "grid objects), or the top-level \"scenes\" for the whole sweep");
            const ojson& list = g.value();
            if (!list.is_array() || list.empty())
              fail(gptr, "got " + (list.is_array() ? std::string("an empty array") : jsonTypeName(list)) +
                             "; expected an array of scene names or paths (the scenes this grid runs on)");
            std::vector<std::string> names;
            for (size_t i = 0; i < list.size(); ++i) {
              if (!list[i].is_string() || list[i].get<std::string>().empty())
                fail(gptr + "/" + std::to_string(i), "got " + jsonTypeName(list[i]) + "; expected a scene name or path");
              std::string sname = list[i].get<std::string>();
              const bool isPath =
                  sname.find('/') != std::string::npos || (sname.size() > 5 && sname.substr(sname.size() - 5) == ".json");
              if (isPath && sname[0] != '/') sname = baseDir + sname;
              names.push_back(sname);
            }
            spec.blockScenes[block] = names;
            spec.blockScenesOrigin[block] = path + ": " + gptr;
            continue;
          }
          SweepAxis axis;
          axis.key = g.key();
          axis.block = block;
          axis.origin = path + ": " + gptr;
          checkKey(axis.key, axis.origin);
          const ojson& list = g.value();
          if (!list.is_array()) fail(gptr, "got " + jsonTypeName(list) + "; expected an array of values");
          if (list.empty()) fail(gptr, "empty list of values; expected at least one");
          for (size_t i = 0; i < list.size(); ++i) {
            const ojson& item = list[i];
            const std::string iptr = gptr + "/" + std::to_string(i);
            if (!item.is_primitive() || item.is_null()) {
              if (!isSceneKey(axis.key) || item.is_null())
                fail(iptr, "got " + jsonTypeName(item) + "; expected a number, string or boolean");
            }
            axis.values.push_back(nlohmann::json::parse(item.dump()));
            axis.valueOrigins.push_back(path + ": " + iptr);
          }
          // A key given twice in a file is caught by the plan's duplicate check.
          spec.grid.push_back(std::move(axis));
        }
      };
      if (v.is_object()) {
        readGrid(v, ptr, -1);
      } else if (v.is_array()) {
        if (v.empty()) fail(ptr, "empty list of grids; expected at least one grid object");
        for (size_t b = 0; b < v.size(); ++b) {
          const std::string bptr = ptr + "/" + std::to_string(b);
          if (!v[b].is_object() || v[b].empty() || (v[b].size() == 1 && v[b].contains("scenes")))
            fail(bptr, "got " + (v[b].is_object() ? std::string("a grid object without axes") : jsonTypeName(v[b])) +
                           "; expected a grid object {\"key\": [v1, v2, ...]}");
          readGrid(v[b], bptr, int(b));
        }
      } else {
        fail(ptr, "got " + jsonTypeName(v) +
                      "; expected an object {\"key\": [v1, v2, ...]} or an array of them (a union of grids)");
      }
    } else if (k == "set") {
      if (!v.is_object()) fail(ptr, "got " + jsonTypeName(v) + "; expected an object {\"key\": value}");
      for (auto s = v.begin(); s != v.end(); ++s) {
        const std::string sptr = ptr + "/" + jsonPointerToken(s.key());
        // A scene: value may be any JSON value (a whole vector); a method key takes a scalar.
        if (s.value().is_null() || (!s.value().is_primitive() && !isSceneKey(s.key())))
          fail(sptr, "got " + jsonTypeName(s.value()) + "; expected a number, string or boolean");
        spec.fixed.push_back({s.key(), nlohmann::json::parse(s.value().dump()), path + ": " + sptr});
      }
    } else if (k == "method") {
      if (!v.is_string() || v.get<std::string>().empty())
        fail(ptr, "got " + jsonTypeName(v) + "; expected a method file path");
      std::string m = v.get<std::string>();
      spec.methodFile = m[0] == '/' ? m : baseDir + m;
    } else if (k == "light") {
      if (!v.is_string()) fail(ptr, "got " + jsonTypeName(v) + "; expected a light name");
      spec.light = v.get<std::string>();
    } else if (k == "spp") {
      if (!v.is_number_integer())
        fail(ptr, "got " + describeJson(v) + "; expected an integer " + std::to_string(kMinSpp) + ".." +
                      std::to_string(kMaxSpp) + " (reference samples per pixel)");
      checkSpp(v.get<int64_t>(), path, ptr);
      spec.spp = v.get<int>();
    } else if (k == "light_samples") {
      if (!v.is_number_integer())
        fail(ptr, "got " + describeJson(v) + "; expected an integer " + std::to_string(kMinLightSamples) + ".." +
                      std::to_string(kMaxLightSamples) + " (light samples per pixel sample of a sized light)");
      checkLightSamples(v.get<int64_t>(), path, ptr);
      spec.lightSamples = v.get<int>();
    } else if (k == "gpu_timeout_s") {
      if (!v.is_number()) fail(ptr, "got " + describeJson(v) + "; expected seconds, a number 0..1e6");
      checkGpuTimeout(v.get<double>(), path, ptr);
      spec.gpuTimeoutS = v.get<double>();
    } else if (k == "keep_images") {
      if (!v.is_boolean()) fail(ptr, "got " + jsonTypeName(v) + "; expected true or false");
      spec.keepImages = v.get<bool>();
    } else if (k == "description" || k == "$schema") {
      if (!v.is_string()) fail(ptr, "got " + jsonTypeName(v) + "; expected a string");
    } else {
      fail(ptr, "unknown key \"" + k +
                    "\"; expected one of scenes, grid, set, method, light, spp, light_samples, gpu_timeout_s, "
                    "keep_images, "
                    "description");
    }
  }
}

SweepPlan planSweep(const SweepSpec& spec) {
  SweepPlan plan;
  plan.spec = spec;
  checkSpp(spec.spp, "--spp");
  checkLightSamples(spec.lightSamples, "--light-samples");
  // Frontier settings: NaN or a negative threshold would make every comparison meaningless.
  if (!std::isfinite(spec.frontierThreshold) || spec.frontierThreshold < 0) {
    char b[64];
    std::snprintf(b, sizeof b, "%g", spec.frontierThreshold);
    throw InputError(formatError("--frontier-threshold", "",
                                 std::string("got ") + b + "; expected a number >= 0 (a rate, e.g. 0.01)"));
  }
  {
    // The metric names a compared frame always has (Metrics::toJson of a comparison of one pixel:
    // an empty one writes its rates as null).
    Metrics one;
    one.pixelsCompared = 1;
    const nlohmann::json known = one.toJson();
    std::string names;
    for (auto it = known.begin(); it != known.end(); ++it)
      if (it.value().is_number()) names += (names.empty() ? "" : ", ") + it.key();
    if (!known.contains(spec.frontierMetric) || !known[spec.frontierMetric].is_number())
      throw InputError(formatError("--frontier-metric", "",
                                   "unknown metric \"" + spec.frontierMetric + "\"; expected one of " + names));
  }

  // Base method: file, then fixed settings.
  Method base;
  if (!spec.methodFile.empty()) base = loadMethodFile(spec.methodFile);
  std::set<std::string> fixedKeys;
  std::vector<SceneOverride> fixedSceneOverrides;
  for (const auto& s : spec.fixed) {
    checkKey(s.key, s.origin);
    if (!fixedKeys.insert(s.key).second)
      throw InputError(formatError(s.origin, "", "\"" + s.key + "\" is set twice; expected each key once"));
    if (isSceneKey(s.key))
      fixedSceneOverrides.push_back({scenePointerOf(s.key), sceneValueFromText(s.value), s.origin});
    else applyValue(base, s.key, s.value, s.origin);
  }

  // Axes: known keys, each once, not also fixed, every value valid on its own and distinct.
  struct Point {
    std::string text;
    nlohmann::json value;
    std::string origin;
  };
  std::vector<std::vector<Point>> axisPoints;
  int blocks = 1;  // a union of grids: blocks 0..blocks-1 (axes of block -1 belong to every block)
  for (const auto& axis : spec.grid) blocks = std::max(blocks, axis.block + 1);
  std::vector<std::string> sweptKeys;  // every key swept in any block, first-given order
  for (size_t a = 0; a < spec.grid.size(); ++a) {
    const SweepAxis& axis = spec.grid[a];
    checkKey(axis.key, axis.origin);
    if (axis.values.empty())
      throw InputError(
          formatError(axis.origin, "", "empty list of values for \"" + axis.key + "\"; expected at least one"));
    for (size_t b = 0; b < a; ++b)
      if (spec.grid[b].key == axis.key &&
          (axis.block < 0 || spec.grid[b].block < 0 || spec.grid[b].block == axis.block))
        throw InputError(
            formatError(axis.origin, "", "\"" + axis.key + "\" is swept twice; expected each key in one --grid"));
    if (std::find(sweptKeys.begin(), sweptKeys.end(), axis.key) == sweptKeys.end()) sweptKeys.push_back(axis.key);
    if (fixedKeys.count(axis.key))
      throw InputError(
          formatError(axis.origin, "", "\"" + axis.key + "\" is both swept and fixed by --set; expected one of them"));
    std::vector<Point> points;
    std::set<std::string> seen;
    for (size_t i = 0; i < axis.values.size(); ++i) {
      const std::string& origin = i < axis.valueOrigins.size() ? axis.valueOrigins[i] : axis.origin;
      Point p;
      p.origin = origin;
      if (isSceneKey(axis.key)) {
        p.value = sceneValueFromText(axis.values[i]);
        p.text = canonicalValueText(p.value);
      } else {
        Method probe = base;
        applyValue(probe, axis.key, axis.values[i], origin);
        p.value = axis.values[i];
        // A technique's key before the technique is known (--grid technique=... beside it): the
        // value as given, checked against the file once each configuration is whole.
        const bool pending = (axis.key.rfind("technique.", 0) == 0 && probe.technique.empty()) ||
                             (isRendererMethodKey(axis.key) && probe.renderer.empty());
        p.text = pending ? canonicalValueText(sceneValueFromText(axis.values[i])) : methodValueText(probe, axis.key);
      }
      if (!seen.insert(p.text).second)
        throw InputError(formatError(
            origin, "", "value \"" + p.text + "\" of \"" + axis.key + "\" appears twice; expected distinct values"));
      points.push_back(std::move(p));
    }
    axisPoints.push_back(std::move(points));
  }

  // The axes of each block; a key a block does not sweep takes the base method's value there (a
  // scene: key has no such value, so it must be swept in every block, unless only blocks that name
  // their scenes sweep it: a configuration without it then runs without it).
  for (const auto& [b, names] : spec.blockScenes)
    if (b < 0 || b >= blocks)
      throw InputError(formatError(spec.blockScenesOrigin.count(b) ? spec.blockScenesOrigin.at(b) : "shadowlab sweep",
                                   "", "\"scenes\" names a grid that has no axes; expected it beside a grid's axes"));
  auto onlyRestrictedBlocksSweep = [&](const std::string& key) {
    for (const auto& axis : spec.grid)
      if (axis.key == key && (axis.block < 0 || !spec.blockScenes.count(axis.block))) return false;
    return true;
  };
  std::vector<std::vector<size_t>> blockAxes(static_cast<size_t>(blocks));
  for (size_t a = 0; a < spec.grid.size(); ++a)
    for (int b = 0; b < blocks; ++b)
      if (spec.grid[a].block < 0 || spec.grid[a].block == b) blockAxes[size_t(b)].push_back(a);
  size_t total = 0;
  for (int b = 0; b < blocks; ++b) {
    size_t product = 1;
    for (size_t a : blockAxes[size_t(b)]) {
      product *= axisPoints[a].size();
      if (product > kMaxConfigurations) break;
    }
    total += product;
    if (total > kMaxConfigurations)
      throw InputError(formatError(
          "shadowlab sweep", "",
          "the grid has more than " + std::to_string(kMaxConfigurations) +
              " configurations; expected a smaller grid (the plan, its journal and results.json are held in "
              "memory, and at ~0.1-0.2 s a row 100000 rows are hours on one machine)"));
    for (const std::string& key : sweptKeys) {
      const auto& axes = blockAxes[size_t(b)];
      const bool inBlock = std::any_of(axes.begin(), axes.end(), [&](size_t a) { return spec.grid[a].key == key; });
      if (!inBlock && isSceneKey(key) && !onlyRestrictedBlocksSweep(key))
        throw InputError(formatError("shadowlab sweep", "/grid/" + std::to_string(b),
                                     "\"" + key +
                                         "\" is swept in another grid of the union but not in this one; "
                                         "expected a scene: key in every grid (or fixed with --set)"));
    }
  }

  // Expand each block: its last axis varies fastest (odometer order); a configuration an earlier
  // block already holds is not repeated.
  std::set<std::string> seenConfigs;
  for (int b = 0; b < blocks; ++b) {
    const std::vector<size_t>& axes = blockAxes[size_t(b)];
    size_t count = 1;
    for (size_t a : axes) count *= axisPoints[a].size();
    std::vector<size_t> idx(axes.size(), 0);
    for (size_t n = 0; n < count; ++n) {
      SweepConfig c;
      c.method = base;
      c.sceneOverrides = fixedSceneOverrides;
      for (size_t i = 0; i < axes.size(); ++i) {
        const Point& p = axisPoints[axes[i]][idx[i]];
        const std::string& key = spec.grid[axes[i]].key;
        if (isSceneKey(key)) c.sceneOverrides.push_back({scenePointerOf(key), p.value, p.origin});
        else applyValue(c.method, key, p.value, p.origin);
        c.values.emplace_back(key, p.text);
      }
      for (const std::string& key : sweptKeys)
        if (std::none_of(axes.begin(), axes.end(), [&](size_t a) { return spec.grid[a].key == key; }) &&
            !isSceneKey(key))
          c.values.emplace_back(key, methodValueText(base, key));
      std::sort(c.values.begin(), c.values.end());
      // The one name of a configuration, as run, tune and stability name it (config_name.h).
      c.config = configName(c.method, c.sceneOverrides);
      for (size_t i = axes.size(); i-- > 0;) {
        if (++idx[i] < axisPoints[axes[i]].size()) break;
        idx[i] = 0;
      }
      auto restricted = spec.blockScenes.find(b);
      if (restricted != spec.blockScenes.end())
        for (const std::string& name : restricted->second) {
          const std::string scenePath = resolveScenePath(name);
          std::error_code ec;
          if (!std::filesystem::is_regular_file(scenePath, ec))
            throw InputError(formatError(spec.blockScenesOrigin.count(b) ? spec.blockScenesOrigin.at(b)
                                                                         : std::string("shadowlab sweep"),
                                         "", "scene \"" + name + "\" not found (" + scenePath +
                                                 "); expected a bundled scene name or a scene file"));
          c.onlyScenes.push_back(scenePath);
        }
      if (!seenConfigs.insert(c.config).second) {
        // The first block's place; its scenes are the union of the blocks' (every scene when one
        // block runs it everywhere).
        auto first = std::find_if(plan.configs.begin(), plan.configs.end(),
                                  [&](const SweepConfig& e) { return e.config == c.config; });
        if (first != plan.configs.end() && !first->onlyScenes.empty()) {
          if (c.onlyScenes.empty()) first->onlyScenes.clear();
          else
            for (const auto& p : c.onlyScenes)
              if (!first->runsOn(p)) first->onlyScenes.push_back(p);
        }
        continue;
      }
      validateMethod(c.method, "shadowlab sweep: configuration " + c.config);
      precompileTechnique(c.method);  // once per file content: a compile error is exit 2 before any output
      plan.configs.push_back(std::move(c));
    }
  }

  // Scenes: resolve, load each under every distinct set of scene values, resolve the light.
  std::vector<std::string> requested = spec.scenes;
  if (requested.empty()) requested = bundledSceneNames();
  if (requested.empty())
    throw InputError(
        formatError("shadowlab sweep", "", "no scenes given and no bundled scenes found in " + bundledScenesDir()));
  std::set<std::string> seenPaths;
  for (const auto& s : requested) {
    std::string p = resolveScenePath(s);
    std::error_code missing;
    auto origin = spec.sceneOrigins.find(s);
    if (origin != spec.sceneOrigins.end() && !std::filesystem::is_regular_file(p, missing)) {
      std::string names;
      for (const std::string& n : bundledSceneNames()) names += (names.empty() ? "" : ", ") + n;
      throw InputError(origin->second + ": error: scene \"" + s + "\" not found (" + p +
                       "); expected a scene file or a bundled scene name: " + names);
    }
    if (!seenPaths.insert(p).second)
      throw InputError(
          formatError("shadowlab sweep", "", "scene \"" + s + "\" is given twice; expected each scene once"));
    plan.scenePaths.push_back(p);
  }
  std::map<std::string, size_t> variantOf;                              // scene index + overrides -> variant
  const std::string failurePointer = scenePointerOf(kSceneFailureKey);  // "failure"
  bool usesFailure = false;
  for (const auto& c : plan.configs)
    for (const auto& o : c.sceneOverrides) usesFailure = usesFailure || o.pointer == failurePointer;
  for (size_t si = 0; si < plan.scenePaths.size(); ++si) {
    std::string sceneName;
    std::string light;
    // scene:failure names this scene's declared failure pointer.
    std::string declared;
    if (usesFailure) {
      declared = loadScene(plan.scenePaths[si]).failurePointer;
      if (declared.empty())
        throw InputError(formatError(plan.scenePaths[si], "",
                                     std::string("the scene declares no \"failure\", so ") + kSceneFailureKey +
                                         " names nothing in it; expected a "
                                         "scene with \"failure\" (scenes/FORMAT.md) or a "
                                         "JSON pointer: scene:/path/to/value"));
    }
    for (size_t ci = 0; ci < plan.configs.size(); ++ci) {
      const SweepConfig& c = plan.configs[ci];
      if (!c.runsOn(plan.scenePaths[si])) continue;
      std::vector<SceneOverride> overrides = c.sceneOverrides;
      for (auto& o : overrides)
        if (o.pointer == failurePointer) {
          o.pointer = declared;
          for (const auto& other : c.sceneOverrides)
            if (other.pointer == declared)
              throw InputError(formatError(plan.scenePaths[si], "",
                                           std::string(kSceneFailureKey) + " is " + declared +
                                               " in this scene, which scene:" + declared +
                                               " also sets; expected one of them"));
        }
      std::string vkey = std::to_string(si);
      for (const auto& o : overrides) vkey += "\n" + o.pointer + "=" + dumpJson(o.value);
      auto found = variantOf.find(vkey);
      size_t vi;
      if (found == variantOf.end()) {
        vi = plan.variants.size();
        plan.variants.push_back(loadScene(plan.scenePaths[si], overrides));
        variantOf.emplace(vkey, vi);
      } else {
        vi = found->second;
      }
      const Scene& scene = plan.variants[vi];
      if (scene.lights.empty())
        throw InputError(
            formatError(plan.scenePaths[si], "/lights", "the scene has no light; expected at least one to compare"));
      if (sceneName.empty()) {
        sceneName = scene.name;
        for (const auto& other : plan.sceneNames)
          if (other == sceneName)
            throw InputError(formatError(
                plan.scenePaths[si], "",
                "two scenes are named \"" + sceneName + "\"; expected distinct file names (rows are matched by name)"));
      }
      if (!spec.light.empty() && !scene.findLight(spec.light)) {
        std::vector<std::string> names;
        for (const auto& l : scene.lights) names.push_back(l.name);
        throw InputError(formatError(plan.scenePaths[si], "",
                                     "no light named \"" + spec.light + "\"; expected one of " +
                                         (names.empty() ? std::string("(none)") : joinKeys(names))));
      }
      light = scene.lightOrDefault(spec.light);
      SweepJob job;
      job.sceneIndex = si;
      job.configIndex = ci;
      job.variantIndex = vi;
      job.light = light;
      job.sceneName = sceneName;
      job.config = c.config;
      plan.jobs.push_back(std::move(job));
    }
    if (sceneName.empty())
      throw InputError(formatError(plan.scenePaths[si], "",
                                   "no configuration of the grid runs on this scene (every grid of the union names "
                                   "its \"scenes\" and none names it); expected it in a grid's \"scenes\", or a "
                                   "grid without \"scenes\""));
    plan.sceneNames.push_back(sceneName);
  }
  return plan;
}

std::vector<SweepAxis> sweptAxes(const SweepPlan& plan) {
  std::vector<SweepAxis> out;
  for (const auto& given : plan.spec.grid) {
    if (std::any_of(out.begin(), out.end(), [&](const SweepAxis& a) { return a.key == given.key; })) continue;
    SweepAxis axis;
    axis.key = given.key;
    axis.origin = given.origin;
    std::vector<std::string> seen;
    for (const auto& c : plan.configs)
      for (const auto& [k, v] : c.values)
        if (k == axis.key && std::find(seen.begin(), seen.end(), v) == seen.end()) seen.push_back(v);
    for (const auto& v : seen) axis.values.push_back(v);
    out.push_back(std::move(axis));
  }
  return out;
}

}  // namespace shadowlab
