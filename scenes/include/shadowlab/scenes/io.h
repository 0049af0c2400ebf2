#pragma once
// Small file helpers shared by every writer: outputs are never left half-written.
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace shadowlab {

// Writes `bytes` to `path` through a temporary file in the same folder and a rename,
// so a reader (or an interrupted run) sees the old file or the whole new one.
// Throws InputError naming the path when the folder is missing or not writable.
void writeFileAtomic(const std::string& path, const std::string& bytes);
void writeJsonAtomic(const std::string& path, const nlohmann::json& j);  // pretty, 2 spaces, trailing \n

// Reads a whole file; throws InputError "<path>: error: cannot open file ..." when missing.
std::string readFile(const std::string& path);
// readFile of a file that must hold at most `maxBytes` (checked from its size before it is read,
// and again after, should it have grown or not be a regular file): InputError "<path>: error: N
// bytes; expected <what> of at most K KiB (maxBytes bytes)" beyond.
std::string readFileAtMost(const std::string& path, size_t maxBytes, const std::string& what);

// Escapes text for XML and HTML, in content and in quoted attribute values (& < > " ' as entities;
// control characters other than tab, CR and LF, which XML 1.0 does not allow, become '?'). Used by
// the gate's JUnit XML and the sweep's report.html.
std::string escapeMarkup(const std::string& text);

// Creates `dir` and its parents; throws InputError naming it when that fails.
void makeDirs(const std::string& dir);

// dir + "/" + name (no second slash where dir ends in one; name alone where dir is empty).
std::string joinPath(const std::string& dir, const std::string& name);

// A command's output folder, claimed before any work: the constructor creates it (and missing
// parents) and writes and removes a probe file there, so an unusable -o (under a file, under /proc,
// read-only, a full disk) is an input error naming `flag` and the folder before anything is traced
// or rendered. access() cannot tell: root passes it everywhere. Unless keep() is called, the
// destructor removes the folders the constructor created, if they are still empty, so a command
// that fails later leaves nothing behind.
class OutputFolder {
 public:
  OutputFolder(const std::string& dir, const std::string& flag = "-o");
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  void keep() { keep_ = true; }
  const std::string& path() const { return dir_; }

 private:
  void removeCreated();
  std::string dir_;
  std::vector<std::string> created_;  // innermost first
  bool keep_ = false;
};

// 64-bit FNV-1a (offset basis 0xcbf29ce484222325), printed as 16 lowercase hex digits. Used for
// scene and camera hashes; pass a previous hash as `seed` to continue hashing more bytes.
uint64_t fnv1a64(const void* data, size_t size, uint64_t seed = 14695981039346656037ull);
std::string hashHex(uint64_t h);

}  // namespace shadowlab
