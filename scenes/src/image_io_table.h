#pragma once
// The image_io.h functions as a table, for the OpenImageIO implementation built as a module
// (SHADOWLAB_IMAGE_IO_MODULE, scenes/CMakeLists.txt): image_io_oiio_table.cpp exports it from the
// module, image_io_module.cpp loads the module on first use and calls through it.
#include "image_io.h"

namespace shadowlab::image_io {

struct Table {
  int version;  // kTableVersion of the module; a mismatch is refused
  std::string (*writeExr)(const std::string& path, const FloatImage& image);
  std::string (*readExr)(const std::string& path, FloatImage& image);
  std::string (*writePng)(const std::string& path, int width, int height, int channels, const uint8_t* pixels,
                          bool unfiltered);
  std::string (*readTexture)(const std::string& path, FloatImage& image, int maxSide);
};
constexpr int kTableVersion = 2;  // 2: FloatImage::readPlanar

}  // namespace shadowlab::image_io

// The module's one exported symbol.
extern "C" const shadowlab::image_io::Table* shadowlab_image_io_table();
