#include "json_util.h"
#include "shadowlab/scenes/json_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

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

namespace {

// nlohmann's DOM builder, but recording where parsing stopped instead of throwing: a number
// overflow (1e999) is reported through the same hook as syntax errors, with its position,
// which the thrown out_of_range exception would lose. It also refuses a key an object already
// has (nlohmann keeps the last one silently), naming the object by its JSON pointer.
template <class Json>
struct PositionedDomParser : nlohmann::detail::json_sax_dom_parser<Json> {
  using Base = nlohmann::detail::json_sax_dom_parser<Json>;
  using typename Base::number_float_t;
  using typename Base::number_integer_t;
  using typename Base::number_unsigned_t;
  using typename Base::string_t;
  explicit PositionedDomParser(Json& result) : Base(result, /*allow_exceptions=*/false) {}

  // Where the parser is: one entry per open object or array, with the child being read.
  struct Open {
    bool array = false;
    size_t count = 0;  // arrays: values begun so far
    std::string key;   // objects: the current key
    std::set<std::string> keys;
  };
  std::vector<Open> open;
  bool duplicate = false;
  std::string duplicatePointer, duplicateKey;

  void beginValue() {
    if (!open.empty() && open.back().array) ++open.back().count;
  }
  std::string pointer() const {
    std::string p;
    for (size_t i = 0; i + 1 < open.size(); ++i)
      p = open[i].array ? childPointer(p, open[i].count - 1) : childPointer(p, open[i].key);
    return p;
  }
  bool null() { return beginValue(), Base::null(); }
  bool boolean(bool v) { return beginValue(), Base::boolean(v); }
  bool number_integer(number_integer_t v) { return beginValue(), Base::number_integer(v); }
  bool number_unsigned(number_unsigned_t v) { return beginValue(), Base::number_unsigned(v); }
  bool number_float(number_float_t v, const string_t& s) { return beginValue(), Base::number_float(v, s); }
  bool string(string_t& v) { return beginValue(), Base::string(v); }
  bool start_object(std::size_t n) {
    beginValue();
    open.push_back(Open{});
    return Base::start_object(n);
  }
  bool end_object() {
    open.pop_back();
    return Base::end_object();
  }
  bool start_array(std::size_t n) {
    beginValue();
    Open a;
    a.array = true;
    open.push_back(a);
    return Base::start_array(n);
  }
  bool end_array() {
    open.pop_back();
    return Base::end_array();
  }
  bool key(string_t& k) {
    if (!open.back().keys.insert(k).second) {
      duplicate = true;
      duplicatePointer = pointer();
      duplicateKey = k;
      return false;
    }
    open.back().key = k;
    return Base::key(k);
  }

  template <class Exception>
  bool parse_error(std::size_t position, const std::string& lastToken, const Exception& ex) {
    errorByte = position;
    errorToken = lastToken;
    errorId = ex.id;
    errorText = ex.what();
    return false;
  }
  std::size_t errorByte = 0;
  std::string errorToken;
  int errorId = 0;
  std::string errorText;
};

template <class Json>
Json parseStrict(const std::string& text, const std::string& file) {
  Json result;
  PositionedDomParser<Json> sax(result);
  bool ok = Json::sax_parse(text, &sax, nlohmann::json::input_format_t::json, /*strict=*/true,
                            /*ignore_comments=*/true);
  if (ok) return result;
  if (sax.duplicate) {
    throw InputError(file + ": " + childPointer(sax.duplicatePointer, sax.duplicateKey) + ": error: key " +
                     nlohmann::json(sax.duplicateKey).dump() +
                     " appears twice in one object; expected each key once (JSON would keep only the last)");
  }
  std::string what = sax.errorText;
  size_t byte = sax.errorByte;
  // nlohmann's text is "[json.exception.parse_error.101] parse error at line L, column C: WHAT";
  // keep WHAT and put the place where GCC puts it.
  size_t at = what.find("column ");
  if (at != std::string::npos) at = what.find(": ", at);
  if (at != std::string::npos) {
    what = what.substr(at + 2);
  } else if (what.rfind("[json.exception", 0) == 0 && what.find("] ") != std::string::npos) {
    what = what.substr(what.find("] ") + 2);
  }
  // nlohmann's position is the last character it read (one past a number); GCC points at the
  // start of the offending token, so find the token just before that position. nlohmann's "last
  // read" text can run over the tokens before it ('"pcf", }', '"distance": N'): the offending
  // token is its last string, or else its last run after whitespace.
  if (!sax.errorToken.empty() && byte > 0) {
    size_t limit = std::min(byte, text.size());
    size_t start = text.rfind(sax.errorToken, limit > 0 ? limit - 1 : 0);
    if (start != std::string::npos && start + sax.errorToken.size() + 2 >= limit) {
      const std::string& t = sax.errorToken;
      size_t offset = 0;
      if (t.size() >= 2 && t.back() == '"') {
        size_t open = t.rfind('"', t.size() - 2);
        offset = open == std::string::npos ? 0 : open;
      } else {
        size_t space = t.find_last_of(" \t\r\n");
        offset = space == std::string::npos ? 0 : space + 1;
      }
      byte = start + offset + 1;
    }
  }
  // nlohmann quotes the text it last read ("; last read: '...'"): never echo a file's bytes (a
  // scene named by a pull request may be any file on the machine); line:col says where.
  const size_t quoted = what.find("; last read");
  if (quoted != std::string::npos) what.erase(quoted);
  // nlohmann joins "while parsing X - detail" with a dash; the house style uses "; ".
  size_t dash = what.find(" - ");
  if (dash != std::string::npos) what.replace(dash, 3, "; ");
  if (sax.errorId == 406) what += "; expected a finite number (NaN and infinity are not allowed)";
  size_t line = 0, column = 0;
  lineColumn(text, byte, line, column);
  throw InputError(file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": error: " + what);
}

}  // namespace

std::string describe(const nlohmann::json& j) {
  using T = nlohmann::json::value_t;
  switch (j.type()) {
    case T::string: {
      std::string s = j.get<std::string>();
      if (s.size() > 60) s = s.substr(0, 57) + "...";
      return nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    }
    case T::array: return "an array of " + std::to_string(j.size()) + (j.size() == 1 ? " value" : " values");
    case T::object: return "an object";
    case T::null: return "null";
    case T::number_float: {
      double d = j.get<double>();
      if (std::isnan(d)) return "NaN";
      if (std::isinf(d))
        return d > 0 ? "inf (a number too large for a double)" : "-inf (a number too large for a double)";
      return j.dump();
    }
    default: return j.dump();
  }
}

std::string childPointer(const std::string& pointer, const std::string& key) {
  return (nlohmann::json::json_pointer(pointer) / key).to_string();
}

std::string childPointer(const std::string& pointer, size_t index) { return pointer + "/" + std::to_string(index); }

std::string didYouMean(const std::string& got, const std::vector<std::string>& choices) {
  // Levenshtein distance; a typo is at most 2 edits and less than half the word.
  auto distance = [](const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
      size_t diag = row[0];
      row[0] = i;
      for (size_t j = 1; j <= b.size(); ++j) {
        size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diag = up;
      }
    }
    return row[b.size()];
  };
  std::string best;
  size_t bestDistance = 3;
  for (const auto& c : choices) {
    size_t d = distance(got, c);
    if (d < bestDistance && 2 * d < std::max(got.size(), c.size())) {
      bestDistance = d;
      best = c;
    }
  }
  return best.empty() ? "" : " (did you mean \"" + best + "\"?)";
}

}  // namespace shadowlab::detail

namespace shadowlab {

std::string describeJson(const nlohmann::json& v) { return detail::describe(v); }

std::string dumpJson(const nlohmann::json& v) {
  return v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

nlohmann::json jsonFloat(float v) {
  if (!std::isfinite(v)) return nullptr;
  // std::to_chars without a format gives the fewest digits that read back to `v` as a float;
  // std::from_chars then gives the double nearest that decimal, whose shortest text (nlohmann's
  // dump) is those same digits.
  char text[64];
  const auto written = std::to_chars(text, text + sizeof text, v);
  double d = double(v);
  std::from_chars(text, written.ptr, d);
  return d;
}

nlohmann::json parseJsonText(const std::string& text, const std::string& file) {
  return detail::parseStrict<nlohmann::json>(text, file);
}

nlohmann::ordered_json parseOrderedJsonText(const std::string& text, const std::string& file) {
  return detail::parseStrict<nlohmann::ordered_json>(text, file);
}

nlohmann::json readJsonFile(const std::string& path) { return parseJsonText(readFile(path), path); }

namespace {
template <class Json>
std::string typeNameOf(const Json& v) {
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_boolean()) return "a boolean";
  if (v.is_null()) return "null";
  if (v.is_array()) return "an array";
  return "an object";
}
}  // namespace

std::string jsonTypeName(const nlohmann::json& v) { return typeNameOf(v); }
std::string jsonTypeName(const nlohmann::ordered_json& v) { return typeNameOf(v); }

std::string jsonPointerToken(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}

}  // namespace shadowlab
