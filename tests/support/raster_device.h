#pragma once
// The one lavapipe device a raster test executable shares, with the validation layer on.
// Every raster test calls REQUIRE_DEVICE() first: without a Vulkan device it is SKIPPED, loudly,
// never passed. Fixtures that derive from ValidatedRasterTest fail any test after which the
// validation layer reported a message.
#include <gtest/gtest.h>

#include <cstdio>
#include <exception>
#include <memory>

#include "shadowlab/raster/raster.h"

namespace shadowlab::testing {

inline Rasterizer* rasterizer() {
  // Initialized in one expression: the static's destructor is registered after the device's
  // own exit handlers (Mesa's thread queues), so it runs before them at exit.
  static std::unique_ptr<Rasterizer> r = []() -> std::unique_ptr<Rasterizer> {
    try {
      RasterDeviceOptions o;
      o.validation = true;
      return std::make_unique<Rasterizer>(o);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "\n*** NO VULKAN DEVICE: raster tests are SKIPPED: %s ***\n\n", e.what());
      return nullptr;
    }
  }();
  return r.get();
}

class ValidatedRasterTest : public ::testing::Test {
 protected:
  void TearDown() override {
    if (Rasterizer* r = rasterizer()) {
      EXPECT_EQ(r->validationMessages(), 0) << "validation messages (printed above)";
    }
  }
};

}  // namespace shadowlab::testing

#define REQUIRE_DEVICE()                                               \
  ::shadowlab::Rasterizer* R = ::shadowlab::testing::rasterizer();     \
  if (!R) {                                                            \
    GTEST_SKIP() << "no Vulkan device (lavapipe) found: test NOT run"; \
  }
