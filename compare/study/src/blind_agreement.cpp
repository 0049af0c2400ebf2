// The blind rule against the full one (blind_agreement.h).
#include "shadowlab/compare/blind_agreement.h"

#include <cstdio>

#include "shadowlab/compare/classify.h"
#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {

uint64_t ClassConfusion::wrong() const {
  uint64_t n = 0;
  for (const auto& row : counts)
    for (uint64_t c : row) n += c;
  return n;
}

uint64_t ClassConfusion::agreeing() const {
  uint64_t n = 0;
  for (size_t k = 0; k < kPixelClassCount; ++k) n += counts[k][k];
  return n;
}

uint64_t ClassConfusion::ofFull(PixelClass full) const {
  uint64_t n = 0;
  for (uint64_t c : counts[classIndex(full)]) n += c;
  return n;
}

double ClassConfusion::worstConfusion(PixelClass* full, PixelClass* blind) const {
  double worst = 0;
  for (const PixelClassInfo& f : kPixelClasses) {
    const uint64_t total = ofFull(f.cls);
    if (total == 0) continue;
    for (const PixelClassInfo& b : kPixelClasses) {
      if (b.cls == f.cls) continue;
      const double share = double(counts[classIndex(f.cls)][classIndex(b.cls)]) / double(total);
      if (share > worst) {
        worst = share;
        if (full) *full = f.cls;
        if (blind) *blind = b.cls;
      }
    }
  }
  return worst;
}

void ClassConfusion::add(const ClassConfusion& other) {
  for (size_t f = 0; f < kPixelClassCount; ++f)
    for (size_t b = 0; b < kPixelClassCount; ++b) counts[f][b] += other.counts[f][b];
}

std::string ClassConfusion::markdown() const {
  std::vector<const PixelClassInfo*> rows, cols;
  for (const PixelClassInfo& c : kPixelClasses) {
    if (!c.error) continue;
    uint64_t asBlind = 0;
    for (size_t f = 0; f < kPixelClassCount; ++f) asBlind += counts[f][classIndex(c.cls)];
    if (ofFull(c.cls) > 0) rows.push_back(&c);
    if (ofFull(c.cls) > 0 || asBlind > 0) cols.push_back(&c);
  }
  std::string out = "| full \\ blind |";
  for (const PixelClassInfo* c : cols) out += std::string(" ") + c->key + " |";
  out += " pixels | same |\n|---|";
  for (size_t k = 0; k < cols.size(); ++k) out += "---|";
  out += "---|---|\n";
  char buf[64];
  for (const PixelClassInfo* r : rows) {
    const uint64_t total = ofFull(r->cls);
    out += std::string("| ") + r->key + " |";
    for (const PixelClassInfo* c : cols) {
      const uint64_t n = counts[classIndex(r->cls)][classIndex(c->cls)];
      if (n == 0) {
        out += " 0 |";
      } else {
        std::snprintf(buf, sizeof buf, " %llu (%.1f %%) |", (unsigned long long)n, 100.0 * double(n) / double(total));
        out += buf;
      }
    }
    std::snprintf(buf, sizeof buf, " %llu | %.1f %% |\n", (unsigned long long)total,
                  100.0 * double(counts[classIndex(r->cls)][classIndex(r->cls)]) / double(total));
    out += buf;
  }
  const uint64_t all = wrong();
  // The "all" row: empty class cells, the total and the share on the diagonal.
  std::string allRow = "| all |";
  for (size_t k = 0; k < cols.size(); ++k) allRow += " |";
  std::snprintf(buf, sizeof buf, " %llu | %.1f %% |\n", (unsigned long long)all,
                all ? 100.0 * double(agreeing()) / double(all) : 0.0);
  out += allRow + buf;
  return out;
}

DeclaredRenderer declaredByRaster(const Rasterizer& rasterizer, const Method& method) {
  DeclaredRenderer d;
  d.name = "shadowlab raster";
  d.lightClipFromWorld = rasterizer.lastLightClipFromWorld();
  d.mapSize = method.mapSize;
  d.filter = toString(method.filter);
  return d;
}

Frame blindCopy(const Frame& raster, const std::string& light) {
  Frame f;
  f.width = raster.width;
  f.height = raster.height;
  const std::string vis = "light." + light + ".vis";
  for (const std::string& name : {std::string("hit"), std::string("object_id"), vis}) {
    if (!raster.has(name)) throw InputError("blind copy: error: the raster frame has no \"" + name + "\" channel");
    f.add(name);
  }
  for (const std::string& name : {std::string("hit"), std::string("object_id"), vis}) f.get(name) = raster.get(name);
  f.meta = nlohmann::json::object();
  f.meta["kind"] = "outside";
  f.meta["light"] = light;
  for (const char* key : {"scene_hash", "camera_hash"})
    if (raster.meta.contains(key)) f.meta[key] = raster.meta[key];
  return f;
}

Metrics addBlindAgreement(const Frame& truthAll, const Frame& raster, const DeclaredRenderer& declared,
                          ClassConfusion& out, const CompareOptions& options) {
  Classification full, blind;
  const Metrics m = compareFrames(truthAll, raster, options, &full);
  const std::string light = resolveCompareLight(truthAll, raster, options);
  Frame outside = blindCopy(raster, light);
  CompareOptions blindOptions = options;
  prepareOutsideComparison(truthAll, outside, declared, blindOptions);
  compareFrames(truthAll, outside, blindOptions, &blind);
  for (size_t i = 0; i < full.classes.size(); ++i) {
    const PixelClass f = full.classes[i];
    if (!isErrorClass(f)) continue;
    ++out.counts[classIndex(f)][classIndex(blind.classes[i])];
  }
  return m;
}

}  // namespace shadowlab
