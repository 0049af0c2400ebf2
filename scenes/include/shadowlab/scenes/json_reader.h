#pragma once
// The one JSON reader of every file the project reads (scene, method, sweep, tolerance, results,
// metrics and baseline files), so they all keep the same promises:
// - comments (// and /* */) are allowed;
// - a key given twice in one object is an InputError "file: /pointer/key: error: key ... appears
//   twice ..." (nlohmann alone keeps the last one silently);
// - a syntax error is an InputError "file:line:col: error: ..." pointing at the offending token,
//   never nlohmann's raw exception text;
// - NaN, infinity and numbers too large for a double are refused with their place.
// Semantic errors are then reported by the caller as "file: /json/pointer: error: got X; expected Y"
// (formatError in error.h), X from jsonTypeName.
#include <string>

#include <nlohmann/json.hpp>

namespace shadowlab {

// Parses `text` read from `file` (`file` only names it in messages).
nlohmann::json parseJsonText(const std::string& text, const std::string& file);
// The same, keeping the keys in the order written (e.g. a sweep's grid axes).
nlohmann::ordered_json parseOrderedJsonText(const std::string& text, const std::string& file);
// readFile + parseJsonText.
nlohmann::json readJsonFile(const std::string& path);

// What a value is, for "got X; expected Y" messages: "a number", "a string", "a boolean", "null",
// "an array", "an object".
std::string jsonTypeName(const nlohmann::json& v);
std::string jsonTypeName(const nlohmann::ordered_json& v);

// The one describer of "got X; expected Y" messages: strings quoted (cut at 60 characters, any
// bytes safe), numbers as written (NaN, inf named), true/false/null, "an array of 3 values",
// "an object" (never a whole document dumped into a message).
std::string describeJson(const nlohmann::json& v);

// v.dump() that never throws: bytes that are not UTF-8 (which a command-line argument may hold,
// though no parsed file can) become U+FFFD instead of nlohmann's type_error 316.
std::string dumpJson(const nlohmann::json& v);

// A float as the JSON number a person would write for it: the double of the shortest decimal that
// reads back to the same float (0.0005f -> 0.0005, where the float widened to a double prints
// 0.0005000000237487257); null for NaN and infinities. Every float that enters an output file
// goes through it (methodToJson: metrics.json, results.json/csv, raster.json, tuned.json), and
// reading the number back as a float gives the same float.
nlohmann::json jsonFloat(float v);

// One reference token of a JSON pointer (RFC 6901: "~" -> "~0", "/" -> "~1"), for keys such as
// "scene:/a/b" that hold slashes.
std::string jsonPointerToken(const std::string& key);

}  // namespace shadowlab
