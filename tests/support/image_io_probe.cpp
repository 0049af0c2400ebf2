// image_io_probe: the image_io.h implementation this build does NOT use, as a small executable
// (tests/CMakeLists.txt compiles it with the other image_io_*.cpp), so that
// tests/scenes_image_io_test.cpp can check both implementations against each other.
//   image_io_probe write DIR        writes DIR/probe.exr, DIR/probe_planar.exr (the same image from
//                                   planes), DIR/probe_rgb.png, DIR/probe_rgba.png
//   image_io_probe exr FILE         prints what readExr gives (JSON, see image_io_probe.h)
//   image_io_probe exr-planar FILE  the same with FloatImage::readPlanar (described interleaved)
//   image_io_probe texture FILE     prints what readTexture gives
#include <cstdio>
#include <limits>
#include <string>

#include "image_io_probe.h"

using namespace shadowlab;

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: image_io_probe write DIR | exr FILE | texture FILE\n");
    return 2;
  }
  const std::string verb = argv[1], path = argv[2];
  if (verb == "write") {
    std::string err = image_io::writeExr(path + "/probe.exr", testing::probeExr());
    std::vector<std::vector<float>> planes;
    if (err.empty()) err = image_io::writeExr(path + "/probe_planar.exr", testing::probeExrPlanar(planes));
    for (int channels : {3, 4}) {
      if (!err.empty()) break;
      const auto px = testing::probePng(testing::kProbePngWidth, testing::kProbePngHeight, channels);
      err = image_io::writePng(path + (channels == 3 ? "/probe_rgb.png" : "/probe_rgba.png"), testing::kProbePngWidth,
                               testing::kProbePngHeight, channels, px.data());
    }
    if (!err.empty()) {
      std::fprintf(stderr, "image_io_probe (%s): %s\n", image_io::backendName(), err.c_str());
      return 3;
    }
    return 0;
  }
  image_io::FloatImage im;
  std::string err;
  im.readPlanar = verb == "exr-planar";
  if (verb == "exr" || verb == "exr-planar") err = image_io::readExr(path, im);
  else if (verb == "texture") err = image_io::readTexture(path, im, std::numeric_limits<int>::max());
  else {
    std::fprintf(stderr, "image_io_probe: unknown verb %s\n", verb.c_str());
    return 2;
  }
  nlohmann::json j = testing::describe(im, err);
  j["backend"] = image_io::backendName();
  std::printf("%s\n", j.dump().c_str());
  return 0;
}
