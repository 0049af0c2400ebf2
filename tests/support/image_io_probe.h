#pragma once
// The images tests/scenes_image_io_test.cpp exchanges between the two image_io.h implementations
// (the build's, linked into the test, and the other one, in the image_io_probe executable), and
// the JSON both sides print of what they read, with every float as its bit pattern so equal means
// identical.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image_io.h"

namespace shadowlab::testing {

// Channel names in an order EXR will not keep (it sorts them) and that OpenImageIO reorders on
// reading (colour, alpha and depth names first, layers last), with exact, negative, tiny and huge values.
inline image_io::FloatImage probeExr() {
  image_io::FloatImage im;
  im.width = 5;
  im.height = 3;
  im.channels = {"visibility", "Z", "depth", "B", "A", "G", "R", "Y", "alpha", "normal.x", "a", "zz", "AR", "r"};
  const size_t n = size_t(im.width) * im.height * im.channels.size();
  for (size_t i = 0; i < n; ++i) {
    const float v = float(i) * 0.37f - 7.0f;
    im.pixels.push_back(i % 7 == 3 ? std::ldexp(v, -120) : (i % 11 == 5 ? std::ldexp(v, 100) : v));
  }
  im.text["shadowlab:meta"] = R"({"scene":"probe","light":"sun","n":3})";
  im.text["shadowlab:channels"] = R"(["visibility","Z"])";
  return im;
}

// The same image handed to writeExr as planes (FloatImage::planes, what writeFrameExr does):
// `storage` keeps the planes alive; the file must read back exactly as probeExr() wrote.
inline image_io::FloatImage probeExrPlanar(std::vector<std::vector<float>>& storage) {
  image_io::FloatImage im = probeExr();
  const size_t channels = im.channels.size(), pixels = size_t(im.width) * im.height;
  storage.assign(channels, std::vector<float>(pixels));
  for (size_t i = 0; i < pixels; ++i)
    for (size_t c = 0; c < channels; ++c) storage[c][i] = im.pixels[i * channels + c];
  im.pixels.clear();
  for (const auto& plane : storage) im.planes.push_back(plane.data());
  return im;
}

// 8-bit un-associated pixels, alpha from 0 to 255 so that associating it changes most values.
inline std::vector<uint8_t> probePng(int width, int height, int channels) {
  std::vector<uint8_t> px;
  for (int i = 0; i < width * height * channels; ++i) px.push_back(uint8_t((i * 37 + 11) % 256));
  if (channels == 4) {
    for (int p = 0; p < width * height; ++p) px[size_t(p) * 4 + 3] = uint8_t(p * 255 / (width * height - 1));
  }
  return px;
}
constexpr int kProbePngWidth = 7, kProbePngHeight = 5;

inline nlohmann::json describe(const image_io::FloatImage& im, const std::string& error) {
  nlohmann::json j;
  j["error"] = error;
  j["width"] = im.width;
  j["height"] = im.height;
  j["channels"] = im.channels;
  // A planar read (FloatImage::readPlanar) is described as the interleaved one it must equal.
  std::vector<float> pixels = im.pixels;
  if (im.readPlanar) {
    const size_t n = size_t(im.width) * size_t(im.height), nc = im.planesRead.size();
    if (!im.pixels.empty()) j["error"] = error + " (a planar read filled the interleaved pixels too)";
    if (nc != im.channels.size()) j["error"] = error + " (a planar read returned " + std::to_string(nc) + " planes)";
    pixels.assign(n * nc, 0.0f);
    for (size_t c = 0; c < nc; ++c) {
      if (im.planesRead[c].size() != n) j["error"] = error + " (a plane of the wrong size)";
      for (size_t i = 0; i < n && i < im.planesRead[c].size(); ++i) pixels[i * nc + c] = im.planesRead[c][i];
    }
  }
  nlohmann::json bits = nlohmann::json::array();
  for (float v : pixels) {
    uint32_t b;
    std::memcpy(&b, &v, sizeof b);
    bits.push_back(b);
  }
  j["pixels"] = bits;
  nlohmann::json text = nlohmann::json::object();
  for (const auto& [k, v] : im.text)
    if (k.rfind("shadowlab:", 0) == 0) text[k] = v;  // each library adds its own standard attributes
  j["text"] = text;
  return j;
}

}  // namespace shadowlab::testing
