// Frame EXR round trip, atomic writers and the small io helpers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/io.h"

namespace scenes_frame_test {

namespace fs = std::filesystem;
using namespace shadowlab;

namespace {

fs::path freshDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("shadowlab_scenes_frame_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST(ScenesFrame, AddGetHas) {
  Frame f;
  f.width = 3;
  f.height = 2;
  auto& hit = f.add("hit", 1.0f);
  EXPECT_EQ(hit.size(), 6u);
  EXPECT_EQ(hit[5], 1.0f);
  hit[2] = 7.0f;
  EXPECT_EQ(&f.add("hit"), &f.get("hit"));  // add of an existing name returns it unchanged
  EXPECT_EQ(f.get("hit")[2], 7.0f);
  EXPECT_TRUE(f.has("hit"));
  EXPECT_FALSE(f.has("miss"));
  try {
    f.get("miss");
    FAIL() << "get of a missing channel must throw";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "frame has no channel miss");
  }
}

// EXR sorts channels by name; reading must go by name. The channel names here are deliberately
// out of order and the values cover the whole float range (denormals, -0, huge, ids near 2^24),
// so any reordering or conversion shows as a bit difference.
TEST(ScenesFrameExr, RoundTripIsBitExactWithNamesAndMeta) {
  fs::path dir = freshDir("roundtrip");
  Frame f;
  f.width = 37;
  f.height = 23;
  const std::vector<std::string> names = {"zeta", "light.sun.vis", "P.x", "alpha", "proj.slide.R", "hit", "object_id"};
  std::mt19937 rng(1234);
  std::uniform_int_distribution<uint32_t> bits;
  for (size_t c = 0; c < names.size(); ++c) {
    auto& plane = f.add(names[c]);
    for (size_t i = 0; i < plane.size(); ++i) {
      uint32_t b = bits(rng);
      float v;
      std::memcpy(&v, &b, 4);
      if (!std::isfinite(v)) v = float(c * 1000 + i);  // NaN payloads need not survive
      plane[i] = v;
    }
  }
  f.get("object_id")[0] = 16777215.0f;
  f.get("hit")[1] = -0.0f;
  f.get("hit")[2] = 1e-40f;  // denormal
  f.meta = {{"kind", "reference"}, {"scene", "sphere_on_plane"}, {"lights", {"sun"}}, {"width", 37}};
  std::string path = (dir / "frame.exr").string();
  writeFrameExr(f, path);
  EXPECT_EQ(listing(dir), std::vector<std::string>{"frame.exr"});  // no temp file left

  Frame g = readFrameExr(path);
  EXPECT_EQ(g.width, 37);
  EXPECT_EQ(g.height, 23);
  EXPECT_EQ(g.names, names);  // insertion order restored
  for (const auto& n : names) {
    ASSERT_TRUE(g.has(n)) << n;
    ASSERT_EQ(g.get(n).size(), f.get(n).size());
    EXPECT_EQ(0, std::memcmp(g.get(n).data(), f.get(n).data(), f.get(n).size() * sizeof(float))) << "channel " << n;
  }
  EXPECT_EQ(g.meta, f.meta);
}

TEST(ScenesFrameExr, OverwriteReplacesWholeFile) {
  fs::path dir = freshDir("overwrite");
  std::string path = (dir / "f.exr").string();
  Frame a;
  a.width = a.height = 4;
  a.add("hit", 1.0f);
  writeFrameExr(a, path);
  Frame b;
  b.width = 2;
  b.height = 3;
  b.add("object_id", 5.0f);
  writeFrameExr(b, path);
  Frame c = readFrameExr(path);
  EXPECT_EQ(c.width, 2);
  EXPECT_EQ(c.height, 3);
  EXPECT_EQ(c.names, std::vector<std::string>{"object_id"});
  EXPECT_EQ(c.get("object_id")[5], 5.0f);
  EXPECT_EQ(listing(dir), std::vector<std::string>{"f.exr"});
}

TEST(ScenesFrameExr, ErrorsNameThePathAndWriteNothing) {
  fs::path dir = freshDir("errors");
  Frame f;
  f.width = f.height = 2;
  f.add("hit");
  std::string missingFolder = (dir / "nope" / "f.exr").string();
  try {
    writeFrameExr(f, missingFolder);
    FAIL() << "writing into a missing folder must throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missingFolder + ": error: "), std::string::npos) << e.what();
  }
  Frame empty;
  EXPECT_THROW(writeFrameExr(empty, (dir / "empty.exr").string()), InputError);
  Frame bad;
  bad.width = bad.height = 2;
  bad.names = {"hit"};
  bad.data = {std::vector<float>(3)};  // wrong plane size: an internal bug, not bad input
  EXPECT_THROW(writeFrameExr(bad, (dir / "bad.exr").string()), DriverError);
  EXPECT_TRUE(listing(dir).empty());
  try {
    readFrameExr((dir / "absent.exr").string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.exr: error: cannot open file"), std::string::npos) << e.what();
  }
  writeFileAtomic((dir / "garbage.exr").string(), "not an exr");
  EXPECT_THROW(readFrameExr((dir / "garbage.exr").string()), InputError);
}

TEST(ScenesRgbPng, WritesAtomicallyAndChecksSize) {
  fs::path dir = freshDir("png");
  std::vector<uint8_t> rgb(5 * 4 * 3, 200);
  std::string path = (dir / "pic.png").string();
  writeRgbPng(path, 5, 4, rgb);
  EXPECT_EQ(listing(dir), std::vector<std::string>{"pic.png"});
  std::string bytes = readFile(path);
  ASSERT_GE(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  EXPECT_THROW(writeRgbPng((dir / "short.png").string(), 5, 4, std::vector<uint8_t>(10)), DriverError);
  EXPECT_EQ(listing(dir), std::vector<std::string>{"pic.png"});
}

TEST(ScenesIo, WriteFileAtomicReadFileMakeDirs) {
  fs::path dir = freshDir("io");
  std::string path = (dir / "a.txt").string();
  writeFileAtomic(path, "first");
  writeFileAtomic(path, std::string("sec\0ond", 7));
  EXPECT_EQ(readFile(path), std::string("sec\0ond", 7));
  writeJsonAtomic((dir / "j.json").string(), nlohmann::json{{"b", 1}, {"a", 2}});
  EXPECT_EQ(readFile((dir / "j.json").string()), "{\n  \"a\": 2,\n  \"b\": 1\n}\n");
  EXPECT_EQ(listing(dir), (std::vector<std::string>{"a.txt", "j.json"}));

  try {
    writeFileAtomic((dir / "missing" / "x.txt").string(), "x");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x.txt: error: cannot write file"), std::string::npos) << e.what();
  }
  try {
    readFile((dir / "none.txt").string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "none.txt").string() + ": error: cannot open file", 0), 0u)
        << e.what();
  }
  makeDirs((dir / "x" / "y" / "z").string());
  EXPECT_TRUE(fs::is_directory(dir / "x" / "y" / "z"));
  EXPECT_THROW(makeDirs((dir / "a.txt" / "sub").string()), InputError);  // a file in the way
}

TEST(ScenesIo, FnvAndHex) {
  // Published FNV-1a 64-bit test vectors.
  EXPECT_EQ(fnv1a64("", 0), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a64("a", 1), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar", 6), 0x85944171f73967e8ull);
  // Chaining through the seed equals hashing the concatenation.
  EXPECT_EQ(fnv1a64("bar", 3, fnv1a64("foo", 3)), fnv1a64("foobar", 6));
  EXPECT_EQ(hashHex(0xaf63dc4c8601ec8cull), "af63dc4c8601ec8c");
  EXPECT_EQ(hashHex(1), "0000000000000001");
}

TEST(ScenesError, Format) {
  EXPECT_EQ(formatError("s.json", "/lights/0", "got 2"), "s.json: /lights/0: error: got 2");
  EXPECT_EQ(formatError("s.json", "", "bad"), "s.json: error: bad");
}

}  // namespace scenes_frame_test
