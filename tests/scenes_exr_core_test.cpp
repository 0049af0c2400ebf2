// The two EXR readers of scenes/src/image_io_exr_png.cpp must read every file alike: readExrCore
// (OpenEXR's core library, the fast one readExr takes where it can) and readExrImf (Imf::InputFile,
// the fallback). Files are written here with OpenEXR's own writer in every compression, with HALF,
// FLOAT and UINT channels, a data window away from the origin and a partial last block; each is read
// by both, interleaved and as planes, and the values must be the same bits. The core reader must
// take the scanline files (else the fast path would be dead code and the test vacuous) and leave
// tiled, truncated and oversized ones to the other.
#include <gtest/gtest.h>

#ifdef SHADOWLAB_TEST_EXR_CORE
#include <unistd.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTiledOutputFile.h>
#include <Imath/half.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "image_io.h"

namespace scenes_exr_core_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

#ifdef SHADOWLAB_IMAGE_IO_HYBRID
namespace io = image_io::exr_png;
#else
namespace io = image_io;
#endif

constexpr int kMax = std::numeric_limits<int>::max();

// Channel values of every kind a file holds: ordinary, negative, tiny (half denormals), huge,
// infinite, NaN; UINTs beyond 2^24 (float rounds them).
struct Planes {
  int width = 0, height = 0;
  std::vector<half> a;        // "A": HALF
  std::vector<float> b, z;    // "B", "layer.z": FLOAT
  std::vector<uint32_t> c;    // "C": UINT
};

Planes makePlanes(int width, int height) {
  Planes p;
  p.width = width;
  p.height = height;
  const size_t n = size_t(width) * size_t(height);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  const float special[] = {0.0f, -0.0f, 1e-7f, 65504.0f, std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN(), 3e38f};
  for (size_t i = 0; i < n; ++i) {
    const float v = i % 17 == 0 ? special[(i / 17) % 8] : u(rng);
    p.a.push_back(half(v));
    p.b.push_back(i % 5 == 0 ? 1.0f : v * 1000.0f);  // runs of equal values too
    p.z.push_back(float(i) * 0.25f - 7.0f);
    p.c.push_back(i % 3 == 0 ? uint32_t(i) : 4294967295u - uint32_t(i * 2654435761u % 1000003u));
  }
  return p;
}

Imf::Header headerFor(const Planes& p, Imf::Compression compression, int x0, int y0) {
  Imf::Header h(Imath::Box2i({-10, -10}, {x0 + p.width + 5, y0 + p.height + 5}),
                Imath::Box2i({x0, y0}, {x0 + p.width - 1, y0 + p.height - 1}));
  h.compression() = compression;
  h.channels().insert("A", Imf::Channel(Imf::HALF));
  h.channels().insert("B", Imf::Channel(Imf::FLOAT));
  h.channels().insert("C", Imf::Channel(Imf::UINT));
  h.channels().insert("layer.z", Imf::Channel(Imf::FLOAT));
  h.insert("shadowlab:note", Imf::StringAttribute("a note, with unicode: \xc3\xa9"));
  return h;
}

Imf::FrameBuffer frameBufferFor(Planes& p, int x0, int y0) {
  Imf::FrameBuffer fb;
  const ptrdiff_t origin = ptrdiff_t(x0) + ptrdiff_t(y0) * p.width;
  auto slice = [&](Imf::PixelType t, void* data, size_t size) {
    return Imf::Slice(t, static_cast<char*>(data) - origin * ptrdiff_t(size), size, size * size_t(p.width));
  };
  fb.insert("A", slice(Imf::HALF, p.a.data(), sizeof(half)));
  fb.insert("B", slice(Imf::FLOAT, p.b.data(), sizeof(float)));
  fb.insert("C", slice(Imf::UINT, p.c.data(), sizeof(uint32_t)));
  fb.insert("layer.z", slice(Imf::FLOAT, p.z.data(), sizeof(float)));
  return fb;
}

void writeScanlines(const std::string& path, Planes& p, Imf::Compression compression, int x0, int y0) {
  Imf::OutputFile out(path.c_str(), headerFor(p, compression, x0, y0));
  out.setFrameBuffer(frameBufferFor(p, x0, y0));
  out.writePixels(p.height);
}

void writeTiled(const std::string& path, Planes& p, int x0, int y0) {
  Imf::Header h = headerFor(p, Imf::ZIP_COMPRESSION, x0, y0);
  h.setTileDescription(Imf::TileDescription(16, 8, Imf::ONE_LEVEL));
  Imf::TiledOutputFile out(path.c_str(), h);
  out.setFrameBuffer(frameBufferFor(p, x0, y0));
  out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
}

// Both readers' results, the same bits (NaN included), channels, order and attributes.
void expectSame(const image_io::FloatImage& core, const image_io::FloatImage& imf, const std::string& what) {
  EXPECT_EQ(core.width, imf.width) << what;
  EXPECT_EQ(core.height, imf.height) << what;
  EXPECT_EQ(core.channels, imf.channels) << what;
  EXPECT_EQ(core.text, imf.text) << what;
  ASSERT_EQ(core.pixels.size(), imf.pixels.size()) << what;
  if (!core.pixels.empty()) {
    EXPECT_EQ(std::memcmp(core.pixels.data(), imf.pixels.data(), core.pixels.size() * sizeof(float)), 0) << what;
  }
  ASSERT_EQ(core.planesRead.size(), imf.planesRead.size()) << what;
  for (size_t c = 0; c < core.planesRead.size(); ++c) {
    ASSERT_EQ(core.planesRead[c].size(), imf.planesRead[c].size()) << what;
    if (!core.planesRead[c].empty()) {
      EXPECT_EQ(std::memcmp(core.planesRead[c].data(), imf.planesRead[c].data(), core.planesRead[c].size() * 4), 0)
          << what << ", plane " << core.channels[c];
    }
  }
}

fs::path freshDir() {
  fs::path d = fs::temp_directory_path() / ("shadowlab_exr_core_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(ExrCore, ReadsEveryCompressionAsImfDoes) {
  const fs::path dir = freshDir();
  // 37 x 45 from (-3, 5): blocks of 1 (ZIPS, RLE, none), 16 (ZIP, PXR24), 32 (PIZ, B44) lines, the
  // last one partial.
  Planes p = makePlanes(37, 45);
  const struct {
    const char* name;
    Imf::Compression compression;
    bool coreMustTake;  // the compressions shadowlab writes and reads most
  } cases[] = {{"none", Imf::NO_COMPRESSION, true},   {"rle", Imf::RLE_COMPRESSION, true},
               {"zips", Imf::ZIPS_COMPRESSION, true}, {"zip", Imf::ZIP_COMPRESSION, true},
               {"piz", Imf::PIZ_COMPRESSION, true},   {"pxr24", Imf::PXR24_COMPRESSION, false},
               {"b44", Imf::B44_COMPRESSION, false},  {"b44a", Imf::B44A_COMPRESSION, false}};
  int taken = 0;
  for (const auto& k : cases) {
    const std::string path = (dir / (std::string(k.name) + ".exr")).string();
    writeScanlines(path, p, k.compression, -3, 5);
    for (bool planar : {false, true}) {
      const std::string what = std::string(k.name) + (planar ? ", planes" : ", interleaved");
      image_io::FloatImage core, imf, viaReadExr;
      core.readPlanar = imf.readPlanar = viaReadExr.readPlanar = planar;
      const bool took = io::readExrCore(path, core, kMax);
      if (k.coreMustTake) {
        EXPECT_TRUE(took) << what;
      }
      ASSERT_EQ(io::readExrImf(path, imf, kMax), "") << what;
      ASSERT_EQ(image_io::readExr(path, viaReadExr), "") << what;
      expectSame(viaReadExr, imf, what + " (readExr)");
      if (!took) continue;
      ++taken;
      expectSame(core, imf, what);
      // OpenImageIO's order: B (blue) before A (alpha), then the rest as the file sorts them.
      ASSERT_EQ(core.channels, (std::vector<std::string>{"B", "A", "C", "layer.z"})) << what;
      EXPECT_EQ(core.text.at("shadowlab:note"), "a note, with unicode: \xc3\xa9") << what;
      // The values themselves, not only the two readers' agreement: HALF and UINT convert to float.
      const size_t i = 17 * 3 + 1, n = size_t(p.width) * size_t(p.height);
      const float a = planar ? core.planesRead[1][i] : core.pixels[i * 4 + 1];
      const float c = planar ? core.planesRead[2][n - 1] : core.pixels[(n - 1) * 4 + 2];
      if (k.compression != Imf::B44_COMPRESSION && k.compression != Imf::B44A_COMPRESSION) {  // lossy for HALF
        EXPECT_EQ(a, float(p.a[i])) << what;
      }
      EXPECT_EQ(c, float(p.c[n - 1])) << what;
    }
  }
  EXPECT_GE(taken, 10);
  fs::remove_all(dir);
}

TEST(ExrCore, LeavesTiledTruncatedAndOversizedFilesToImf) {
  const fs::path dir = freshDir();
  Planes p = makePlanes(29, 21);
  const std::string tiled = (dir / "tiled.exr").string();
  writeTiled(tiled, p, 2, -4);
  image_io::FloatImage core, imf, viaReadExr;
  EXPECT_FALSE(io::readExrCore(tiled, core, kMax));
  EXPECT_TRUE(core.channels.empty() && core.pixels.empty()) << "untouched";
  ASSERT_EQ(io::readExrImf(tiled, imf, kMax), "");
  ASSERT_EQ(image_io::readExr(tiled, viaReadExr), "");
  expectSame(viaReadExr, imf, "tiled");
  EXPECT_EQ(viaReadExr.width, 29);
  EXPECT_EQ(viaReadExr.height, 21);

  // Larger than the caller allows: left to Imf, which returns the size alone (readTexture's rule).
  const std::string zip = (dir / "zip.exr").string();
  writeScanlines(zip, p, Imf::ZIP_COMPRESSION, 0, 0);
  image_io::FloatImage small;
  EXPECT_FALSE(io::readExrCore(zip, small, 20));
  ASSERT_EQ(io::readExrImf(zip, small, 20), "");
  EXPECT_EQ(small.width, 29);
  EXPECT_TRUE(small.pixels.empty());

  // Cut in the middle of its blocks: the core reader gives up and the other names the damage.
  const std::string cut = (dir / "cut.exr").string();
  fs::copy_file(zip, cut);
  fs::resize_file(cut, fs::file_size(zip) * 2 / 3);
  image_io::FloatImage damaged;
  EXPECT_FALSE(io::readExrCore(cut, damaged, kMax));
  EXPECT_NE(image_io::readExr(cut, damaged), "");

  // A header claiming a 2^30 x 2^30 data window (its dataWindow box patched): an error, no crash
  // and no attempt to hold 2^60 values.
  std::string bytes;
  {
    std::ifstream in(zip, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string key("dataWindow\0box2i\0", 17);
  const size_t at = bytes.find(key);
  ASSERT_NE(at, std::string::npos);
  const int32_t huge = 1 << 30;
  std::memcpy(&bytes[at + key.size() + 4 + 8], &huge, 4);   // xMax
  std::memcpy(&bytes[at + key.size() + 4 + 12], &huge, 4);  // yMax
  const std::string lying = (dir / "huge_window.exr").string();
  { std::ofstream(lying, std::ios::binary) << bytes; }
  image_io::FloatImage claimed;
  EXPECT_FALSE(io::readExrCore(lying, claimed, kMax));
  EXPECT_NE(image_io::readExr(lying, claimed), "");

  // A float attribute declaring 2 bytes (fuzz_exr's finding, tests/fuzz/regressions/exr): Imf reads
  // 4 and goes on, a lenient parse would read 2 and misname the attributes after it. The core reader
  // parses headers strictly and leaves such a file to Imf, so readExr reads it as Imf does.
  std::string odd = bytes;
  std::memcpy(&odd[at + key.size() + 4 + 8], "\x1c\0\0\0", 4);  // the window as it was (29 - 1)
  std::memcpy(&odd[at + key.size() + 4 + 12], "\x14\0\0\0", 4);  // (21 - 1)
  const std::string floatKey("screenWindowWidth\0float\0", 24);
  const size_t f = odd.find(floatKey);
  ASSERT_NE(f, std::string::npos);
  odd[f + floatKey.size()] = 2;
  const std::string twoBytes = (dir / "float_in_2_bytes.exr").string();
  { std::ofstream(twoBytes, std::ios::binary) << odd; }
  image_io::FloatImage strict, viaImf, viaReadExr2;
  EXPECT_FALSE(io::readExrCore(twoBytes, strict, kMax));
  ASSERT_EQ(io::readExrImf(twoBytes, viaImf, kMax), "");
  ASSERT_EQ(image_io::readExr(twoBytes, viaReadExr2), "");
  expectSame(viaReadExr2, viaImf, "a float attribute of 2 bytes");
  EXPECT_TRUE(viaReadExr2.text.count("shadowlab:note")) << "the attribute after it keeps its name";
  fs::remove_all(dir);
}

// An uncompressed block shorter than its lines (fuzz_exr's finding, tests/fuzz/regressions/exr):
// OpenEXR 3.1's core library decoded it without an error from beyond its buffer (values that
// changed from run to run) and Imf reads it too. The core reader names the damage and readExr
// reports it.
TEST(ExrCore, NamesAnUncompressedBlockShorterThanItsLines) {
  const fs::path dir = freshDir();
  Planes p = makePlanes(29, 21);
  const std::string whole = (dir / "none.exr").string();
  writeScanlines(whole, p, Imf::NO_COMPRESSION, 0, 3);
  std::string bytes;
  {
    std::ifstream in(whole, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  // The first block: its line (3) and its size, 29 pixels of A (2 bytes), B, C and layer.z (4 each).
  const int32_t head[2] = {3, 29 * 14};
  const size_t block = bytes.find(std::string(reinterpret_cast<const char*>(head), sizeof(head)));
  ASSERT_NE(block, std::string::npos);
  const int32_t shorter = head[1] - 2;
  std::memcpy(&bytes[block + 4], &shorter, 4);
  const std::string cut = (dir / "short_block.exr").string();
  { std::ofstream(cut, std::ios::binary) << bytes; }

  image_io::FloatImage intact;
  std::string damage = "unset";
  EXPECT_TRUE(io::readExrCore(whole, intact, kMax, &damage)) << "the file as written";
  for (bool planar : {false, true}) {
    image_io::FloatImage core, viaReadExr;
    core.readPlanar = viaReadExr.readPlanar = planar;
    damage.clear();
    EXPECT_FALSE(io::readExrCore(cut, core, kMax, &damage));
    EXPECT_TRUE(core.channels.empty() && core.pixels.empty() && core.planesRead.empty()) << "untouched";
    EXPECT_NE(damage.find("line 3 holds 404 bytes, its lines 406"), std::string::npos) << damage;
    const std::string err = image_io::readExr(cut, viaReadExr);
    EXPECT_NE(err.find("damaged"), std::string::npos) << err;
  }
  fs::remove_all(dir);
}

#else

TEST(ExrCore, NeedsTheOpenExrReaders) {
  GTEST_SKIP() << "this build reads EXR through OpenImageIO alone (no image_io_exr_png.cpp)";
}

#endif

}  // namespace scenes_exr_core_test
