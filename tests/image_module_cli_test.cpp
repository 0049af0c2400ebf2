// OpenImageIO as a module loaded on first use (scenes/src/image_io_module.cpp): the program does
// not load OpenImageIO's ~260 libraries when it starts, a command that needs no image runs without
// the module, and one that needs it names the module it could not load, exits 2 and leaves no
// half-written file. Skipped in builds that link the image library (SHADOWLAB_IMAGE_IO=exr-png or
// SHADOWLAB_IMAGE_IO_MODULE=OFF).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "support/cli.h"

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

TEST(ImageModule, WithoutItOnlyTheCommandsThatNeedImagesFailNamingIt) {
  if (!kModule) GTEST_SKIP() << "this build links its image library";
  const fs::path dir = freshTempDir("shadowlab_image_module_missing");
  const std::string missing = (dir / "no-such-module.so").string();
  const std::string env = "SHADOWLAB_IMAGE_IO_MODULE='" + missing + "' ";

  auto r = runShadowlab("classes", dir, env);  // no image read or written
  EXPECT_EQ(r.code, 0) << r.err;

  const fs::path out = dir / "ref";
  r = runShadowlab(kSmallReference + "'" + out.string() + "'", dir, env);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(
      r.err.find("cannot load OpenImageIO's module libshadowlab_image_io_oiio.so: tried " + missing + " (missing)"),
      std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("reference.exr"), std::string::npos) << "the file it was writing is named: " << r.err;
  EXPECT_FALSE(fs::exists(out / "reference.exr")) << "no half-written output";

  // A library that is not the module is refused by name, not called.
  r = runShadowlab(kSmallReference + "'" + out.string() + "'", dir,
                   "SHADOWLAB_IMAGE_IO_MODULE=/lib/x86_64-linux-gnu/libm.so.6 ");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("libm.so.6 (not this build's image module)"), std::string::npos) << r.err;

  // The module named by the variable is the one used.
  r = runShadowlab(kSmallReference + "'" + out.string() + "'", dir,
                   "SHADOWLAB_IMAGE_IO_MODULE='" + std::string(kModule) + "' ");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(out / "reference.exr"));
  fs::remove_all(dir);
}
