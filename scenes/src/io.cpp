#include "shadowlab/scenes/io.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <unistd.h>

#include "shadowlab/scenes/error.h"

namespace shadowlab {

namespace fs = std::filesystem;

namespace {

// A temp name in the same folder as `path` (rename is only atomic within one filesystem),
// unique per process and call so parallel writers of different outputs never collide.
std::string tempPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  fs::path p(path);
  std::string stem =
      "." + p.filename().string() + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  return (p.parent_path() / stem).string();
}

}  // namespace

void writeFileAtomic(const std::string& path, const std::string& bytes) {
  fs::path parent = fs::path(path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent))
    throw InputError(formatError(path, "", "cannot write file: folder " + parent.string() + " does not exist"));
  std::string tmp = tempPathFor(path);
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError(formatError(path, "", std::string("cannot write file: ") + std::strerror(errno)));
  size_t written = bytes.empty() ? 0 : std::fwrite(bytes.data(), 1, bytes.size(), f);
  bool ok = written == bytes.size();
  ok = (std::fflush(f) == 0) && ok;
  // Data on disk before the rename publishes it: after a crash the name holds the old file or
  // the whole new one, never an empty one.
  ok = (::fdatasync(::fileno(f)) == 0) && ok;
  int err = errno;
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) {
    std::remove(tmp.c_str());
    throw InputError(formatError(path, "", std::string("cannot write file: ") + std::strerror(err)));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    err = errno;
    std::remove(tmp.c_str());
    throw InputError(formatError(path, "", std::string("cannot write file: ") + std::strerror(err)));
  }
}

void writeJsonAtomic(const std::string& path, const nlohmann::json& j) { writeFileAtomic(path, j.dump(2) + "\n"); }

std::string readFile(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(formatError(path, "", "cannot open file: it is a folder"));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(formatError(path, "", std::string("cannot open file: ") + std::strerror(errno)));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(formatError(path, "", "cannot read file"));
  return ss.str();
}

std::string readFileAtMost(const std::string& path, size_t maxBytes, const std::string& what) {
  auto tooLarge = [&](uintmax_t size) {
    return InputError(formatError(path, "",
                                  std::to_string(size) + " bytes; expected " + what + " of at most " +
                                      std::to_string(maxBytes / 1024) + " KiB (" + std::to_string(maxBytes) +
                                      " bytes)"));
  };
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (!ec && size > maxBytes) throw tooLarge(size);
  std::string bytes = readFile(path);
  if (bytes.size() > maxBytes) throw tooLarge(bytes.size());
  return bytes;
}

void makeDirs(const std::string& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(
        formatError(dir, "", "cannot create folder: " + (ec ? ec.message() : std::string("not a folder"))));
}

OutputFolder::OutputFolder(const std::string& dir, const std::string& flag) : dir_(dir) {
  if (dir.empty()) throw InputError(flag + ": error: the output folder is empty; expected a folder");
  std::error_code ec;
  // The folders that do not exist yet, innermost first, to remove them again on failure.
  for (fs::path p = fs::absolute(dir, ec).lexically_normal(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created_.push_back(p.string());
    if (p == p.parent_path()) break;
  }
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(formatError(dir, "", "exists and is not a folder; expected an output folder for " + flag));
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir, ec)) {
    created_.clear();  // nothing of ours to remove
    throw InputError(formatError(
        dir, "",
        "cannot create the output folder for " + flag + ": " + (ec ? ec.message() : std::string("not a folder"))));
  }
  const std::string probe = tempPathFor((fs::path(dir) / "probe").string());
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  int err = errno;
  bool ok = f && std::fputc('x', f) != EOF;
  if (f) ok = (std::fclose(f) == 0) && ok, err = ok ? 0 : errno;
  std::remove(probe.c_str());
  if (!ok) {
    removeCreated();
    throw InputError(formatError(
        dir, "", "cannot write into the output folder for " + flag + ": " + std::strerror(err ? err : EIO)));
  }
}

void OutputFolder::removeCreated() {
  std::error_code ec;
  for (const std::string& p : created_) fs::remove(p, ec);  // only removes empty folders
  created_.clear();
}

OutputFolder::~OutputFolder() {
  if (!keep_) removeCreated();
}

uint64_t fnv1a64(const void* data, size_t size, uint64_t seed) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  uint64_t h = seed;
  for (size_t i = 0; i < size; ++i) {
    h ^= bytes[i];
    h *= 1099511628211ull;
  }
  return h;
}

std::string hashHex(uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string escapeMarkup(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') out += '?';
        else out += c;
    }
  }
  return out;
}

std::string joinPath(const std::string& dir, const std::string& name) {
  if (dir.empty()) return name;
  return dir.back() == '/' ? dir + name : dir + "/" + name;
}

}  // namespace shadowlab
