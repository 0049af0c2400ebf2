// What `shadowlab tune` writes (compare/TUNE.md, "Outputs"): the verdict, tuned.json (a method
// file), tune.json (every evaluation, the choices, the counts), tune.html (the acne/leak curves
// around the chosen bias, the cost/accuracy points with the choice marked, a triptych per scene)
// and, through the sweep's writer, results.json / results.csv / report.html of every row.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>

#include "shadowlab/compare/classes.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "json_number.h"
#include "tune_output.h"

namespace shadowlab {
namespace {

namespace fs = std::filesystem;

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}
std::string percent(double rate) { return fmt("%.3g %%", rate * 100.0); }
std::string mib(double bytes) { return fmt("%.3g MiB", bytes / (1024.0 * 1024.0)); }

std::string fileSafe(const std::string& s) {
  std::string out;
  for (char c : s) out += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ? c : '_';
  return out;
}

// "bias.slope 1.75, filter pcf, map.size 1024" (a key that does not matter here is left out).
std::string describe(const TunePlan& plan, const TuneEvaluation& e) {
  std::string out;
  for (const auto& k : plan.keys) {
    std::string v;
    for (const auto& [key, value] : e.values)
      if (key == k.key) v = value;
    if (!k.onlyWithKey.empty() && canonicalValueText(methodToJson(e.method).at(k.onlyWithKey)) != k.onlyWithValue)
      continue;
    out += (out.empty() ? "" : ", ") + k.key + " " + v;
  }
  return out.empty() ? "the base method" : out;
}

// The error class with the largest rate in a row's metrics: "acne", "leak", ...
std::string dominantClass(const nlohmann::json& metrics) {
  std::string best = "error";
  double bestRate = -1;
  for (const auto& c : kPixelClasses) {
    if (!c.error || !c.rateMetric) continue;
    const double r = numberAt(metrics, c.rateMetric);
    if (r > bestRate) {
      bestRate = r;
      best = c.key;
    }
  }
  return best;
}

double worstOf(const TuneEvaluation& e, const std::vector<size_t>& scenes, size_t* sceneOut = nullptr) {
  double worst = -1;
  for (size_t s : scenes) {
    const double err = numberAt(e.rows.at(s).metrics, "error_rate");
    if (err > worst) {
      worst = err;
      if (sceneOut) *sceneOut = s;
    }
  }
  return worst;
}

bool hasAll(const TuneEvaluation& e, const std::vector<size_t>& scenes) {
  for (size_t s : scenes)
    if (!e.rows.count(s)) return false;
  return true;
}

// Evaluations equal to `chosen` in every tuned key but `key`, run on every scene of `scenes`,
// by increasing value of `key`.
std::vector<const TuneEvaluation*> lineThrough(const TuneResult& r, const TuneEvaluation& chosen,
                                               const std::string& key, const std::vector<size_t>& scenes) {
  std::vector<const TuneEvaluation*> out;
  for (const auto& e : r.evaluations) {
    if (!hasAll(e, scenes)) continue;
    bool same = true;
    for (size_t i = 0; i < e.values.size(); ++i)
      if (e.values[i].first != key && e.values[i].second != chosen.values[i].second) same = false;
    if (same) out.push_back(&e);
  }
  auto valueOf = [&](const TuneEvaluation* e) {
    for (const auto& [k, v] : e->values)
      if (k == key) return std::strtod(v.c_str(), nullptr);
    return 0.0;
  };
  std::stable_sort(out.begin(), out.end(), [&](auto* a, auto* b) { return valueOf(a) < valueOf(b); });
  return out;
}

std::string valueIn(const TuneEvaluation& e, const std::string& key) {
  for (const auto& [k, v] : e.values)
    if (k == key) return v;
  return "";
}

// "bias.slope 1.25 starts acne on grazing (0.31 %), 2.5 starts leak on contact (0.25 %)": the
// nearest evaluated values on either side that miss the target (--budget-ms: the nearest evaluated).
std::string biasNeighbours(const TunePlan& plan, const TuneResult& r, const TuneEvaluation& chosen,
                           const std::vector<size_t>& scenes) {
  const bool target = !std::isnan(plan.spec.maxError);
  std::string out;
  for (const auto& k : plan.keys) {
    if (k.role != TuneRole::Bias) continue;
    const auto line = lineThrough(r, chosen, k.key, scenes);
    size_t at = line.size();
    for (size_t i = 0; i < line.size(); ++i)
      if (line[i] == &chosen) at = i;
    if (at == line.size()) continue;
    auto describeSide = [&](long step) -> std::string {
      for (long i = long(at) + step; i >= 0 && i < long(line.size()); i += step) {
        const TuneEvaluation& e = *line[size_t(i)];
        if (target && tuneMeetsTarget(plan, e, scenes)) continue;
        size_t s = 0;
        const double w = worstOf(e, scenes, &s);
        return valueIn(e, k.key) + (target ? " starts " : ": ") + dominantClass(e.rows.at(s).metrics) + " on " +
               plan.sweep.sceneNames[s] + " (" + percent(w) + ")";
      }
      return "";
    };
    const std::string below = describeSide(-1), above = describeSide(+1);
    std::string part;
    if (!below.empty()) part = k.key + " " + below;
    if (!above.empty()) part += (part.empty() ? k.key + " " : ", ") + above;
    if (part.empty())
      part = "every evaluated " + k.key + " (" + std::to_string(line.size()) + " values) meets the target";
    out += (out.empty() ? "" : "; ") + part;
  }
  return out;
}

// --max alone leaves error_rate free (--max-error 1): the target is its --max limits alone.
bool errorRateFree(const TunePlan& plan) { return plan.spec.maxError >= 1.0 && !plan.spec.maxRates.empty(); }

// "0.002 (acne_rate 0.0005)", or with error_rate free "penumbra_mae 0.3".
std::string targetText(const TunePlan& plan) {
  std::string limit = errorRateFree(plan) ? "" : fmt("%g", plan.spec.maxError);
  for (const auto& [k, v] : plan.spec.maxRates)
    limit += errorRateFree(plan) ? (limit.empty() ? "" : ", ") + k + " " + fmt("%g", v)
                                 : " (" + k + " " + fmt("%g", v) + ")";
  return limit;
}

std::string choiceSentence(const TunePlan& plan, const TuneResult& r, const TuneChoice& c) {
  const bool target = !std::isnan(plan.spec.maxError);
  const std::string where = c.scope == "all" ? "" : c.scope + ": ";
  if (c.evaluation < 0 && target)  // no configuration has a row on every scene: nothing to rank
    return where + "no configuration was measured on every scene; nothing meets the target";
  if (c.evaluation < 0) {
    // --budget-ms with nothing inside it.
    double cheapest = std::numeric_limits<double>::infinity();
    const TuneEvaluation* which = nullptr;
    for (const auto& e : r.evaluations) {
      const double ms = tuneCost(e, c.scenes).first;
      if (ms < cheapest) {
        cheapest = ms;
        which = &e;
      }
    }
    return where + "nothing fits " + fmt("%g", plan.spec.budgetMs) + " ms: the cheapest configuration" +
           (which ? ", " + describe(plan, *which) + ", is estimated at " + fmt("%.3g", cheapest) + " ms" : "");
  }
  const TuneEvaluation& e = r.evaluations[size_t(c.evaluation)];
  const std::string costs = !plan.base.renderer.empty()
                                ? "measured renderer_frame_ms " + fmt("%.3g", c.measuredMs) +
                                      " ms (an outside renderer: no cost model)"
                                : "estimated " + fmt("%.3g", c.costMs) + " ms (measured method_gpu_ms " +
                                      fmt("%.3g", c.measuredMs) + " ms), map " + mib(c.mapBytes);
  if (!c.met) {
    std::string failing;
    for (size_t s : c.scenes)
      if (!tuneMeetsTarget(plan, e, {s})) failing += (failing.empty() ? "" : ", ") + plan.sweep.sceneNames[s];
    std::string limit = targetText(plan);
    return where + "no setting meets " + limit + " on " + failing + "; best found " + fmt("%.3g", c.worstError) + " (" +
           c.worstScene + ") with " + describe(plan, e) + ", " + costs;
  }
  std::string s = where + describe(plan, e) + ": error " + percent(c.worstError) + " at most (" + c.worstScene + ")" +
                  (target ? ", target " + (errorRateFree(plan) ? targetText(plan) : percent(plan.spec.maxError))
                          : ", budget " + fmt("%g", plan.spec.budgetMs) + " ms") +
                  ", " + costs;
  const std::string n = biasNeighbours(plan, r, e, c.scenes);
  if (!n.empty()) s += "; " + n;
  return s;
}

nlohmann::json choiceJson(const TunePlan& plan, const TuneResult& r, const TuneChoice& c) {
  nlohmann::json j = {{"scope", c.scope},
                      {"met", c.met},
                      {"worst_error_rate", c.evaluation >= 0 ? nlohmann::json(c.worstError) : nlohmann::json()},
                      {"worst_scene", c.worstScene},
                      {"estimated_ms", c.costMs},
                      {"map_bytes", c.mapBytes},
                      {"measured_method_gpu_ms", c.measuredMs},
                      {"rows_asked", c.rowsAsked},
                      {"rows_run", c.rowsRun},
                      {"sentence", c.sentence}};
  std::vector<std::string> names;
  for (size_t s : c.scenes) names.push_back(plan.sweep.sceneNames[s]);
  j["scenes"] = names;
  if (c.evaluation >= 0) {
    const TuneEvaluation& e = r.evaluations[size_t(c.evaluation)];
    j["config"] = e.config;
    j["method"] = methodToJson(e.method);
  } else {
    j["config"] = nullptr;
  }
  return j;
}

// ---- tune.html: small inline SVG charts -----------------------------------------------------------
struct Series {
  std::string label, color;
  std::vector<std::pair<double, double>> points;
  bool dashed = false, line = true;
};

struct Chart {
  std::string title, xLabel, yLabel;
  std::vector<Series> series;
  std::optional<double> markX, hLine;
  std::optional<std::pair<double, double>> markPoint;
  bool logY = true;
  bool logX = false;
};

std::string svgChart(const Chart& c) {
  const double W = 560, H = 320, L = 70, R = 150, T = 30, B = 50;
  constexpr double kFloor = 1e-5;  // rates of 0 drawn here on the log axis
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  auto ty = [&](double y) { return c.logY ? std::log10(std::max(y, kFloor)) : y; };
  auto tx = [&](double x) { return c.logX ? std::log10(std::max(x, 1e-6)) : x; };
  for (const auto& s : c.series)
    for (const auto& [x, y] : s.points) {
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      x0 = std::min(x0, tx(x)), x1 = std::max(x1, tx(x)), y0 = std::min(y0, ty(y)), y1 = std::max(y1, ty(y));
    }
  if (c.hLine) y0 = std::min(y0, ty(*c.hLine)), y1 = std::max(y1, ty(*c.hLine));
  if (!std::isfinite(x0)) return "<p>(no points)</p>\n";
  if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
  if (c.logY) y0 = std::floor(y0), y1 = std::ceil(y1);
  if (y1 - y0 < 1e-12) y0 -= 0.5, y1 += 0.5;
  auto px = [&](double x) { return L + (tx(x) - x0) / (x1 - x0) * (W - L - R); };
  auto py = [&](double y) { return H - B - (ty(y) - y0) / (y1 - y0) * (H - T - B); };
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H << "\" viewBox=\"0 0 " << W
    << " " << H << "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  o << "<text x=\"" << L << "\" y=\"18\" font-size=\"13\">" << escapeMarkup(c.title) << "</text>\n";
  o << "<rect x=\"" << L << "\" y=\"" << T << "\" width=\"" << W - L - R << "\" height=\"" << H - T - B
    << "\" fill=\"none\" stroke=\"#999\"/>\n";
  for (int i = 0; i <= 4; ++i) {
    const double t = x0 + (x1 - x0) * i / 4, x = c.logX ? std::pow(10.0, t) : t;
    o << "<text x=\"" << px(x) << "\" y=\"" << H - B + 15 << "\" text-anchor=\"middle\">" << fmt("%.4g", x)
      << "</text>\n";
  }
  if (c.logY) {
    for (int d = int(y0); d <= int(y1); ++d)
      o << "<text x=\"" << L - 5 << "\" y=\"" << py(std::pow(10.0, d)) + 4 << "\" text-anchor=\"end\">"
        << fmt("%g", std::pow(10.0, d)) << "</text>\n";
  } else {
    for (int i = 0; i <= 4; ++i) {
      const double y = y0 + (y1 - y0) * i / 4;
      o << "<text x=\"" << L - 5 << "\" y=\"" << py(y) + 4 << "\" text-anchor=\"end\">" << fmt("%.3g", y)
        << "</text>\n";
    }
  }
  o << "<text x=\"" << (L + W - R) / 2 << "\" y=\"" << H - 12 << "\" text-anchor=\"middle\">" << escapeMarkup(c.xLabel)
    << "</text>\n";
  o << "<text transform=\"translate(14," << (T + H - B) / 2 << ") rotate(-90)\" text-anchor=\"middle\">"
    << escapeMarkup(c.yLabel) << "</text>\n";
  if (c.hLine)
    o << "<line x1=\"" << L << "\" x2=\"" << W - R << "\" y1=\"" << py(*c.hLine) << "\" y2=\"" << py(*c.hLine)
      << "\" stroke=\"#000\" stroke-dasharray=\"5,4\"/>\n";
  if (c.markX)
    o << "<line x1=\"" << px(*c.markX) << "\" x2=\"" << px(*c.markX) << "\" y1=\"" << T << "\" y2=\"" << H - B
      << "\" stroke=\"#2a2\" stroke-width=\"2\"/>\n";
  int legend = 0;
  for (const auto& s : c.series) {
    std::string path;
    for (const auto& [x, y] : s.points) {
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      path += (path.empty() ? "M" : " L") + fmt("%.1f", px(x)) + "," + fmt("%.1f", py(y));
      o << "<circle cx=\"" << px(x) << "\" cy=\"" << py(y) << "\" r=\"2.5\" fill=\"" << s.color << "\"/>\n";
    }
    if (s.line && !path.empty())
      o << "<path d=\"" << path << "\" fill=\"none\" stroke=\"" << s.color
        << "\"" + std::string(s.dashed ? " stroke-dasharray=\"3,3\"" : "") + "/>\n";
    o << "<text x=\"" << W - R + 8 << "\" y=\"" << T + 12 + 14 * legend << "\" fill=\"" << s.color << "\">"
      << escapeMarkup(s.label) << "</text>\n";
    ++legend;
  }
  if (c.markPoint)
    o << "<circle cx=\"" << px(c.markPoint->first) << "\" cy=\"" << py(c.markPoint->second)
      << "\" r=\"7\" fill=\"none\" stroke=\"#d00\" stroke-width=\"2\"/>\n";
  o << "</svg>\n";
  return o.str();
}

const char* kSceneColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#17becf"};

std::string tuneHtml(const TunePlan& plan, const TuneResult& r,
                     const std::vector<std::pair<std::string, std::string>>& triptychs) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>shadowlab tune</title>\n"
       "<style>body{font-family:sans-serif;max-width:1200px;margin:1em auto;padding:0 1em}"
       "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}"
       "td.t,th.t{text-align:left}.verdict{background:#f4f4f4;padding:.6em;border-left:4px solid #2a2}"
       ".fail{border-left-color:#d00}img{max-width:100%}</style>\n</head>\n<body>\n";
  h << "<h1>shadowlab tune</h1>\n";
  const bool target = !std::isnan(plan.spec.maxError);
  h << "<p>Target: ";
  if (target) {
    h << "error_rate &le; " << escapeMarkup(fmt("%g", plan.spec.maxError)) << " on every scene";
    for (const auto& [k, v] : plan.spec.maxRates) h << ", " << escapeMarkup(k) << " &le; " << fmt("%g", v);
    h << "; the least estimated cost wins (map memory breaks ties).";
  } else {
    h << "the lowest worst-case error_rate whose estimated cost is within " << fmt("%g", plan.spec.budgetMs) << " ms.";
  }
  h << " Costs are the deterministic model of compare/TUNE.md (\"The cost model\"), not measured times; the measured "
       "method_gpu_ms (shadow pass + lookup pass, compare/TIMINGS.md) stands beside them. Rows: <a "
       "href=\"results.json\">results.json</a>, "
       "<a href=\"results.csv\">results.csv</a>, <a href=\"tune.json\">tune.json</a>, the method: "
       "<a href=\"tuned.json\">tuned.json</a>.</p>\n";
  h << "<p class=\"verdict" << (r.robust.met ? "" : " fail") << "\">" << escapeMarkup(r.verdict) << "</p>\n";

  h << "<h2>Choices</h2>\n<table>\n<tr><th class=\"t\">scenes</th><th class=\"t\">configuration</th><th>met</th>"
       "<th>worst error_rate</th><th>estimated ms</th><th>measured ms</th><th>map MiB</th><th>rows asked</th>"
       "<th>rows run</th></tr>\n";
  std::vector<const TuneChoice*> choices{&r.robust};
  for (const auto& c : r.perScene) choices.push_back(&c);
  for (const TuneChoice* c : choices) {
    h << "<tr><td class=\"t\">" << escapeMarkup(c->scope == "all" ? "all (minimax)" : c->scope)
      << "</td><td class=\"t\">"
      << (c->evaluation >= 0 ? escapeMarkup(r.evaluations[size_t(c->evaluation)].config) : "-") << "</td><td>"
      << (c->met ? "yes" : "no") << "</td><td>" << (c->evaluation >= 0 ? fmt("%.4g", c->worstError) : "-")
      << "</td><td>" << fmt("%.3g", c->costMs) << "</td><td>" << fmt("%.3g", c->measuredMs) << "</td><td>"
      << fmt("%.3g", c->mapBytes / 1048576.0) << "</td><td>" << c->rowsAsked << "</td><td>" << c->rowsRun
      << "</td></tr>\n";
  }
  h << "</table>\n<p>" << r.rowsTotal << " rows evaluated (" << r.rowsRun << " rendered by this run, " << r.rowsResumed
    << " read back from rows.jsonl) against " << r.gridRows << " rows of the dense grid of the same keys and values ("
    << fmt("%.1f", r.gridRows ? 100.0 * double(r.rowsTotal) / double(r.gridRows) : 0.0) << " %).</p>\n";

  std::vector<size_t> all;
  for (size_t s = 0; s < plan.sweep.sceneNames.size(); ++s) all.push_back(s);
  if (r.robust.evaluation >= 0) {
    const TuneEvaluation& chosen = r.evaluations[size_t(r.robust.evaluation)];
    for (const auto& k : plan.keys) {
      if (k.role != TuneRole::Bias) continue;
      const auto line = lineThrough(r, chosen, k.key, all);
      Chart c;
      c.title = "acne and leaks along " + k.key + " (the rest as chosen)";
      c.xLabel = k.key;
      c.yLabel = "rate (log; 0 drawn at 1e-5)";
      if (target) c.hLine = plan.spec.maxError;
      c.markX = std::strtod(valueIn(chosen, k.key).c_str(), nullptr);
      for (size_t s : all) {
        const std::string colour = kSceneColours[s % 8];
        Series acne{plan.sweep.sceneNames[s] + " acne", colour, {}, false, true};
        Series leak{plan.sweep.sceneNames[s] + " leak (dashed)", colour, {}, true, true};
        Series err{plan.sweep.sceneNames[s] + " error (dots)", colour, {}, false, false};
        for (const TuneEvaluation* e : line) {
          const double x = std::strtod(valueIn(*e, k.key).c_str(), nullptr);
          acne.points.emplace_back(x, numberAt(e->rows.at(s).metrics, "acne_rate"));
          leak.points.emplace_back(x, numberAt(e->rows.at(s).metrics, "leak_rate"));
          err.points.emplace_back(x, numberAt(e->rows.at(s).metrics, "error_rate"));
        }
        c.series.push_back(err);
        c.series.push_back(acne);
        c.series.push_back(leak);
      }
      h << "<h2>" << escapeMarkup(k.key) << "</h2>\n<p>The evaluated values of " << escapeMarkup(k.key)
        << " with every other key as chosen (" << line.size()
        << " points; a search evaluates few): acne_rate solid, leak_rate dashed, error_rate as dots, one colour per "
           "scene; the chosen value is the green line"
        << (target ? ", the target the dashed black line" : "") << ".</p>\n"
        << svgChart(c);
    }
  }
  {
    Chart c;
    c.title = "cost against accuracy: every configuration evaluated on every scene";
    c.xLabel = "estimated ms (cost model, largest over the scenes; log)";
    c.logX = true;
    c.yLabel = "worst error_rate (log)";
    if (target) c.hLine = plan.spec.maxError;
    Series ok{"meets the target", "#2a2", {}, false, false}, bad{"misses it", "#999", {}, false, false};
    if (!target) ok.label = "within the budget", bad.label = "over the budget";
    for (const auto& e : r.evaluations) {
      if (!hasAll(e, all)) continue;
      (tuneMeetsTarget(plan, e, all) ? ok : bad).points.emplace_back(tuneCost(e, all).first, worstOf(e, all));
    }
    c.series = {ok, bad};
    if (r.robust.evaluation >= 0) c.markPoint = {r.robust.costMs, r.robust.worstError};
    h << "<h2>Cost and accuracy</h2>\n<p>The red ring is the choice.</p>\n" << svgChart(c);
  }
  if (!triptychs.empty()) {
    h << "<h2>The choice on each scene</h2>\n<p>Reference | raster | errors (colours: compare/METRICS.md).</p>\n";
    for (const auto& [scene, file] : triptychs)
      h << "<h3>" << escapeMarkup(scene) << "</h3>\n<img src=\"" << escapeMarkup(file) << "\" alt=\"triptych of "
        << escapeMarkup(scene) << "\">\n";
  }
  h << "</body>\n</html>\n";
  return h.str();
}

}  // namespace

void writeTuneOutputs(TunePlan& plan, SweepRunner& runner, const TuneOptions& options, TuneResult& result) {
  const std::string out = options.outDir;
  std::vector<TuneChoice*> choices{&result.robust};
  for (auto& c : result.perScene) choices.push_back(&c);
  // results.json / results.csv / report.html: every evaluated row, through the sweep's writer.
  SweepPlan rows = plan.sweep;
  rows.configs.clear();
  rows.jobs.clear();
  rows.spec.grid.clear();
  for (const auto& k : plan.keys) {
    SweepAxis axis;
    axis.key = k.key;
    for (const auto& v : k.values) axis.values.push_back(v);
    axis.origin = k.origin;
    rows.spec.grid.push_back(axis);
  }
  const SweepConfig base = plan.sweep.configs.at(0);
  std::vector<size_t> configOf(result.evaluations.size(), size_t(-1));
  for (size_t e = 0; e < result.evaluations.size(); ++e) {
    if (result.evaluations[e].rows.empty()) continue;
    SweepConfig c = base;
    c.config = result.evaluations[e].config;
    c.values = result.evaluations[e].values;
    c.method = result.evaluations[e].method;
    configOf[e] = rows.configs.size();
    rows.configs.push_back(c);
  }
  for (size_t s = 0; s < plan.sweep.jobs.size(); ++s)
    for (size_t e = 0; e < result.evaluations.size(); ++e) {
      if (!result.evaluations[e].rows.count(s)) continue;
      SweepJob job = plan.sweep.jobs[s];
      job.configIndex = configOf[e];
      job.config = result.evaluations[e].config;
      rows.jobs.push_back(job);
    }
  SweepOptions o;
  o.outDir = out;
  o.progress = options.progress;
  o.stop = options.stop;
  o.writeReport = options.writeReport;
  o.triptychs = options.triptychs;
  o.reportScript = options.reportScript;
  o.python = options.python;
  o.timingRepetitions = options.timingRepetitions;
  // The rows the verdict quotes (each choice's configuration on each scene of its scope) carry a
  // median of timed runs, besides the rows near each scene's front that every sweep times again.
  for (const TuneChoice* c : choices)
    if (c->evaluation >= 0)
      for (size_t sc : c->scenes)
        if (result.evaluations[size_t(c->evaluation)].rows.count(sc))
          o.retimeKeys.push_back(result.evaluations[size_t(c->evaluation)].rows.at(sc).key());
  const SweepSummary summary = runSweep(rows, runner, o);
  for (auto& e : result.evaluations)
    for (auto& [sc, row] : e.rows) {
      auto t = summary.retimedTimings.find(row.key());
      if (t != summary.retimedTimings.end()) row.timings = t->second;
    }
  for (TuneChoice* c : choices) {
    if (c->evaluation < 0) continue;
    c->measuredMs = 0;
    for (size_t sc : c->scenes)
      if (result.evaluations[size_t(c->evaluation)].rows.count(sc))
        c->measuredMs = std::max(c->measuredMs, methodMs(result.evaluations[size_t(c->evaluation)].rows.at(sc)));
  }
  result.resultsJson = summary.resultsJson;
  result.reportHtml = summary.reportHtml;
  result.notes.insert(result.notes.end(), summary.notes.begin(), summary.notes.end());

  // Sentences and the verdict.
  result.robust.sentence = choiceSentence(plan, result, result.robust);
  for (auto& c : result.perScene) c.sentence = choiceSentence(plan, result, c);
  result.verdict = result.robust.sentence;
  if (!result.perScene.empty()) {
    result.verdict += ". Each scene alone: ";
    for (size_t i = 0; i < result.perScene.size(); ++i) {
      const TuneChoice& c = result.perScene[i];
      result.verdict += (i ? "; " : "") + c.scope + " " +
                        (c.evaluation >= 0 ? result.evaluations[size_t(c.evaluation)].config : std::string("-")) +
                        (c.met ? "" : " (not met)") + " (" + fmt("%.3g", c.costMs) + " ms)";
    }
  }
  result.verdict += ". " + std::to_string(result.rowsTotal) + " rows evaluated, " +
                    fmt("%.1f", result.gridRows ? 100.0 * double(result.rowsTotal) / double(result.gridRows) : 0.0) +
                    " % of the dense grid's " + std::to_string(result.gridRows) + ".";

  if (result.grid.checked) {
    const TuneResult::Grid& g = result.grid;
    const double fraction = g.rows ? double(result.rowsTotal) / double(g.rows) : 0.0;
    if (!g.met) {
      result.verdict += " The dense grid (" + std::to_string(g.rows) + " rows) has no configuration that " +
                        (std::isnan(plan.spec.maxError) ? "fits the budget" : "meets the target") + " either.";
    } else {
      const bool target = !std::isnan(plan.spec.maxError);
      const double mine = target ? result.robust.costMs : result.robust.worstError;
      const double theirs = target ? g.costMs : g.worstError;
      result.verdict += " The dense grid (" + std::to_string(g.rows) + " rows) finds " + g.config + " (" +
                        (target ? fmt("%.3g ms", g.costMs) : fmt("error %.4g", g.worstError)) + "): the search's " +
                        (target ? "cost" : "error") + " is " +
                        (result.robust.met && theirs > 0 ? fmt("%+.1f %%", 100.0 * (mine / theirs - 1.0))
                                                         : std::string(result.robust.met ? "equal" : "not found")) +
                        " of it, with " + fmt("%.1f", 100.0 * fraction) + " % of its rows.";
    }
  }

  // tuned.json: the robust choice (the best found when the target is not met) as a method file.
  if (result.robust.evaluation >= 0) {
    Method m = result.evaluations[size_t(result.robust.evaluation)].method;
    m.name = "tuned";
    result.tunedJson = (fs::path(out) / "tuned.json").string();
    writeJsonAtomic(result.tunedJson, methodToJson(m));
  }

  // The robust choice on each scene: reference | raster | errors.
  std::vector<std::pair<std::string, std::string>> triptychs;
  if (options.triptychs && result.robust.evaluation >= 0) {
    makeDirs((fs::path(out) / "figures").string());
    for (size_t s = 0; s < plan.sweep.jobs.size(); ++s) {
      const SweepJob& job = plan.sweep.jobs[s];
      const std::string rel = "figures/tune_triptych_" + fileSafe(plan.sweep.sceneNames[s]) + ".png";
      try {
        if (runner.writeTriptych(plan.sweep.variants[job.variantIndex],
                                 result.evaluations[size_t(result.robust.evaluation)].method, job.light,
                                 (fs::path(out) / rel).string()))
          triptychs.emplace_back(plan.sweep.sceneNames[s], rel);
      } catch (const std::exception& e) {
        result.notes.push_back("triptych for " + plan.sweep.sceneNames[s] + " failed: " + e.what());
      }
    }
  }

  // tune.json.
  nlohmann::json j;
  j["schema"] = "shadowlab.tune/1";
  nlohmann::json targetJson = nlohmann::json::object();
  if (!std::isnan(plan.spec.maxError)) {
    targetJson["max_error"] = plan.spec.maxError;
    for (const auto& [k, v] : plan.spec.maxRates) targetJson["max"][k] = v;
  } else {
    targetJson["budget_ms"] = plan.spec.budgetMs;
  }
  j["target"] = targetJson;
  j["scenes"] = plan.sweep.sceneNames;
  nlohmann::json keys = nlohmann::json::array();
  for (const auto& k : plan.keys)
    keys.push_back({{"key", k.key},
                    {"role", k.role == TuneRole::Bias       ? "bias"
                             : k.role == TuneRole::Monotone ? "monotone"
                                                            : "categorical"},
                    {"values", k.values},
                    {"origin", k.origin}});
  j["keys"] = keys;
  nlohmann::json fixed = nlohmann::json::object();
  for (const auto& f : plan.spec.fixed) fixed[f.key] = f.value;
  j["fixed"] = fixed;
  if (!plan.spec.methodFile.empty()) j["method_file"] = plan.spec.methodFile;
  j["cost_model"] = "compare/TUNE.md, \"The cost model\" (estimateMethodCost)";
  j["robust"] = choiceJson(plan, result, result.robust);
  j["per_scene"] = nlohmann::json::array();
  for (const auto& c : result.perScene) j["per_scene"].push_back(choiceJson(plan, result, c));
  nlohmann::json evals = nlohmann::json::array();
  std::vector<size_t> all;
  for (size_t s = 0; s < plan.sweep.sceneNames.size(); ++s) all.push_back(s);
  for (const auto& e : result.evaluations) {
    if (e.rows.empty()) continue;
    nlohmann::json ej = {{"config", e.config}};
    nlohmann::json scenes = nlohmann::json::object();
    for (const auto& [s, row] : e.rows) {
      nlohmann::json sj = {{"cost", e.cost[s].toJson()}};
      if (row.metrics.contains("error_rate")) sj["error_rate"] = row.metrics["error_rate"];
      for (const auto& c : kPixelClasses)  // each error class's rate (classes.h)
        if (c.error && c.rateMetric && row.metrics.contains(c.rateMetric)) sj[c.rateMetric] = row.metrics[c.rateMetric];
      for (const char* t : {"shadow_gpu_ms", "lookup_gpu_ms", "method_gpu_ms", "camera_gpu_ms"})
        if (row.timings.contains(t)) sj[t] = row.timings[t];
      scenes[plan.sweep.sceneNames[s]] = sj;
    }
    ej["scenes"] = scenes;
    if (hasAll(e, all)) {
      ej["worst_error_rate"] = worstOf(e, all);
      ej["estimated_ms"] = tuneCost(e, all).first;
      ej["meets_target"] = tuneMeetsTarget(plan, e, all);
    }
    evals.push_back(ej);
  }
  j["evaluations"] = evals;
  j["rows_total"] = result.rowsTotal;
  j["rows_run"] = result.rowsRun;
  j["rows_resumed"] = result.rowsResumed;
  j["grid_configurations"] = plan.gridConfigurations;
  j["grid_rows"] = result.gridRows;
  j["fraction_of_grid"] = result.gridRows ? double(result.rowsTotal) / double(result.gridRows) : 0.0;
  if (result.grid.checked)
    j["grid_check"] = {
        {"rows", result.grid.rows},
        {"rows_run", result.grid.rowsRun},
        {"met", result.grid.met},
        {"config", result.grid.met ? nlohmann::json(result.grid.config) : nlohmann::json()},
        {"estimated_ms", result.grid.costMs},
        {"map_bytes", result.grid.mapBytes},
        {"worst_error_rate", result.grid.worstError},
        {"search_rows_fraction", result.grid.rows ? double(result.rowsTotal) / double(result.grid.rows) : 0.0}};
  j["verdict"] = result.verdict;
  result.tuneJson = (fs::path(out) / "tune.json").string();
  writeJsonAtomic(result.tuneJson, j);

  result.tuneHtml = (fs::path(out) / "tune.html").string();
  writeFileAtomic(result.tuneHtml, tuneHtml(plan, result, triptychs));
}

}  // namespace shadowlab
