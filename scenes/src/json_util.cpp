#include "json_util.h"

#include <algorithm>
#include <cmath>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"

namespace shadowlab::detail {

void lineColumn(const std::string& text, size_t byte, size_t& line, size_t& column) {
  size_t end = byte == 0 ? 0 : std::min(byte - 1, text.size());
  line = 1;
  size_t lineStart = 0;
  for (size_t i = 0; i < end; ++i)
    if (text[i] == '\n') {
      ++line;
      lineStart = i + 1;
    }
  column = end - lineStart + 1;
}

nlohmann::json parseJsonText(const std::string& text, const std::string& file) {
  try {
    return nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    size_t line = 0, column = 0;
    lineColumn(text, e.byte, line, column);
    // nlohmann's text is "[json.exception.parse_error.101] parse error at line L, column C: WHAT";
    // keep WHAT and put the place where GCC puts it.
    std::string what = e.what();
    size_t at = what.find("column ");
    if (at != std::string::npos) at = what.find(": ", at);
    if (at != std::string::npos) {
      what = what.substr(at + 2);
    } else if (what.rfind("[json.exception", 0) == 0 && what.find("] ") != std::string::npos) {
      what = what.substr(what.find("] ") + 2);
    }
    throw InputError(file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": error: " + what);
  }
}

nlohmann::json parseJsonFile(const std::string& path) { return parseJsonText(readFile(path), path); }

std::string describe(const nlohmann::json& j) {
  using T = nlohmann::json::value_t;
  switch (j.type()) {
    case T::string: {
      std::string s = j.get<std::string>();
      if (s.size() > 60) s = s.substr(0, 57) + "...";
      return nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    }
    case T::array:
      return "an array of " + std::to_string(j.size()) + (j.size() == 1 ? " value" : " values");
    case T::object:
      return "an object";
    case T::null:
      return "null";
    case T::number_float: {
      double d = j.get<double>();
      if (std::isnan(d)) return "NaN";
      if (std::isinf(d)) return d > 0 ? "inf (a number too large for a double)" : "-inf (a number too large for a double)";
      return j.dump();
    }
    default:
      return j.dump();
  }
}

std::string childPointer(const std::string& pointer, const std::string& key) {
  return (nlohmann::json::json_pointer(pointer) / key).to_string();
}

std::string childPointer(const std::string& pointer, size_t index) {
  return pointer + "/" + std::to_string(index);
}

}  // namespace shadowlab::detail
