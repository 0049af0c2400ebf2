#pragma once
// The few image operations shadowlab needs, behind one interface with two implementations; the
// build compiles exactly one (CMake option SHADOWLAB_IMAGE_IO, scenes/CMakeLists.txt):
//   image_io_oiio.cpp     OpenImageIO (the default; reads every format OIIO knows), built as a
//                         module the program loads on first use (image_io_module.cpp forwards to
//                         it; SHADOWLAB_IMAGE_IO_MODULE=OFF and the fuzz build link it instead)
//   image_io_exr_png.cpp  OpenEXR + libpng only: a few MB of libraries instead of OIIO's ~390 MB of
//                         dependencies, so the binary and its libraries fit a small bundle
//                         (scripts/device-bundle.sh). Reads .exr and .png only.
// Both give the same results (tests/scenes_image_io_test.cpp writes with one and reads with the
// other, both ways):
//   * EXR: channels are 32-bit float, ZIPS compression (one scanline per block) at zlib level 1,
//     string attributes by name. On reading (any compression, any pixel type), channels come in
//     OpenImageIO's order (R, G, B, A, Z ... first, then the file's order, which EXR sorts by
//     name): callers go by name, never by position.
//   * PNG writes: 8 bits per channel, 3 (RGB) or 4 (RGBA) channels, alpha stored as given
//     (un-associated, as PNG defines it).
//   * Textures: read as floats, 8/16-bit values times 1/255 or 1/65535, no colour transform; a PNG
//     with alpha has its colour multiplied by alpha (associated), as OpenImageIO does by default.
// The default build (SHADOWLAB_IMAGE_IO=oiio with the module, and OpenEXR and libpng found) uses
// both: image_io_module.cpp reads and writes EXR and PNG through image_io_exr_png.cpp, linked into
// the program (a handful of libraries), and loads OpenImageIO's module only for a texture in any
// other format, so that a sweep or a reference never waits ~0.2 s for OpenImageIO's ~260 libraries.
// Internal to shadowlab_scenes (frame.cpp, loader.cpp); no public header names either library.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace shadowlab::image_io {

struct FloatImage {
  int width = 0;
  int height = 0;
  std::vector<std::string> channels;  // names, in the order of `pixels`
  std::vector<float> pixels;          // interleaved: (y * width + x) * channels.size() + c, top row first
  // writeExr only: when not empty, channel c's values are planes[c][y * width + x] (one plane per
  // channel, e.g. a Frame's) and `pixels` is not used: no full interleaved copy is made.
  std::vector<const float*> planes;
  std::map<std::string, std::string> text;  // string attributes (EXR header); empty for other formats
  // readExr only: set before the call, the channels come back one plane each in `planesRead`
  // (planesRead[c][y * width + x], in the order of `channels`) and `pixels` stays empty: no
  // interleaved copy of the whole image (a reference frame's planes are read straight in).
  bool readPlanar = false;
  std::vector<std::vector<float>> planesRead;
};

// Every function returns "" on success, else what went wrong (without the path: callers add it).

// Writes an EXR of float channels (pixels as given, channel names as given), ZIPS level 1, with
// `image.text` as string attributes.
std::string writeExr(const std::string& path, const FloatImage& image);
// Reads an image file's first part with every channel as float (any EXR pixel type); planar
// where image.readPlanar is set.
std::string readExr(const std::string& path, FloatImage& image);
// Writes an 8-bit PNG of `channels` (3 or 4) interleaved values per pixel. `unfiltered`: no
// per-row PNG filter (PNG_FILTER_NONE) instead of libpng's adaptive choice (PngRows, frame.h).
std::string writePng(const std::string& path, int width, int height, int channels, const uint8_t* pixels,
                     bool unfiltered = false);
// Reads a texture (PNG, EXR; OpenImageIO: any format it knows): gray, gray+alpha, RGB or RGBA
// channels as stored (a palette PNG expands to RGB(A)). When a side is outside 1..maxSide only width and height are set
// (pixels stay empty) so the caller can refuse the size before anything large is allocated.
std::string readTexture(const std::string& path, FloatImage& image, int maxSide);
// "oiio", "exr-png", or "exr-png+oiio" (the two side by side, above).
const char* backendName();
// Where the library is a module loaded on first use (image_io_module.cpp): starts loading it on a
// thread of its own, so that a command sure to read or write images soon need not wait for it
// then. Elsewhere nothing to do.
void preload();

#ifdef SHADOWLAB_IMAGE_IO_HYBRID
// image_io_exr_png.cpp's functions where the module is the rest (see the top).
namespace exr_png {
std::string writeExr(const std::string& path, const FloatImage& image);
std::string readExr(const std::string& path, FloatImage& image);
std::string writePng(const std::string& path, int width, int height, int channels, const uint8_t* pixels,
                     bool unfiltered);
std::string readTexture(const std::string& path, FloatImage& image, int maxSide);
bool readsTexture(const std::string& path);  // a name readTexture reads (.png, .exr, any case)
}  // namespace exr_png
#endif

#if defined(SHADOWLAB_IMAGE_IO_HYBRID) || defined(SHADOWLAB_IMAGE_IO_EXR_READERS)
// image_io_exr_png.cpp's two EXR readers, which readExr and readTexture use in turn, for
// tests/scenes_exr_core_test.cpp: readExrCore (OpenEXR's core library; false, `image` untouched,
// for a file it leaves to the other: tiled, deep, several parts, subsampled, a size outside
// 1..maxSide, or one it cannot decode; false with `damage` named for a damaged block the other
// would read without a word: an uncompressed block shorter or longer than its lines) and
// readExrImf (Imf::InputFile: any EXR, every error it finds named).
#ifdef SHADOWLAB_IMAGE_IO_HYBRID
namespace exr_png {
#endif
bool readExrCore(const std::string& path, FloatImage& image, int maxSide, std::string* damage = nullptr);
std::string readExrImf(const std::string& path, FloatImage& image, int maxSide);
#ifdef SHADOWLAB_IMAGE_IO_HYBRID
}  // namespace exr_png
#endif
#endif

}  // namespace shadowlab::image_io
