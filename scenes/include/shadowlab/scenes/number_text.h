#pragma once
// Numbers in error messages, as the shortest text that reads back to the same value: "got 1e-07"
// where printf's %f would say "got 0.000000" and hide the value that was wrong. A float reads as
// the float it is (0.1f is "0.1", not 0.10000000149011612). Header-only, so that any library can
// name a number the same way. Output files keep their own formats (jsonFloat, json_reader.h).
#include <charconv>
#include <cmath>
#include <string>

namespace shadowlab {

template <typename T>
std::string numberText(T v) {
  if (std::isnan(v)) return "nan";  // to_chars may write "-nan", which says nothing more
  char text[64];
  const auto written = std::to_chars(text, text + sizeof text, v);
  return std::string(text, written.ptr);
}

}  // namespace shadowlab
