// OpenImageIO as a module loaded on first use (scenes/src/image_io_module.cpp): the program does
// not load OpenImageIO's ~260 libraries when it starts, a command that needs no image runs without
// the module, and one that needs it names the module it could not load, exits 2 and leaves no
// half-written file. Skipped in builds that link the image library (SHADOWLAB_IMAGE_IO=exr-png or
// SHADOWLAB_IMAGE_IO_MODULE=OFF).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "support/cli.h"

namespace image_module_cli_test {

namespace fs = std::filesystem;
using shadowlab::testing::freshTempDir;
using shadowlab::testing::runShadowlab;
using shadowlab::testing::slurp;

namespace {

#ifdef SHADOWLAB_TEST_IMAGE_MODULE
constexpr const char* kModule = SHADOWLAB_TEST_IMAGE_MODULE;
#else
constexpr const char* kModule = nullptr;
#endif
// The default build: EXR and PNG through OpenEXR and libpng, the module for other formats only.
#ifdef SHADOWLAB_TEST_IMAGE_HYBRID
constexpr bool kHybrid = true;
#else
constexpr bool kHybrid = false;
#endif

const std::string kSmallReference =
    "reference sphere_on_plane --set scene:/camera/width=32 --set scene:/camera/height=24 -o ";

}  // namespace

TEST(ImageModule, TheProgramStartsWithoutOpenImageIO) {
  if (!kModule) GTEST_SKIP() << "this build links its image library";
  const fs::path dir = freshTempDir("shadowlab_image_module_ldd");
  ASSERT_EQ(std::system(("ldd '" + std::string(SHADOWLAB_BINARY) + "' >'" + (dir / "ldd.txt").string() + "'").c_str()),
            0);
  const std::string libraries = slurp(dir / "ldd.txt");
  EXPECT_NE(libraries.find("libembree3"), std::string::npos) << libraries;  // the listing is the program's
  EXPECT_EQ(libraries.find("OpenImageIO"), std::string::npos) << libraries;
  ASSERT_EQ(std::system(("ldd '" + std::string(kModule) + "' >'" + (dir / "ldd.txt").string() + "'").c_str()), 0);
  EXPECT_NE(slurp(dir / "ldd.txt").find("libOpenImageIO"), std::string::npos) << "the module is where it went";
  fs::remove_all(dir);
}

namespace {

// A projector scene whose slide is a PPM file: a format only OpenImageIO reads, so reading the scene
// needs the module in every build that has one.
fs::path ppmSlideScene(const fs::path& dir) {
  std::ofstream(dir / "slide.ppm", std::ios::binary) << "P6\n2 2\n255\n" << std::string("\xff\x00\x00\x00\xff\x00\x00\x00\xff\xff\xff\xff", 12);
  const fs::path scene = dir / "slide.json";
  std::ofstream(scene) << R"({"camera": {"position": [11, 5, 1], "look_at": [0, 2, 0.5], "vfov_deg": 60, "width": 32, "height": 24},
    "objects": [{"type": "quad", "name": "screen", "size": [10, 6], "transform": {"translate": [0, 3, -5]}}],
    "projectors": [{"name": "slide", "position": [0, 2.5, 3], "look_at": [0, 2.5, -5], "fov_deg": 40,
                    "near": 0.1, "far": 50, "image": "slide.ppm"}]})";
  return scene;
}

}  // namespace

TEST(ImageModule, WithoutItOnlyTheCommandsThatNeedImagesFailNamingIt) {
  if (!kModule) GTEST_SKIP() << "this build links its image library";
  const fs::path dir = freshTempDir("shadowlab_image_module_missing");
  const std::string missing = (dir / "no-such-module.so").string();
  const std::string env = "SHADOWLAB_IMAGE_IO_MODULE='" + missing + "' ";
  const std::string cannotLoad =
      "cannot load OpenImageIO's module libshadowlab_image_io_oiio.so: tried " + missing + " (missing)";

  auto r = runShadowlab("classes", dir, env);  // no image read or written
  EXPECT_EQ(r.code, 0) << r.err;

  const fs::path out = dir / "ref";
  r = runShadowlab(kSmallReference + "'" + out.string() + "'", dir, env);
  if (kHybrid) {
    // EXR and PNG through OpenEXR and libpng, linked in: no module needed (image_io_module.cpp).
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::is_regular_file(out / "reference.exr"));
  } else {
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find(cannotLoad), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("reference.exr"), std::string::npos) << "the file it was writing is named: " << r.err;
    EXPECT_FALSE(fs::exists(out / "reference.exr")) << "no half-written output";
  }

  // A texture in a format only OpenImageIO reads: the command names the module and the texture.
  const fs::path scene = ppmSlideScene(dir), slideOut = dir / "slide_ref";
  r = runShadowlab("reference '" + scene.string() + "' -o '" + slideOut.string() + "'", dir, env);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(cannotLoad), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("slide.ppm"), std::string::npos) << "the texture is named: " << r.err;
  EXPECT_FALSE(fs::exists(slideOut / "reference.exr")) << "no output";

  // A library that is not the module is refused by name, not called.
  r = runShadowlab("reference '" + scene.string() + "' -o '" + slideOut.string() + "'", dir,
                   "SHADOWLAB_IMAGE_IO_MODULE=/lib/x86_64-linux-gnu/libm.so.6 ");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("libm.so.6 (not this build's image module)"), std::string::npos) << r.err;

  // The module named by the variable is the one used.
  r = runShadowlab("reference '" + scene.string() + "' -o '" + slideOut.string() + "'", dir,
                   "SHADOWLAB_IMAGE_IO_MODULE='" + std::string(kModule) + "' ");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(slideOut / "reference.exr"));
  fs::remove_all(dir);
}

}  // namespace image_module_cli_test
