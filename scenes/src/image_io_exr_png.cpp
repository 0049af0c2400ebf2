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
#include <OpenEXR/openexr.h>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <map>
#include <memory>
#include <system_error>
#include <thread>
#include <vector>

#define SHADOWLAB_IMAGE_IO_EXR_READERS 1  // image_io.h declares readExrCore and readExrImf
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

}  // namespace

// A single-part scanline EXR whose channels all have one value per pixel, read through OpenEXR's
// core (C) library: its unpackers copy each block's values into the planes (or the interleaved
// buffer) directly. Imf::InputFile (OpenEXR 3.1) converts every value of a ZIP or uncompressed block
// through Xdr::read, one at a time: a 1080p reference cache entry took ~105 ms of wall time, this
// ~30-45 ms (compare/SWEEPS.md, "The reference cache"). The values are the same bits: the same
// decompressors, and FLOAT to float is a copy (HALF and UINT convert as Imf does; checked against
// OpenImageIO by tests/scenes_image_io_test.cpp). Returns false, with `image` untouched, for
// anything else (tiled, deep, several parts, subsampled channels, a size outside 1..maxSide, a
// file the core library does not open or decode): readExrFile then reads it with readExrImf,
// which says what is wrong where something is.
namespace {

bool readExrCoreUnguarded(const std::string& path, FloatImage& image, int maxSide, std::string* damage) {
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = [](exr_const_context_t, exr_result_t, const char*) {};  // Imf reports instead
  // A header Imf would read another way (e.g. a float attribute declaring 2 bytes: Imf reads 4, a
  // lenient core parse 2, and the names after it differ) is refused here and left to Imf.
  init.flags |= EXR_CONTEXT_FLAG_STRICT_HEADER;
  exr_context_t ctxt = nullptr;
  if (exr_start_read(&ctxt, path.c_str(), &init) != EXR_ERR_SUCCESS) {
    if (ctxt) exr_finish(&ctxt);
    return false;
  }
  struct Finish {
    exr_context_t& c;
    ~Finish() { exr_finish(&c); }
  } finish{ctxt};
  int parts = 0;
  exr_storage_t storage = EXR_STORAGE_LAST_TYPE;
  exr_compression_t compression = EXR_COMPRESSION_LAST_TYPE;
  exr_attr_box2i_t window{};
  int32_t linesPerChunk = 0;
  const exr_attr_chlist_t* list = nullptr;
  if (exr_get_count(ctxt, &parts) != EXR_ERR_SUCCESS || parts != 1 ||
      exr_get_storage(ctxt, 0, &storage) != EXR_ERR_SUCCESS || storage != EXR_STORAGE_SCANLINE ||
      exr_get_data_window(ctxt, 0, &window) != EXR_ERR_SUCCESS ||
      exr_get_scanlines_per_chunk(ctxt, 0, &linesPerChunk) != EXR_ERR_SUCCESS || linesPerChunk <= 0 ||
      exr_get_compression(ctxt, 0, &compression) != EXR_ERR_SUCCESS ||
      exr_get_channels(ctxt, 0, &list) != EXR_ERR_SUCCESS || !list || list->num_channels <= 0)
    return false;
  const int64_t w64 = int64_t(window.max.x) - window.min.x + 1, h64 = int64_t(window.max.y) - window.min.y + 1;
  if (w64 <= 0 || h64 <= 0 || w64 > maxSide || h64 > maxSide || w64 > INT32_MAX || h64 > INT32_MAX) return false;
  const int width = int(w64), height = int(h64);
  std::vector<std::string> names;
  for (int c = 0; c < list->num_channels; ++c) {
    const exr_attr_chlist_entry_t& e = list->entries[c];
    if (e.x_sampling != 1 || e.y_sampling != 1 || !e.name.str) return false;
    names.emplace_back(e.name.str, size_t(e.name.length));
  }
  const int chunks = int((int64_t(height) + linesPerChunk - 1) / linesPerChunk);
  // An uncompressed block must hold its lines' bytes exactly. OpenEXR 3.1 decodes a shorter one
  // without an error, from beyond its buffer (values that change from run to run), and Imf 3.1
  // reads one too: the file is damaged, and the first such block is named. Checked before anything
  // is allocated or decoded, in file order, so that the message does not depend on the threads.
  if (compression == EXR_COMPRESSION_NONE)
    for (int k = 0; k < chunks; ++k) {
      exr_chunk_info_t chunk;
      if (exr_read_scanline_chunk_info(ctxt, 0, window.min.y + k * linesPerChunk, &chunk) != EXR_ERR_SUCCESS)
        return false;
      if (chunk.packed_size != chunk.unpacked_size) {
        if (damage)
          *damage = "damaged: the uncompressed block of line " + std::to_string(chunk.start_y) + " holds " +
                    std::to_string(chunk.packed_size) + " bytes, its lines " + std::to_string(chunk.unpacked_size);
        return false;
      }
    }
  std::vector<std::string> order = oiioChannelOrder(names);
  const size_t nc = names.size(), n = size_t(width) * size_t(height);
  std::vector<size_t> target(nc);  // file channel -> index in `order`
  for (size_t c = 0; c < nc; ++c) target[c] = size_t(std::find(order.begin(), order.end(), names[c]) - order.begin());
  std::vector<std::vector<float>> planes;
  std::vector<float> pixels;
  if (image.readPlanar)
    planes.assign(nc, std::vector<float>(n));
  else
    pixels.assign(n * nc, 0.0f);

  // The blocks in turn on every core, each thread with its own decode pipeline; each block fills
  // its own rows, so the result does not depend on the threads.
  std::atomic<bool> failed{false};
  std::atomic<int> next{0};
  auto decode = [&] {
    exr_decode_pipeline_t pipeline{};  // EXR_DECODE_PIPELINE_INITIALIZER: all zero
    bool started = false;
    for (int k = next++; k < chunks && !failed.load(std::memory_order_relaxed); k = next++) {
      exr_chunk_info_t chunk;
      if (exr_read_scanline_chunk_info(ctxt, 0, window.min.y + k * linesPerChunk, &chunk) != EXR_ERR_SUCCESS ||
          (started ? exr_decoding_update(ctxt, 0, &chunk, &pipeline)
                   : exr_decoding_initialize(ctxt, 0, &chunk, &pipeline)) != EXR_ERR_SUCCESS ||
          pipeline.channel_count != int16_t(nc) || chunk.start_y < window.min.y ||
          int64_t(chunk.start_y) + chunk.height > int64_t(window.max.y) + 1) {
        failed = true;
        break;
      }
      const size_t row = size_t(chunk.start_y - window.min.y);
      for (int c = 0; c < pipeline.channel_count; ++c) {
        exr_coding_channel_info_t& ch = pipeline.channels[c];
        const size_t t = target[size_t(c)];
        if (image.readPlanar) {
          ch.decode_to_ptr = reinterpret_cast<uint8_t*>(planes[t].data() + row * size_t(width));
          ch.user_pixel_stride = int32_t(sizeof(float));
        } else {
          ch.decode_to_ptr = reinterpret_cast<uint8_t*>(pixels.data() + row * size_t(width) * nc + t);
          ch.user_pixel_stride = int32_t(nc * sizeof(float));
        }
        ch.user_line_stride = int32_t(size_t(width) * size_t(ch.user_pixel_stride));
        ch.user_data_type = EXR_PIXEL_FLOAT;
        ch.user_bytes_per_element = int8_t(sizeof(float));
      }
      if (!started && exr_decoding_choose_default_routines(ctxt, 0, &pipeline) != EXR_ERR_SUCCESS) {
        failed = true;
        break;
      }
      started = true;
      if (exr_decoding_run(ctxt, 0, &pipeline) != EXR_ERR_SUCCESS) {
        failed = true;
        break;
      }
    }
    exr_decoding_destroy(ctxt, &pipeline);
  };
  const int threads = std::clamp(int(std::thread::hardware_concurrency()), 1, std::max(1, chunks));
  std::vector<std::thread> helpers;
  try {
    for (int t = 1; t < threads; ++t) helpers.emplace_back(decode);
  } catch (const std::system_error&) {  // no thread to be had: fewer helpers, the same blocks
  }
  decode();
  for (std::thread& t : helpers) t.join();
  if (failed) return false;

  std::map<std::string, std::string> text;
  int32_t attributes = 0;
  if (exr_get_attribute_count(ctxt, 0, &attributes) != EXR_ERR_SUCCESS) return false;
  for (int32_t i = 0; i < attributes; ++i) {
    const exr_attribute_t* a = nullptr;
    if (exr_get_attribute_by_index(ctxt, 0, EXR_ATTR_LIST_FILE_ORDER, i, &a) != EXR_ERR_SUCCESS || !a) return false;
    if (a->type == EXR_ATTR_STRING && a->name && a->string)
      text[a->name] = a->string->str ? std::string(a->string->str, size_t(std::max(0, a->string->length))) : "";
  }
  image.width = width;
  image.height = height;
  image.channels = std::move(order);
  image.pixels = std::move(pixels);
  image.planesRead = std::move(planes);
  image.text = std::move(text);
  return true;
}

}  // namespace

bool readExrCore(const std::string& path, FloatImage& image, int maxSide, std::string* damage) {
  try {
    return readExrCoreUnguarded(path, image, maxSide, damage);
  } catch (const std::exception&) {  // e.g. no memory for a size a damaged header claims
    return false;                     // readExrImf says so
  }
}

std::string readExrImf(const std::string& path, FloatImage& image, int maxSide) {
  useAllCores();
  image.planesRead.clear();
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

namespace {

// Every EXR read: the core library's reader where it takes the file, Imf::InputFile's otherwise.
std::string readExrFile(const std::string& path, FloatImage& image, int maxSide) {
  std::string damage;
  if (readExrCore(path, image, maxSide, &damage)) return "";
  if (!damage.empty()) return damage;  // a damaged block Imf would read anyway
  return readExrImf(path, image, maxSide);
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
