// image_io.h through OpenEXR and libpng (SHADOWLAB_IMAGE_IO=exr-png): the same results as the
// OpenImageIO implementation (image_io_oiio.cpp) for the files shadowlab reads and writes, with a
// few MB of libraries. Where OpenImageIO has a convention of its own (channel order on reading,
// associated alpha on reading a PNG), it is reproduced here and named.
#include <png.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfThreading.h>
#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <thread>

#include "image_io.h"

// SHADOWLAB_IMAGE_IO=exr-png: image_io.h's functions. Beside the OpenImageIO module (the default
// build, SHADOWLAB_IMAGE_IO_HYBRID): image_io::exr_png's, which image_io_module.cpp calls for EXR
// and PNG files.
#ifdef SHADOWLAB_IMAGE_IO_HYBRID
namespace shadowlab::image_io::exr_png {
#else
namespace shadowlab::image_io {
#endif
namespace {

// OpenImageIO compresses and decompresses EXR lines on all cores; so does this.
void useAllCores() {
  static const bool once = [] {
    Imf::setGlobalThreadCount(int(std::max(1u, std::thread::hardware_concurrency())));
    return true;
  }();
  (void)once;
}

bool iequals(const std::string& a, const char* b) {
  if (a.size() != std::strlen(b)) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  return true;
}

// OpenImageIO's channel order for an EXR part: grouped by layer ("normal.x" is layer "normal."),
// within a layer the named colour, alpha and depth channels first in this order (case-insensitive),
// then the rest in the file's (sorted) order. Checked against OpenImageIO 2.4 by
// tests/scenes_image_io_test.cpp ("R r G B Y A a alpha AR Z depth visibility zz normal.x").
int specialRank(const std::string& suffix) {
  static const char* kSpecial[] = {"R",     "Red", "G",  "Green", "B",  "Blue", "Y",  "real", "imag",  "A",
                                   "Alpha", "AR",  "RA", "AG",    "GA", "AB",   "BA", "Z",    "Depth", "Zback"};
  for (size_t i = 0; i < sizeof kSpecial / sizeof kSpecial[0]; ++i)
    if (iequals(suffix, kSpecial[i])) return int(i);
  return int(sizeof kSpecial / sizeof kSpecial[0]);
}

std::vector<std::string> oiioChannelOrder(std::vector<std::string> names) {
  auto layer = [](const std::string& n) {
    size_t dot = n.rfind('.');
    return dot == std::string::npos ? std::string() : n.substr(0, dot + 1);
  };
  std::stable_sort(names.begin(), names.end(), [&](const std::string& a, const std::string& b) {
    const std::string la = layer(a), lb = layer(b);
    if (la != lb) return la < lb;
    return specialRank(a.substr(la.size())) < specialRank(b.substr(lb.size()));
  });
  return names;
}

std::string readExrFile(const std::string& path, FloatImage& image, int maxSide) {
  useAllCores();
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    const int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
    image.width = width;
    image.height = height;
    image.pixels.clear();
    image.channels.clear();
    image.text.clear();
    if (width <= 0 || height <= 0 || width > maxSide || height > maxSide)
      return maxSide == std::numeric_limits<int>::max() ? "empty image" : "";
    std::vector<std::string> names;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
      if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
        return std::string("channel ") + it.name() + " is subsampled; expected one value per pixel";
      names.push_back(it.name());
    }
    if (names.empty()) return "empty image";
    image.channels = oiioChannelOrder(names);
    const size_t nc = image.channels.size();
    Imf::FrameBuffer fb;
    // A slice's base is the address of pixel (0, 0) of the data window's coordinate system.
    const ptrdiff_t origin = ptrdiff_t(window.min.x) + ptrdiff_t(window.min.y) * width;
    image.planesRead.clear();
    if (image.readPlanar) {
      image.planesRead.resize(nc);
      for (size_t c = 0; c < nc; ++c) {
        image.planesRead[c].resize(size_t(width) * height);
        char* base = reinterpret_cast<char*>(image.planesRead[c].data()) - origin * ptrdiff_t(sizeof(float));
        fb.insert(image.channels[c], Imf::Slice(Imf::FLOAT, base, sizeof(float), size_t(width) * sizeof(float)));
      }
    } else {
      image.pixels.assign(size_t(width) * height * nc, 0.0f);
      char* base = reinterpret_cast<char*>(image.pixels.data()) - origin * ptrdiff_t(nc * sizeof(float));
      for (size_t c = 0; c < nc; ++c)
        fb.insert(image.channels[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), nc * sizeof(float),
                                                size_t(width) * nc * sizeof(float)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(window.min.y, window.max.y);
    for (auto it = header.begin(); it != header.end(); ++it)
      if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
        image.text[it.name()] = s->value();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// libpng reports errors by longjmp; the message is kept here.
struct PngError {
  std::jmp_buf jump;
  std::string message;
};
void onPngError(png_structp png, png_const_charp message) {
  auto* err = static_cast<PngError*>(png_get_error_ptr(png));
  err->message = message;
  std::longjmp(err->jump, 1);
}
void onPngWarning(png_structp, png_const_charp) {}

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// OpenImageIO associates alpha when it reads a PNG (unless asked not to), in the file's integer
// type: colour = colour * alpha / max, truncated; with a gAMA chunk of gamma g != 1 (and no sRGB
// chunk) it scales by (alpha / max)^g instead, in float, truncated back.
template <class T>
void associateAlpha(T* data, size_t pixels, int channels, int alpha, float gamma) {
  const T max = std::numeric_limits<T>::max();
  for (size_t i = 0; i < pixels; ++i, data += channels) {
    if (gamma == 1.0f) {
      for (int c = 0; c < channels; ++c)
        if (c != alpha) data[c] = T((unsigned(data[c]) * unsigned(data[alpha])) / max);
    } else {
      const float a = std::pow(data[alpha] * (1.0f / max), gamma);
      for (int c = 0; c < channels; ++c)
        if (c != alpha) data[c] = static_cast<T>(data[c] * a);
    }
  }
}

std::string readPngFile(const std::string& path, FloatImage& image, int maxSide) {
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) return std::string("cannot open: ") + std::strerror(errno);
  PngError err;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &err, onPngError, onPngWarning);
  if (!png) return "cannot start libpng";
  png_infop info = png_create_info_struct(png);
  std::vector<unsigned char> bytes;
  std::vector<png_bytep> rows;
  if (setjmp(err.jump)) {
    png_destroy_read_struct(&png, &info, nullptr);
    return err.message.empty() ? "not a readable PNG" : err.message;
  }
  png_init_io(png, f.get());
  png_read_info(png, info);
  const int width = int(png_get_image_width(png, info)), height = int(png_get_image_height(png, info));
  image.width = width;
  image.height = height;
  image.pixels.clear();
  image.channels.clear();
  image.text.clear();
  if (width <= 0 || height <= 0 || width > maxSide || height > maxSide) {
    png_destroy_read_struct(&png, &info, nullptr);
    return "";
  }
  // What OpenImageIO's PNG reader does: palettes to RGB, 1/2/4-bit gray to 8 bits, tRNS to an
  // alpha channel, 16-bit values kept (and byte-swapped to the host's order).
  const int colorType = png_get_color_type(png, info);
  const int bitDepth = png_get_bit_depth(png, info);
  if (colorType == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colorType == PNG_COLOR_TYPE_GRAY && bitDepth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (bitDepth == 16) png_set_swap(png);
  float gamma = 1.0f;
  int srgbIntent = 0;
  double fileGamma = 0;
  if (!png_get_sRGB(png, info, &srgbIntent) && png_get_gAMA(png, info, &fileGamma) && fileGamma > 0)
    gamma = std::round(100.0f * float(1.0 / fileGamma)) / 100.0f;
  png_read_update_info(png, info);
  const int channels = png_get_channels(png, info);
  const bool wide = png_get_bit_depth(png, info) == 16;
  // Integers become floats as OpenImageIO converts them: times the reciprocal of the maximum (not
  // divided by it: the two differ in the last bit for some values).
  const size_t rowBytes = png_get_rowbytes(png, info);
  bytes.resize(rowBytes * size_t(height));
  rows.resize(size_t(height));
  for (int y = 0; y < height; ++y) rows[size_t(y)] = bytes.data() + rowBytes * size_t(y);
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);

  const size_t pixels = size_t(width) * size_t(height);
  const int alpha = (channels == 2 || channels == 4) ? channels - 1 : -1;
  if (wide) {
    auto* data = reinterpret_cast<uint16_t*>(bytes.data());
    if (alpha >= 0) associateAlpha(data, pixels, channels, alpha, gamma);
    image.pixels.resize(pixels * size_t(channels));
    for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = data[i] * (1.0f / 65535.0f);
  } else {
    if (alpha >= 0) associateAlpha(bytes.data(), pixels, channels, alpha, gamma);
    image.pixels.resize(pixels * size_t(channels));
    for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = bytes[i] * (1.0f / 255.0f);
  }
  static const char* kNames[4][4] = {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
  for (int c = 0; c < channels; ++c) image.channels.push_back(kNames[channels - 1][c]);
  return "";
}

bool endsWith(const std::string& s, const char* suffix) {
  const size_t n = std::strlen(suffix);
  if (s.size() < n) return false;
  for (size_t i = 0; i < n; ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - n + i])) != suffix[i]) return false;
  return true;
}

}  // namespace

std::string writeExr(const std::string& path, const FloatImage& image) {
  useAllCores();
  try {
    Imf::Header header(image.width, image.height);
    // The same file OpenImageIO writes for "compression" "zips:1": ZIPS (one scanline per block) at
    // zlib level 1 (image_io_oiio.cpp has the measured alternatives).
    header.compression() = Imf::ZIPS_COMPRESSION;
    header.zipCompressionLevel() = 1;
    const size_t nc = image.channels.size();
    Imf::FrameBuffer fb;
    char* base = reinterpret_cast<char*>(const_cast<float*>(image.pixels.data()));
    for (size_t c = 0; c < nc; ++c) {
      header.channels().insert(image.channels[c], Imf::Channel(Imf::FLOAT));
      if (!image.planes.empty()) {  // planar input: each slice reads its plane directly
        char* plane = reinterpret_cast<char*>(const_cast<float*>(image.planes[c]));
        fb.insert(image.channels[c], Imf::Slice(Imf::FLOAT, plane, sizeof(float), size_t(image.width) * sizeof(float)));
        continue;
      }
      fb.insert(image.channels[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), nc * sizeof(float),
                                              size_t(image.width) * nc * sizeof(float)));
    }
    for (const auto& [name, value] : image.text) header.insert(name, Imf::StringAttribute(value));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

std::string readExr(const std::string& path, FloatImage& image) {
  return readExrFile(path, image, std::numeric_limits<int>::max());
}

std::string writePng(const std::string& path, int width, int height, int channels, const uint8_t* pixels,
                     bool unfiltered) {
  if (channels != 3 && channels != 4) return "expected 3 or 4 channels, got " + std::to_string(channels);
  File f(std::fopen(path.c_str(), "wb"));
  if (!f) return std::string("cannot create: ") + std::strerror(errno);
  PngError err;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &err, onPngError, onPngWarning);
  if (!png) return "cannot start libpng";
  png_infop info = png_create_info_struct(png);
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  if (setjmp(err.jump)) {
    png_destroy_write_struct(&png, &info);
    return err.message.empty() ? "cannot write PNG" : err.message;
  }
  png_init_io(png, f.get());
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8,
               channels == 4 ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 6);  // OpenImageIO's default
  if (unfiltered) png_set_filter(png, 0, PNG_FILTER_NONE);
  png_write_info(png, info);
  const size_t stride = size_t(width) * size_t(channels);
  for (int y = 0; y < height; ++y) rows[size_t(y)] = const_cast<png_bytep>(pixels + stride * size_t(y));
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fflush(f.get()) != 0 || std::ferror(f.get())) return std::string("cannot write: ") + std::strerror(errno);
  return "";
}

std::string readTexture(const std::string& path, FloatImage& image, int maxSide) {
  if (endsWith(path, ".png")) return readPngFile(path, image, maxSide);
  if (endsWith(path, ".exr")) return readExrFile(path, image, maxSide);
  return "this build (SHADOWLAB_IMAGE_IO=exr-png) reads .png and .exr images only";
}

#ifdef SHADOWLAB_IMAGE_IO_HYBRID
bool readsTexture(const std::string& path) { return endsWith(path, ".png") || endsWith(path, ".exr"); }
#endif

#ifndef SHADOWLAB_IMAGE_IO_HYBRID
const char* backendName() { return "exr-png"; }

void preload() {}  // linked: loaded with the program
#endif

}  // namespace
