#pragma once
// Frames compared float for float, for the tests that hold two renderings of one scene to the same
// bits (a glTF file against its OBJ or JSON twin, a mirrored node against its mirror image).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "shadowlab/scenes/frame.h"

namespace shadowlab::testing {

// Every channel of `b` equals `a`'s, float for float (NaN equal to NaN); returns the differing
// count, each differing channel a failure naming it.
inline size_t differingValues(const Frame& a, const Frame& b, const std::string& what) {
  EXPECT_EQ(a.names, b.names) << what;
  size_t differ = 0;
  for (const auto& name : a.names) {
    const auto& x = a.get(name);
    const auto& y = b.get(name);
    EXPECT_EQ(x.size(), y.size()) << what << " " << name;
    size_t here = 0;
    for (size_t i = 0; i < std::min(x.size(), y.size()); ++i)
      if (!(x[i] == y[i] || (std::isnan(x[i]) && std::isnan(y[i])))) ++here;
    EXPECT_EQ(here, 0u) << what << ": channel " << name << " differs in " << here << " pixels";
    differ += here;
  }
  return differ;
}

}  // namespace shadowlab::testing
