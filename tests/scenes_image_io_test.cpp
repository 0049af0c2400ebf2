// The two implementations of scenes/src/image_io.h (OpenImageIO; OpenEXR + libpng) must give the
// same results, or a bundle built with exr-png (scripts/device-bundle.sh) would measure something
// else than the default build. This test links the build's implementation; image_io_probe is the
// other one. Each writes the probe images (support/image_io_probe.h); each reads both sets; every
// read must be bit-identical across implementations and equal to what was written (by name).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/loader.h"
#include "support/cli.h"
#include "support/image_io_probe.h"

namespace scenes_image_io_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

#ifdef SHADOWLAB_IMAGE_IO_PROBE
const char* kProbe = SHADOWLAB_IMAGE_IO_PROBE;
#else
const char* kProbe = nullptr;
#endif

fs::path freshDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shadowlab_image_io_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Runs the probe; its stdout parsed as JSON (or the command's failure).
nlohmann::json probe(const std::string& verb, const fs::path& file, const fs::path& scratch) {
  const std::string cmd = std::string(kProbe) + " " + verb + " '" + file.string() + "' >'" +
                          (scratch / "probe.json").string() + "' 2>'" + (scratch / "probe.err").string() + "'";
  const int rc = std::system(cmd.c_str());
  if (rc != 0)
    return {{"error", "probe exited " + std::to_string(rc) + ": " + shadowlab::testing::slurp(scratch / "probe.err")}};
  const std::string out = shadowlab::testing::slurp(scratch / "probe.json");
  return out.empty() ? nlohmann::json::object() : nlohmann::json::parse(out);  // "write" prints nothing
}

nlohmann::json ours(const std::string& verb, const fs::path& file) {
  image_io::FloatImage im;
  im.readPlanar = verb == "exr-planar";
  const std::string err = verb == "exr" || verb == "exr-planar" ? image_io::readExr(file.string(), im)
                                        : image_io::readTexture(file.string(), im, std::numeric_limits<int>::max());
  return shadowlab::testing::describe(im, err);
}

// What was written, by channel name, against what was read.
void expectSameByName(const image_io::FloatImage& written, const nlohmann::json& read, const std::string& who) {
  ASSERT_EQ(read.at("error"), "") << who;
  ASSERT_EQ(read.at("width"), written.width) << who;
  ASSERT_EQ(read.at("height"), written.height) << who;
  const auto names = read.at("channels").get<std::vector<std::string>>();
  ASSERT_EQ(names.size(), written.channels.size()) << who;
  const size_t nc = names.size(), pixels = size_t(written.width) * written.height;
  for (size_t wc = 0; wc < nc; ++wc) {
    size_t rc = std::find(names.begin(), names.end(), written.channels[wc]) - names.begin();
    ASSERT_LT(rc, nc) << who << " lost channel " << written.channels[wc];
    for (size_t i = 0; i < pixels; ++i) {
      uint32_t bits;
      std::memcpy(&bits, &written.pixels[i * nc + wc], sizeof bits);
      ASSERT_EQ(read.at("pixels")[i * nc + rc].get<uint32_t>(), bits)
          << who << " channel " << written.channels[wc] << " pixel " << i;
    }
  }
  for (const auto& [k, v] : written.text)
    EXPECT_EQ(read.at("text").value(k, std::string("(missing)")), v) << who << " " << k;
}

// A PNG texture as read: value * (1/255), colour associated with alpha as OpenImageIO does
// (colour * alpha / 255 in integers, truncated).
void expectPngTexture(const nlohmann::json& read, int channels, const std::string& who) {
  ASSERT_EQ(read.at("error"), "") << who;
  ASSERT_EQ(read.at("channels").size(), size_t(channels)) << who;
  const auto px =
      shadowlab::testing::probePng(shadowlab::testing::kProbePngWidth, shadowlab::testing::kProbePngHeight, channels);
  for (size_t i = 0; i < px.size(); ++i) {
    unsigned v = px[i];
    if (channels == 4 && i % 4 != 3) v = v * px[i - i % 4 + 3] / 255;
    float expected = float(v) * (1.0f / 255.0f);  // OpenImageIO's conversion, to the last bit
    uint32_t bits;
    std::memcpy(&bits, &expected, sizeof bits);
    ASSERT_EQ(read.at("pixels")[i].get<uint32_t>(), bits) << who << " value " << i << " (stored " << int(px[i]) << ")";
  }
}

}  // namespace

TEST(ImageIo, BothImplementationsReadWhatEitherWroteIdentically) {
  if (!kProbe)
    GTEST_SKIP() << "SKIPPED LOUDLY: the other image_io implementation was not built (libopenexr-dev, "
                    "libpng-dev and libopenimageio-dev are all needed; scripts/install-deps.sh installs them)";
  const fs::path mine = freshDir("mine"), theirs = freshDir("theirs"), scratch = freshDir("scratch");
  // Ours writes the probe images...
  ASSERT_EQ(image_io::writeExr((mine / "probe.exr").string(), shadowlab::testing::probeExr()), "");
  std::vector<std::vector<float>> planes;
  ASSERT_EQ(image_io::writeExr((mine / "probe_planar.exr").string(), shadowlab::testing::probeExrPlanar(planes)), "");
  for (int channels : {3, 4}) {
    const auto px =
        shadowlab::testing::probePng(shadowlab::testing::kProbePngWidth, shadowlab::testing::kProbePngHeight, channels);
    ASSERT_EQ(image_io::writePng((mine / (channels == 3 ? "probe_rgb.png" : "probe_rgba.png")).string(),
                                 shadowlab::testing::kProbePngWidth, shadowlab::testing::kProbePngHeight, channels,
                                 px.data()),
              "");
  }
  // ... and so does the other implementation.
  const nlohmann::json written = probe("write", theirs, scratch);
  ASSERT_FALSE(written.contains("error")) << written.dump();

  for (const fs::path& dir : {mine, theirs}) {
    const std::string from = dir == mine ? std::string(image_io::backendName()) + " wrote" : "the other wrote";
    // probe_planar.exr: the same image written from planes (FloatImage::planes), as frames are.
    for (const char* file : {"probe.exr", "probe_planar.exr"}) {
      const nlohmann::json a = ours("exr", dir / file), b = probe("exr", dir / file, scratch);
      const std::string what = std::string(file) + ", ";
      expectSameByName(shadowlab::testing::probeExr(), a,
                       what + std::string(image_io::backendName()) + " read, " + from);
      expectSameByName(shadowlab::testing::probeExr(), b, what + b.value("backend", "?") + " read, " + from);
      nlohmann::json bSame = b;
      bSame.erase("backend");
      // Same channel order too (OpenImageIO's), not only the same values by name.
      EXPECT_EQ(a, bSame) << what << from << "\n" << a.at("channels").dump() << "\n" << bSame.at("channels").dump();
      // The planar read (readFrameExr's) gives the same channels, order and bits, in both.
      const nlohmann::json pa = ours("exr-planar", dir / file);
      nlohmann::json pb = probe("exr-planar", dir / file, scratch);
      pb.erase("backend");
      EXPECT_EQ(pa, a) << what << from << ": " << image_io::backendName() << "'s planar read";
      EXPECT_EQ(pb, bSame) << what << from << ": the other's planar read";
    }
    for (int channels : {3, 4}) {
      const fs::path png = dir / (channels == 3 ? "probe_rgb.png" : "probe_rgba.png");
      const nlohmann::json ta = ours("texture", png), tb = probe("texture", png, scratch);
      expectPngTexture(ta, channels, std::string(image_io::backendName()) + " read, " + from);
      expectPngTexture(tb, channels, tb.value("backend", "?") + " read, " + from);
    }
  }
  // The bundled textures (8-bit gray, 8-bit RGB) read the same through both.
  for (const char* name : {"fence_alpha.png", "projector_image.png"}) {
    const fs::path file = fs::path(bundledScenesDir()) / name;
    nlohmann::json a = ours("texture", file), b = probe("texture", file, scratch);
    b.erase("backend");
    EXPECT_EQ(a.at("error"), "") << name;
    EXPECT_EQ(a.at("pixels"), b.at("pixels")) << name;
    EXPECT_EQ(a.at("channels").size(), b.at("channels").size()) << name;
  }
  fs::remove_all(mine);
  fs::remove_all(theirs);
  fs::remove_all(scratch);
}

// Each implementation says what it failed to read, and the Frame reader turns that into an
// InputError naming the file.
TEST(ImageIo, UnreadableFilesAreNamedErrors) {
  const fs::path dir = freshDir("bad");
  const fs::path notExr = dir / "not.exr";
  { std::ofstream(notExr) << "not an image"; }
  image_io::FloatImage im;
  EXPECT_NE(image_io::readExr(notExr.string(), im), "");
  EXPECT_NE(image_io::readTexture(notExr.string(), im, 16), "");
  const fs::path notPng = dir / "not.png";
  { std::ofstream(notPng) << "not an image"; }
  EXPECT_NE(image_io::readTexture(notPng.string(), im, 16), "");
  try {
    readFrameExr(notExr.string());
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(notExr.string()), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// PngRows::Unfiltered (errors.png, the triptychs) changes how the file is compressed, never the
// pixels: both files read back as what was written, and the files differ (the option reaches
// the encoder: on a gradient libpng's adaptive filters pick Sub/Up/Paeth rows, not None).
TEST(ImageIo, UnfilteredPngHoldsTheSamePixels) {
  const fs::path dir = freshDir("unfiltered");
  const int w = 64, h = 16;
  std::vector<uint8_t> rgb(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) rgb[(size_t(y) * w + x) * 3 + c] = uint8_t(x * 3 + y * 7 + c * 50);
  const std::string adaptive = (dir / "adaptive.png").string(), unfiltered = (dir / "unfiltered.png").string();
  writeRgbPng(adaptive, w, h, rgb);
  writeRgbPng(unfiltered, w, h, rgb, PngRows::Unfiltered);
  for (const std::string& path : {adaptive, unfiltered}) {
    image_io::FloatImage im;
    ASSERT_EQ(image_io::readTexture(path, im, std::numeric_limits<int>::max()), "") << path;
    ASSERT_EQ(im.width, w);
    ASSERT_EQ(im.height, h);
    ASSERT_EQ(im.pixels.size(), rgb.size()) << path;
    for (size_t i = 0; i < rgb.size(); ++i)
      ASSERT_EQ(im.pixels[i], float(rgb[i]) * (1.0f / 255.0f)) << path << " value " << i;  // as expectPngTexture
  }
  EXPECT_NE(shadowlab::testing::slurp(adaptive), shadowlab::testing::slurp(unfiltered));
  fs::remove_all(dir);
}

}  // namespace scenes_image_io_test
