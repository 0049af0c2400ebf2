#pragma once
// Errors a user can act on. The message is complete and GCC-style, e.g.
//   scenes/contact.json:14:9: error: syntax error ...; expected string literal
//   scenes/contact.json: /lights/0/direction: error: got 2 numbers; expected 3 (x, y, z)
// The CLI prints what() verbatim and maps the type to the exit code:
//   InputError -> 2 (bad input or usage), DriverError -> 3 (internal/driver failure).
// Library code throws; it never calls exit().
//
// Messages quote what users wrote (tokens, OBJ lines, file names), and files and arguments can
// hold any bytes: both error types keep their message printable (printableText), so a Latin-1
// byte or an escape sequence in a file reaches the terminal as \xE9 or \x1B, never raw.
#include <stdexcept>
#include <string>

namespace shadowlab {

// `text` with each byte that is not part of valid UTF-8, and each control character (C0 other
// than the line feed that separates several errors, DEL, and the C1 controls U+0080..U+009F),
// written as \xNN (upper-case hex). Valid UTF-8 otherwise passes unchanged; a backslash is kept
// as it is, so applying it twice changes nothing.
std::string printableText(const std::string& text);

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(printableText(what)) {}
  explicit InputError(const char* what) : InputError(std::string(what)) {}
};

class DriverError : public std::runtime_error {
 public:
  explicit DriverError(const std::string& what) : std::runtime_error(printableText(what)) {}
  explicit DriverError(const char* what) : DriverError(std::string(what)) {}
};

// "file: place: error: what" (place may be empty: "file: error: what").
std::string formatError(const std::string& file, const std::string& place, const std::string& what);

}  // namespace shadowlab
