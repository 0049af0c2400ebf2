// errors.png and triptych.png. The legend is drawn with a tiny built-in 5x7 bitmap font:
// OpenImageIO's render_text needs a system font by name (it fails with "Could not set default
// font face" when none is given), and a built-in font keeps the pictures byte-identical on
// every machine.
#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <string>

#include "shadowlab/compare/classify.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {
namespace {

// 5x7 glyphs, one row per byte, bit 4 = leftmost column.
struct Glyph {
  char c;
  std::array<uint8_t, 7> rows;
};
constexpr Glyph kFont[] = {
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}}, {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}}, {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}}, {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}}, {'|', {0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
};
constexpr int kGlyphW = 5, kGlyphH = 7, kAdvance = 6;

const Glyph* findGlyph(char c) {
  c = char(std::toupper(static_cast<unsigned char>(c)));
  for (const auto& g : kFont)
    if (g.c == c) return &g;
  return nullptr;  // space and anything unknown: blank
}

struct Canvas {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  Canvas(int w, int h, const uint8_t fill[3]) : width(w), height(h), rgb(size_t(w) * h * 3) {
    for (size_t i = 0; i < size_t(w) * h; ++i) std::copy(fill, fill + 3, rgb.begin() + i * 3);
  }
  void fillRect(int x0, int y0, int w, int h, const uint8_t c[3]) {
    for (int y = std::max(0, y0); y < std::min(height, y0 + h); ++y)
      for (int x = std::max(0, x0); x < std::min(width, x0 + w); ++x)
        std::copy(c, c + 3, &rgb[(size_t(y) * width + x) * 3]);
  }
  // Draws text with its top-left at (x, y), each font pixel scale x scale. Clipped at the edges.
  void text(int x, int y, const std::string& s, int scale, const uint8_t c[3]) {
    for (char ch : s) {
      if (const Glyph* g = findGlyph(ch)) {
        for (int r = 0; r < kGlyphH; ++r)
          for (int col = 0; col < kGlyphW; ++col)
            if (g->rows[size_t(r)] & (0x10 >> col)) fillRect(x + col * scale, y + r * scale, scale, scale, c);
      }
      x += kAdvance * scale;
    }
  }
  void blit(const std::vector<uint8_t>& src, int w, int h, int x0, int y0) {
    for (int y = 0; y < h; ++y) {
      if (y0 + y < 0 || y0 + y >= height) continue;
      for (int x = 0; x < w; ++x) {
        if (x0 + x < 0 || x0 + x >= width) continue;
        std::copy(&src[(size_t(y) * w + x) * 3], &src[(size_t(y) * w + x) * 3] + 3,
                  &rgb[(size_t(y0 + y) * width + x0 + x) * 3]);
      }
    }
  }
};

constexpr uint8_t kLegendBackground[3] = {12, 12, 12};
constexpr uint8_t kText[3] = {235, 235, 235};

// Font scale so the legend stays readable on large frames and fits on small ones.
int fontScale(int width) { return std::clamp(width / 480, 1, 4); }

struct LegendEntry {
  PixelClass cls;
  bool lit;
  std::string label;
};

std::string percent(uint64_t count, uint64_t total) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f%%", total ? 100.0 * double(count) / double(total) : 0.0);
  return buf;
}

}  // namespace

void classColor(PixelClass c, bool referenceLit, uint8_t rgb[3]) {
  if (size_t(c) >= kPixelClassCount) {  // not a class code: black, so it stands out
    rgb[0] = rgb[1] = rgb[2] = 0;
    return;
  }
  const PixelClassInfo& info = classInfo(c);
  const uint32_t v = referenceLit ? info.rgbLit : info.rgbShadowed;
  rgb[0] = uint8_t(v >> 16);
  rgb[1] = uint8_t(v >> 8);
  rgb[2] = uint8_t(v);
}

namespace {

// 1 where `hit` or `object_id` differs from the right or lower neighbour: silhouettes and the
// seams between objects. Empty when the frame lacks the channels or has another size.
std::vector<uint8_t> silhouettes(const Frame* f, int w, int h) {
  if (!f || f->width != w || f->height != h || !f->has("hit") || !f->has("object_id")) return {};
  const auto& hit = f->get("hit");
  const auto& id = f->get("object_id");
  std::vector<uint8_t> edge(size_t(w) * h, 0);
  auto key = [&](size_t i) { return hit[i] >= 0.5f ? id[i] : -1.0f; };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const float k = key(i);
      if (x + 1 < w && key(i + 1) != k) edge[i] = edge[i + 1] = 1;
      if (y + 1 < h && key(i + w) != k) edge[i] = edge[i + w] = 1;
    }
  }
  return edge;
}

void darken(uint8_t* p) {
  for (int k = 0; k < 3; ++k) p[k] = uint8_t(p[k] * 3 / 5);
}

void checkClassification(const Classification& c) {
  if (c.width <= 0 || c.height <= 0 || c.classes.size() != size_t(c.width) * c.height) {
    throw InputError("errors picture: error: classification is " + std::to_string(c.width) + "x" +
                     std::to_string(c.height) + " with " + std::to_string(c.classes.size()) +
                     " pixels; expected a non-empty frame");
  }
}

// errorsPicture with the outlines' silhouettes given (empty: none), so that the triptych finds
// the reference's once for two panels.
std::vector<uint8_t> drawErrors(const Classification& c, int* outWidth, int* outHeight,
                                const std::vector<uint8_t>& edge) {
  checkClassification(c);
  const int w = c.width, h = c.height;
  const PerPixelClass<uint64_t> counts = countClasses(c.classes);
  Metrics shares;  // pixels_compared and the rates the legend prints
  setClassMetrics(shares, counts);
  // The table's rows in its order: an error class with its count and share of the compared
  // pixels, another counted class (geometry mismatch) with its count, a class whose colour shows
  // the reference's decision (correct) once per decision, a class without a label not at all.
  std::vector<LegendEntry> entries;
  for (const PixelClassInfo& k : kPixelClasses) {
    const std::string label = k.label;
    if (label.empty()) continue;
    const uint64_t n = counts[classIndex(k.cls)];
    if (k.error) {
      entries.push_back({k.cls, false, label + " " + std::to_string(n) + " " + percent(n, shares.pixelsCompared)});
    } else if (k.countMetric) {
      entries.push_back({k.cls, false, label + " " + std::to_string(n)});
    } else if (k.rgbLit != k.rgbShadowed) {
      entries.push_back({k.cls, true, label + " lit"});
      entries.push_back({k.cls, false, label + " shadowed"});
    } else {
      entries.push_back({k.cls, false, label});
    }
  }

  // Lay the legend out in rows below the image, wrapping at the image width.
  const int s = fontScale(w);
  const int pad = 3 * s, swatch = kGlyphH * s, lineH = swatch + pad;
  std::vector<std::pair<int, int>> pos;  // top-left of each entry within the legend strip
  int x = pad, y = pad;
  for (const auto& e : entries) {
    const int entryW = swatch + 2 * s + int(e.label.size()) * kAdvance * s;
    if (x > pad && x + entryW > w - pad) {
      x = pad;
      y += lineH;
    }
    pos.emplace_back(x, y);
    x += entryW + 4 * pad;
  }
  const int legendH = y + lineH;

  Canvas canvas(w, h + legendH, kLegendBackground);
  for (int py = 0; py < h; ++py) {
    for (int px = 0; px < w; ++px) {
      const size_t i = size_t(py) * w + px;
      const bool lit = c.referenceLit.size() == c.classes.size() && c.referenceLit[i];
      classColor(c.classes[i], lit, &canvas.rgb[i * 3]);
    }
  }
  // Outlines only over correct and background pixels: an error pixel keeps its class color.
  for (size_t i = 0; i < edge.size(); ++i) {
    if (edge[i] && (c.classes[i] == PixelClass::Correct || c.classes[i] == PixelClass::NotCompared)) {
      darken(&canvas.rgb[i * 3]);
    }
  }
  for (size_t k = 0; k < entries.size(); ++k) {
    uint8_t col[3];
    classColor(entries[k].cls, entries[k].lit, col);
    const int ex = pos[k].first, ey = h + pos[k].second;
    canvas.fillRect(ex, ey, swatch, swatch, col);
    canvas.text(ex + swatch + 2 * s, ey, entries[k].label, s, kText);
  }
  *outWidth = canvas.width;
  *outHeight = canvas.height;
  return std::move(canvas.rgb);
}

}  // namespace

std::vector<uint8_t> errorsPicture(const Classification& c, int* outWidth, int* outHeight, const Frame* outlines) {
  return drawErrors(c, outWidth, outHeight, silhouettes(outlines, c.width, c.height));
}

void writeErrorsPng(const std::string& path, const Classification& c, const Frame* outlines) {
  int w = 0, h = 0;
  std::vector<uint8_t> rgb = errorsPicture(c, &w, &h, outlines);
  writeRgbPng(path, w, h, rgb, PngRows::Unfiltered);
}

namespace {

// Grey shading from visibility only (compare sees frames, not the scene): lit surfaces light grey,
// shadowed ones dark grey, background dark blue; each object slightly tinted and outlined so
// that a lit object in front of a lit ground stays visible. `edge`: silhouettes(&f, ...).
std::vector<uint8_t> visibilityPicture(const Frame& f, const std::string& light, const std::vector<uint8_t>& edge) {
  const float* id = f.has("object_id") ? f.get("object_id").data() : nullptr;
  std::vector<uint8_t> rgb(f.pixelCount() * 3);
  const std::string visName = "light." + light + ".vis";
  const float* hit = f.has("hit") ? f.get("hit").data() : nullptr;
  const float* vis = f.has(visName) ? f.get(visName).data() : nullptr;
  for (size_t i = 0; i < f.pixelCount(); ++i) {
    uint8_t* p = &rgb[i * 3];
    if (!hit || !(hit[i] >= 0.5f)) {
      classColor(PixelClass::NotCompared, false, p);
      continue;
    }
    float v = vis ? vis[i] : 1.0f;
    v = v >= 0.0f ? std::min(v, 1.0f) : 0.0f;
    const float g = 60.0f + 170.0f * v;
    const uint32_t tint = id ? uint32_t(id[i]) * 2654435761u : 0u;  // a fixed hash per object id
    for (int k = 0; k < 3; ++k) p[k] = uint8_t(g * (0.82f + 0.18f * float((tint >> (8 * k + 5)) & 7) / 7.0f) + 0.5f);
    if (!edge.empty() && edge[i]) darken(p);
  }
  return rgb;
}

}  // namespace

void writeTriptychPng(const std::string& path, const Frame& reference, const Frame& raster, const Classification& c) {
  const int w = c.width, h = c.height;
  if (reference.width != w || reference.height != h || raster.width != w || raster.height != h) {
    throw InputError(path + ": error: triptych of frames with different sizes (" + std::to_string(reference.width) +
                     "x" + std::to_string(reference.height) + ", " + std::to_string(raster.width) + "x" +
                     std::to_string(raster.height) + ", classification " + std::to_string(w) + "x" + std::to_string(h) +
                     "); expected one size");
  }
  CompareOptions none;
  std::string light;
  try {
    light = resolveCompareLight(reference, raster, none);
  } catch (const InputError&) {
    light.clear();  // no light: both panels show geometry only
  }
  int ew = 0, eh = 0;
  const std::vector<uint8_t> referenceEdge = silhouettes(&reference, w, h);  // the errors panel's outlines too
  const std::vector<uint8_t> errors = drawErrors(c, &ew, &eh, referenceEdge);
  const int s = fontScale(w);
  const int gap = 4 * s, header = kGlyphH * s + 4 * s;
  Canvas canvas(3 * w + 2 * gap, header + std::max(h, eh), kLegendBackground);
  canvas.blit(visibilityPicture(reference, light, referenceEdge), w, h, 0, header);
  canvas.blit(visibilityPicture(raster, light, silhouettes(&raster, w, h)), w, h, w + gap, header);
  canvas.blit(errors, ew, eh, 2 * (w + gap), header);
  const std::string titles[3] = {"reference", "raster", "errors"};
  for (int k = 0; k < 3; ++k) canvas.text(k * (w + gap) + 2 * s, 2 * s, titles[k], s, kText);
  writeRgbPng(path, canvas.width, canvas.height, canvas.rgb, PngRows::Unfiltered);
}

}  // namespace shadowlab
