#pragma once
// Every method key as the parser knows it (`shadowlab methods` lists these), built from the
// parser's own table (scenes/src/method.cpp's setters), so the listing cannot drift from what
// method files, --set and --grid accept. A new key is a new row there (its parser and one line of
// help); its default comes from Method{} and its range from the parser's "expected ...".
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace shadowlab {

struct MethodKeyInfo {
  std::string key;
  std::string type;             // integer, number, boolean, choice or string
  nlohmann::json defaultValue;  // Method{}'s, as methodToJson writes it
  std::string range;            // the parser's "expected ...", e.g. "an integer 16..16384 (...)"
  std::string help;             // one line
};

// "name" first, then methodKeys()' order.
const std::vector<MethodKeyInfo>& methodKeyTable();

}  // namespace shadowlab
