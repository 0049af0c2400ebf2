// The module's export (image_io_table.h): the OpenImageIO implementation's functions. Everything
// else in the module is hidden (CXX_VISIBILITY_PRESET hidden), so its calls never bind to the
// program's forwarders of the same names (image_io_module.cpp).
#include "image_io_table.h"

extern "C" __attribute__((visibility("default"))) const shadowlab::image_io::Table* shadowlab_image_io_table() {
  namespace io = shadowlab::image_io;
  static const io::Table table{io::kTableVersion, &io::writeExr, &io::readExr, &io::writePng, &io::readTexture};
  return &table;
}
