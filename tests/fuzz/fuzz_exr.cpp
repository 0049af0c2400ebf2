// EXR files a user hands shadowlab (`compare`'s frames, a cached reference, a projector's .exr
// texture), read by scenes/src/image_io_exr_png.cpp's two readers: readExrCore (OpenEXR's core
// library, taken where it can) and readExrImf (Imf::InputFile). Compiled into this target with that
// file alone (the fuzz build's scenes library reads images through OpenImageIO). Besides crashes
// and sanitizer reports, a difference is a finding: where the core reader takes a file and Imf
// reads it too, every channel, value (bit for bit), size and attribute must be the same, as planes
// and interleaved.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fuzz_support.h"
#include "image_io.h"

using namespace shadowlab;

namespace {

// Sizes beyond this are refused before anything is allocated (readTexture's rule): the inputs are
// at most 8 KB, and a header may claim any size.
constexpr int kMaxSide = 64;

bool same(const image_io::FloatImage& a, const image_io::FloatImage& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels || a.text != b.text) return false;
  if (a.pixels.size() != b.pixels.size() || a.planesRead.size() != b.planesRead.size()) return false;
  if (!a.pixels.empty() && std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) != 0)
    return false;
  for (size_t c = 0; c < a.planesRead.size(); ++c)
    if (a.planesRead[c].size() != b.planesRead[c].size() ||
        (!a.planesRead[c].empty() &&
         std::memcmp(a.planesRead[c].data(), b.planesRead[c].data(), a.planesRead[c].size() * sizeof(float)) != 0))
      return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = fuzz::writeFile("input.exr", std::string(reinterpret_cast<const char*>(data), size));
  for (bool planar : {false, true}) {
    image_io::FloatImage core, imf;
    core.readPlanar = imf.readPlanar = planar;
    // Imf only where the core reader took the file, to compare: on a header that lies about its
    // size Imf 3.1 first allocates what the header claims (its line offset table), which makes
    // a run slow and large without testing anything of ours.
    if (!image_io::readExrCore(path, core, kMaxSide)) continue;
    const std::string err = image_io::readExrImf(path, imf, kMaxSide);
    if (err.empty() && !imf.channels.empty() && !same(core, imf)) {
      std::fprintf(stderr, "fuzz_exr: the two readers differ (%s)\n", planar ? "planes" : "interleaved");
      std::abort();
    }
  }
  return 0;
}
