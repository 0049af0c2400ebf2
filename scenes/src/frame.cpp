// Frame <-> EXR through image_io.h (OpenImageIO, or OpenEXR + libpng). EXR stores channels sorted
// by name, so reading goes by name, never by position; the insertion order is kept in a second
// attribute so a round trip returns the very same Frame.
#include "shadowlab/scenes/frame.h"

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include <fcntl.h>
#include <unistd.h>

#include "image_io.h"
#include "shadowlab/scenes/error.h"

namespace shadowlab {

namespace fs = std::filesystem;

namespace {

constexpr const char* kMetaAttribute = "shadowlab:meta";
constexpr const char* kOrderAttribute = "shadowlab:channels";

// Temp file beside `path` with the same extension (OpenImageIO picks the format by extension).
std::string tempImagePath(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  fs::path p(path);
  std::string name = "." + p.stem().string() + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++) +
                     p.extension().string();
  return (p.parent_path() / name).string();
}

void checkFolder(const std::string& path) {
  fs::path parent = fs::path(path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent))
    throw InputError(formatError(path, "", "cannot write file: folder " + parent.string() + " does not exist"));
}

// Writes through `write(tmp)` then renames; the temp file never survives a failure.
template <class WriteFn>
void writeImageAtomic(const std::string& path, WriteFn&& write) {
  checkFolder(path);
  std::string tmp = tempImagePath(path);
  std::string err = write(tmp);
  if (err.empty()) {
    // The writer closed the file; flush it to disk before the rename publishes it.
    int fd = ::open(tmp.c_str(), O_RDONLY);
    if (fd < 0 || ::fdatasync(fd) != 0) err = "cannot flush the temporary file";
    if (fd >= 0) ::close(fd);
  }
  if (err.empty() && std::rename(tmp.c_str(), path.c_str()) != 0) err = "cannot rename the temporary file";
  if (!err.empty()) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw InputError(formatError(path, "", "cannot write image: " + err));
  }
}

}  // namespace

bool Frame::has(const std::string& name) const {
  for (const auto& n : names)
    if (n == name) return true;
  return false;
}

std::vector<float>& Frame::add(const std::string& name, float fill) {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return data[i];
  names.push_back(name);
  data.emplace_back(pixelCount(), fill);
  return data.back();
}

const std::vector<float>& Frame::get(const std::string& name) const {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return data[i];
  throw InputError("frame has no channel " + name);
}

std::vector<float>& Frame::get(const std::string& name) {
  return const_cast<std::vector<float>&>(static_cast<const Frame&>(*this).get(name));
}

void writeFrameExr(const Frame& frame, const std::string& path) {
  if (frame.width <= 0 || frame.height <= 0)
    throw InputError(formatError(
        path, "",
        "cannot write an empty frame (" + std::to_string(frame.width) + "x" + std::to_string(frame.height) + ")"));
  if (frame.names.empty()) throw InputError(formatError(path, "", "cannot write a frame with no channels"));
  if (frame.data.size() != frame.names.size())
    throw DriverError(formatError(path, "",
                                  "frame has " + std::to_string(frame.names.size()) + " names but " +
                                      std::to_string(frame.data.size()) + " planes"));
  const size_t pixels = frame.pixelCount();
  const size_t channels = frame.names.size();
  for (size_t c = 0; c < channels; ++c) {
    if (frame.data[c].size() != pixels)
      throw DriverError(formatError(path, "",
                                    "channel " + frame.names[c] + " has " + std::to_string(frame.data[c].size()) +
                                        " values; expected " + std::to_string(pixels)));
    for (size_t k = 0; k < c; ++k)
      if (frame.names[k] == frame.names[c])
        throw DriverError(formatError(path, "", "duplicate channel " + frame.names[c]));
  }
  image_io::FloatImage image;
  image.width = frame.width;
  image.height = frame.height;
  image.channels = frame.names;
  // The planes go to the writer as they are: no interleaved copy of the whole frame.
  for (size_t c = 0; c < channels; ++c) image.planes.push_back(frame.data[c].data());
  image.text[kMetaAttribute] = frame.meta.dump();
  image.text[kOrderAttribute] = nlohmann::json(frame.names).dump();
  writeImageAtomic(path, [&](const std::string& tmp) { return image_io::writeExr(tmp, image); });
}

Frame readFrameExr(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(formatError(path, "", "cannot open file: no such file"));
  image_io::FloatImage image;
  image.readPlanar = true;  // the frame's planes as read: no interleaved copy
  const std::string err = image_io::readExr(path, image);
  if (!err.empty()) throw InputError(formatError(path, "", "cannot read image: " + err));
  const int channels = int(image.channels.size());
  if (image.planesRead.size() != image.channels.size())
    throw InputError(formatError(path, "", "cannot read image: the reader returned no planes"));
  auto text = [&](const char* name) {
    auto it = image.text.find(name);
    return it == image.text.end() ? std::string() : it->second;
  };

  Frame frame;
  frame.width = image.width;
  frame.height = image.height;
  std::string metaText = text(kMetaAttribute);
  if (!metaText.empty()) {
    frame.meta = nlohmann::json::parse(metaText, nullptr, false);
    if (frame.meta.is_discarded())
      throw InputError(formatError(path, std::string(kMetaAttribute), "attribute is not valid JSON"));
  }
  // The file's order is EXR's sorted order; restore the writer's insertion order when recorded.
  std::map<std::string, int> fileIndex;
  for (int c = 0; c < channels; ++c) fileIndex[image.channels[c]] = c;
  std::vector<std::string> order;
  nlohmann::json recorded = nlohmann::json::parse(text(kOrderAttribute), nullptr, false);
  if (recorded.is_array() && recorded.size() == fileIndex.size()) {
    std::set<std::string> seen;  // the recorded order is used only when it names every channel once
    for (const auto& n : recorded)
      if (n.is_string() && fileIndex.count(n.get<std::string>()) && seen.insert(n.get<std::string>()).second)
        order.push_back(n.get<std::string>());
  }
  if (order.size() != fileIndex.size()) {
    order.clear();
    for (int c = 0; c < channels; ++c) order.push_back(image.channels[c]);
  }
  const size_t pixels = frame.pixelCount();
  for (const auto& name : order) {
    std::vector<float>& plane = image.planesRead[size_t(fileIndex.at(name))];
    if (plane.size() != pixels)
      throw InputError(formatError(path, name, "channel has " + std::to_string(plane.size()) + " values; expected " +
                                                   std::to_string(pixels)));
    frame.names.push_back(name);
    frame.data.push_back(std::move(plane));
  }
  return frame;
}

void writeRgbPng(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb, PngRows rows) {
  if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * size_t(height) * 3)
    throw DriverError(formatError(path, "",
                                  "picture is " + std::to_string(width) + "x" + std::to_string(height) + " with " +
                                      std::to_string(rgb.size()) + " bytes; expected w*h*3"));
  writeImageAtomic(path, [&](const std::string& tmp) {
    return image_io::writePng(tmp, width, height, 3, rgb.data(), rows == PngRows::Unfiltered);
  });
}

void preloadImageLibrary() { image_io::preload(); }

}  // namespace shadowlab
