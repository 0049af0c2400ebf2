#pragma once
// The checks of an OBJ file before tinyobjloader reads it (scenes/FORMAT.md, "OBJ files"), with the
// line numbers tinyobjloader does not give: it skips a face of two corners or a bare "f", reads a
// missing coordinate as 0 and an out-of-range index as nothing, all without a word. Every line is
// checked against the table of statements in obj_reader.cpp; the first bad one is an InputError
// "file.obj:LINE: error: what; expected ...".
#include <cstdint>
#include <string>
#include <vector>

namespace shadowlab::obj {

struct ObjText {
  // What tinyobjloader reads: the file's lines, without a byte order mark and without the
  // comments after geometry statements (tinyobjloader reads "# ..." after a face as a corner).
  std::string text;
  // Each face ("f" line) in file order, the order of tinyobjloader's shapes: its line and corners.
  std::vector<int> faceLine;
  std::vector<uint32_t> faceCorners;
};

// Reads `path` (a regular file) and checks every line; throws InputError at the first bad one.
ObjText scanObj(const std::string& path);

// "path:LINE: error: what" (no line when `line` is 0).
[[noreturn]] void objError(const std::string& path, int line, const std::string& what);

}  // namespace shadowlab::obj
