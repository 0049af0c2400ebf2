// Outside frames (outside_frame.h): the image reader and the Frame built from it. The renderer
// JSON's parser is declared_renderer.cpp, the evidence filled in before compare outside_evidence.cpp.
#include "shadowlab/compare/outside_frame.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/number_text.h"

namespace shadowlab {
namespace {

namespace fs = std::filesystem;

bool endsWithNoCase(const std::string& s, const char* suffix) {
  const size_t n = std::strlen(suffix);
  if (s.size() < n) return false;
  for (size_t i = 0; i < n; ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - n + i])) != suffix[i]) return false;
  return true;
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

struct PngFailure {
  std::jmp_buf jump;
  std::string message;
};

void onPngError(png_structp png, png_const_charp message) {
  auto* failure = static_cast<PngFailure*>(png_get_error_ptr(png));
  failure->message = message ? message : "";
  std::longjmp(failure->jump, 1);
}
void onPngWarning(png_structp, png_const_charp) {}

std::string channelList(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// The decoded PNG: every channel, interleaved, as code / (2^bits - 1).
struct PngPixels {
  int width = 0, height = 0, bits = 8;
  std::vector<std::string> channels;
  std::vector<float> pixels;
};

// libpng's classic interface, so that nothing is converted behind our back: no gamma, no sRGB
// decoding, no alpha association (a renderer's visibility is a number, not a colour).
PngPixels readPng(const std::string& path, const std::function<void(int, int)>& checkSize) {
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw InputError(formatError(path, "", std::string("cannot open file: ") + std::strerror(errno)));
  PngFailure failure;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &failure, onPngError, onPngWarning);
  if (!png) throw DriverError(path + ": error: cannot start libpng");
  png_infop info = png_create_info_struct(png);
  // Declared before setjmp: what longjmp unwinds past must be valid (no destructor runs there).
  PngPixels out;
  std::vector<unsigned char> bytes;
  std::vector<png_bytep> rows;
  if (setjmp(failure.jump)) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw InputError(
        formatError(path, "", "cannot read PNG: " + (failure.message.empty() ? "not a PNG" : failure.message)));
  }
  png_init_io(png, file.get());
  png_read_info(png, info);
  const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
  if (width < 1 || height < 1 || width > png_uint_32(kMaxOutsideImageSide) ||
      height > png_uint_32(kMaxOutsideImageSide)) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw InputError(formatError(path, "",
                                 "image is " + std::to_string(width) + "x" + std::to_string(height) +
                                     "; expected sides of 1.." + std::to_string(kMaxOutsideImageSide) + " pixels"));
  }
  if (checkSize) {
    try {
      checkSize(int(width), int(height));
    } catch (...) {
      png_destroy_read_struct(&png, &info, nullptr);
      throw;
    }
  }
  const int colorType = png_get_color_type(png, info);
  const int bitDepth = png_get_bit_depth(png, info);
  if (colorType == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colorType == PNG_COLOR_TYPE_GRAY && bitDepth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (bitDepth == 16) png_set_swap(png);  // the host's byte order (x86: little-endian)
  png_read_update_info(png, info);
  const int channels = png_get_channels(png, info);
  const bool wide = png_get_bit_depth(png, info) == 16;
  const size_t rowBytes = png_get_rowbytes(png, info);
  bytes.resize(rowBytes * size_t(height));
  rows.resize(size_t(height));
  for (png_uint_32 y = 0; y < height; ++y) rows[y] = bytes.data() + rowBytes * y;
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);

  out.width = int(width);
  out.height = int(height);
  out.bits = wide ? 16 : 8;
  static const char* kNames[4][4] = {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
  for (int c = 0; c < channels; ++c) out.channels.push_back(kNames[channels - 1][c]);
  const size_t values = size_t(width) * size_t(height) * size_t(channels);
  out.pixels.resize(values);
  if (wide) {
    for (size_t i = 0; i < values; ++i) {
      uint16_t v;
      std::memcpy(&v, bytes.data() + 2 * i, 2);
      out.pixels[i] = float(v) / 65535.0f;
    }
  } else {
    for (size_t i = 0; i < values; ++i) out.pixels[i] = float(bytes[i]) / 255.0f;
  }
  return out;
}

ImagePlane pngPlane(const std::string& path, const std::string& wanted,
                    const std::function<void(int, int)>& checkSize) {
  const PngPixels png = readPng(path, checkSize);
  const size_t n = png.channels.size();
  const std::string kind = std::string(n >= 3 ? (n == 4 ? "RGBA" : "RGB") : (n == 2 ? "grey+alpha" : "grey"));
  ImagePlane plane;
  plane.width = png.width;
  plane.height = png.height;
  plane.description = std::to_string(png.bits) + "-bit " + kind + " PNG";
  std::string channel = wanted;
  if (channel.empty()) {
    channel = png.channels[0];
    if (n >= 3) {
      // A grey picture stored as colour (a canvas's RGBA readback) needs no channel named.
      for (size_t i = 0; i < png.pixels.size(); i += n) {
        if (png.pixels[i] != png.pixels[i + 1] || png.pixels[i] != png.pixels[i + 2]) {
          throw InputError(formatError(path, "",
                                       "the " + plane.description +
                                           " has colour (R, G and B differ); expected its visibility in one "
                                           "channel: name it with --channel R|G|B" +
                                           (n == 4 ? "|A" : "")));
        }
      }
    }
  }
  const auto it = std::find(png.channels.begin(), png.channels.end(), channel);
  if (it == png.channels.end()) {
    throw InputError(
        formatError(path, "channel " + channel,
                    "a " + plane.description + " has no such channel; expected one of " + channelList(png.channels)));
  }
  const size_t c = size_t(it - png.channels.begin());
  plane.channel = channel;
  plane.values.resize(size_t(png.width) * size_t(png.height));
  for (size_t i = 0; i < plane.values.size(); ++i) plane.values[i] = png.pixels[i * n + c];
  return plane;
}

ImagePlane exrPlane(const std::string& path, const std::string& wanted,
                    const std::function<void(int, int)>& checkSize) {
  const Frame image = readFrameExr(path);
  if (image.width < 1 || image.height < 1 || image.width > kMaxOutsideImageSide ||
      image.height > kMaxOutsideImageSide) {
    throw InputError(formatError(path, "",
                                 "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                     "; expected sides of 1.." + std::to_string(kMaxOutsideImageSide) + " pixels"));
  }
  if (checkSize) checkSize(image.width, image.height);
  std::string channel = wanted;
  if (channel.empty()) {
    if (image.has("vis")) {
      channel = "vis";
    } else if (image.names.size() == 1) {
      channel = image.names[0];
    } else {
      throw InputError(formatError(path, "",
                                   "the EXR has " + std::to_string(image.names.size()) +
                                       " channels and none named \"vis\"; expected the visibility channel named "
                                       "with --channel NAME"));
    }
  }
  if (!image.has(channel)) {
    // The file's own channel names are not repeated: they are the file's content.
    throw InputError(formatError(path, "channel " + channel,
                                 "the EXR has no such channel (it has " + std::to_string(image.names.size()) +
                                     "); expected the name of its visibility channel"));
  }
  ImagePlane plane;
  plane.width = image.width;
  plane.height = image.height;
  plane.channel = channel;
  plane.description = "EXR";
  plane.values = image.get(channel);
  return plane;
}

// "FILE: CHANNEL pixel (x, y): error: got V; expected WHAT (first of N such pixels)", frame_check's
// form, for the first value `bad` holds.
template <typename Bad>
void checkPlane(const ImagePlane& plane, const std::string& file, const char* expected, Bad bad) {
  size_t first = plane.values.size(), count = 0;
  for (size_t i = 0; i < plane.values.size(); ++i) {
    if (bad(plane.values[i]) && count++ == 0) first = i;
  }
  if (count == 0) return;
  const int x = int(first % size_t(plane.width)), y = int(first / size_t(plane.width));
  throw InputError(
      formatError(file, "channel " + plane.channel + " pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")",
                  "got " + numberText(plane.values[first]) + "; expected " + expected + " (first of " +
                      std::to_string(count) + (count == 1 ? " such pixel)" : " such pixels)")));
}

std::string metaText(const Frame& f, const char* key) {
  auto it = f.meta.find(key);
  return it != f.meta.end() && it->is_string() ? it->get<std::string>() : std::string();
}

}  // namespace

ImagePlane readImagePlane(const std::string& path, const std::string& channel,
                          const std::function<void(int, int)>& checkSize) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(formatError(path, "", "cannot open file: no such file"));
  ImagePlane plane;
  if (endsWithNoCase(path, ".png")) {
    plane = pngPlane(path, channel, checkSize);
  } else if (endsWithNoCase(path, ".exr")) {
    plane = exrPlane(path, channel, checkSize);
    checkPlane(plane, path, "a finite number", [](float v) { return !std::isfinite(v); });
  } else {
    throw InputError(formatError(path, "", "unknown image type; expected a .png or .exr file"));
  }
  return plane;
}

void writeGreyPng16(const std::string& path, int width, int height, const std::vector<float>& values) {
  if (width < 1 || height < 1 || values.size() != size_t(width) * size_t(height))
    throw InputError(formatError(path, "", "nothing to write: the plane is not width x height"));
  std::vector<png_byte> rowsBytes(values.size() * 2);
  for (size_t i = 0; i < values.size(); ++i) {
    const float v = std::clamp(values[i], 0.0f, 1.0f);  // NaN: the clamp keeps it; the cast below
    const uint16_t code = std::isnan(v) ? 0 : uint16_t(std::lround(double(v) * 65535.0));
    rowsBytes[2 * i] = png_byte(code >> 8);  // PNG's 16-bit samples are big-endian
    rowsBytes[2 * i + 1] = png_byte(code & 0xff);
  }
  const std::string temporary = path + ".tmp-png";
  {
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(temporary.c_str(), "wb"));
    if (!file) throw InputError(formatError(path, "", std::string("cannot write file: ") + std::strerror(errno)));
    PngFailure failure;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &failure, onPngError, onPngWarning);
    if (!png) throw DriverError(path + ": error: cannot start libpng");
    png_infop info = png_create_info_struct(png);
    std::vector<png_bytep> rows(static_cast<size_t>(height));
    for (int y = 0; y < height; ++y) rows[size_t(y)] = rowsBytes.data() + size_t(y) * size_t(width) * 2;
    if (setjmp(failure.jump)) {
      png_destroy_write_struct(&png, &info);
      file.reset();
      std::remove(temporary.c_str());
      throw InputError(formatError(path, "", "cannot write PNG: " + failure.message));
    }
    png_init_io(png, file.get());
    png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 16, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
  }
  std::error_code ec;
  fs::rename(temporary, path, ec);
  if (ec) {
    fs::remove(temporary, ec);
    throw InputError(formatError(path, "", "cannot write file: " + ec.message()));
  }
}

bool isOutsideFrameFile(const std::string& path) {
  if (endsWithNoCase(path, ".png")) return true;
  std::error_code ec;
  if (!endsWithNoCase(path, ".exr") || !fs::is_regular_file(path, ec)) return false;
  const Frame frame = readFrameExr(path);
  return frame.meta.empty() || !frame.meta.contains("kind");
}

Frame makeOutsideFrame(const Frame& truth, const std::string& light, const ImagePlane& vis, const std::string& visFile,
                       const ImagePlane* coverage, const std::string& coverageFile, const CoverageRule& rule,
                       const DeclaredRenderer& declared) {
  if (vis.width != truth.width || vis.height != truth.height ||
      (coverage && (coverage->width != truth.width || coverage->height != truth.height))) {
    throw InputError(formatError(visFile, "",
                                 "the image is not the camera's size; expected " + std::to_string(truth.width) + "x" +
                                     std::to_string(truth.height)));
  }
  checkPlane(vis, visFile, "a number in [0, 1] (1 = lit)", [](float v) { return !(v >= 0.0f && v <= 1.0f); });
  if (coverage) {
    if (rule.far) {
      checkPlane(*coverage, coverageFile, "a finite depth", [](float v) { return !std::isfinite(v); });
    } else {
      checkPlane(*coverage, coverageFile, "a coverage in [0, 1]", [](float v) { return !(v >= 0.0f && v <= 1.0f); });
    }
  }
  Frame frame;
  frame.width = truth.width;
  frame.height = truth.height;
  const std::vector<float>& truthHit = truth.get("hit");
  const std::vector<float>& truthId = truth.get("object_id");
  frame.add("hit");
  frame.add("object_id");
  frame.add("light." + light + ".vis");  // add() moves the planes: take them after the last one
  std::vector<float>& hit = frame.get("hit");
  std::vector<float>& id = frame.get("object_id");
  std::vector<float>& value = frame.get("light." + light + ".vis");
  for (size_t i = 0; i < frame.pixelCount(); ++i) {
    bool surface = truthHit[i] >= 0.5f;
    if (coverage) {
      const float c = coverage->values[i];
      surface = rule.far ? c != *rule.far : c > 0.5f;
    }
    hit[i] = surface ? 1.0f : 0.0f;
    // Ids: the truth's where both see a surface; 0 where the outside frame sees none (frame.h),
    // and 0 where only it sees one, so that the pixel counts as a geometry mismatch either way.
    id[i] = surface && truthHit[i] >= 0.5f ? truthId[i] : 0.0f;
    value[i] = surface ? vis.values[i] : 0.0f;
  }
  frame.meta = nlohmann::json::object();
  frame.meta["kind"] = "outside";
  frame.meta["renderer"] = declared.name;
  frame.meta["light"] = light;
  frame.meta["coverage"] = coverage ? "given" : "assumed";
  for (const char* key : {"scene", "scene_hash", "camera_hash"})
    if (!metaText(truth, key).empty()) frame.meta[key] = metaText(truth, key);
  if (truth.meta.contains("lights")) frame.meta["lights"] = truth.meta["lights"];
  frame.meta["width"] = frame.width;
  frame.meta["height"] = frame.height;
  return frame;
}

}  // namespace shadowlab
