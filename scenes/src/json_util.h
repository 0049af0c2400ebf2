#pragma once
// Internal helpers for the scene and method parsers: JSON pointers for semantic errors and
// "got ..." descriptions of values. The reader itself (comments, duplicate keys, line:col) is
// public: shadowlab/scenes/json_reader.h.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace shadowlab::detail {

// 1-based line and column of the byte at 1-based offset `byte` (as nlohmann's parse_error::byte).
void lineColumn(const std::string& text, size_t byte, size_t& line, size_t& column);

// How a value reads in "got ..." messages: "abc" for strings, 1.5, true, null,
// "an array of 2 values", "an object".
std::string describe(const nlohmann::json& j);

// "/a/b" + key with RFC 6901 escaping; "" + 0 -> "/0".
std::string childPointer(const std::string& pointer, const std::string& key);
std::string childPointer(const std::string& pointer, size_t index);

// ' (did you mean "x"?)' for the closest choice within a small edit distance, else "".
std::string didYouMean(const std::string& got, const std::vector<std::string>& choices);

}  // namespace shadowlab::detail
