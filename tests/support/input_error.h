#pragma once
// The message of the InputError a call throws, for tests that check what a user would read.
#include <gtest/gtest.h>

#include <string>

#include "shadowlab/scenes/error.h"

namespace shadowlab::testing {

// The what() of the InputError `f` throws; "" when it throws none (the test then fails here).
template <class F>
std::string inputErrorOf(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError";
  return "";
}

}  // namespace shadowlab::testing
