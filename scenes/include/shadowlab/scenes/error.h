#pragma once
// Errors a user can act on. The message is complete and GCC-style, e.g.
//   scenes/contact.json:14:9: error: syntax error ...; expected string literal
//   scenes/contact.json: /lights/0/direction: error: got 2 numbers; expected 3 (x, y, z)
// The CLI prints what() verbatim and maps the type to the exit code:
//   InputError -> 2 (bad input or usage), DriverError -> 3 (internal/driver failure).
// Library code throws; it never calls exit().
#include <stdexcept>
#include <string>

namespace shadowlab {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class DriverError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "file: place: error: what" (place may be empty: "file: error: what").
std::string formatError(const std::string& file, const std::string& place, const std::string& what);

}  // namespace shadowlab
