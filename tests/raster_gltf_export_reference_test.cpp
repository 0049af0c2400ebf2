// The rasterizer draws an exported scene as it draws the scene it came from: every bundled scene,
// exported to .glb (shadowlab export) and loaded back, gives the same raster channels bit for bit
// under the default method, for each of its lights (projectors, which glTF does not carry, left
// out of both). tests/reference_gltf_export_test.cpp checks the truth the same way.
#include <gtest/gtest.h>

#include <filesystem>

#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/gltf_export.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"
#include "support/cli.h"
#include "support/raster_device.h"
#include "support/same_frames.h"

namespace raster_gltf_export_reference_test {

namespace fs = std::filesystem;
using namespace shadowlab;

using GltfExportRaster = shadowlab::testing::ValidatedRasterTest;

TEST_F(GltfExportRaster, EveryBundledSceneRastersTheSameAfterARoundTrip) {
  REQUIRE_DEVICE();
  const fs::path dir = shadowlab::testing::freshTempDir("gltf_export_raster");
  for (const std::string& name : bundledSceneNames()) {
    SCOPED_TRACE(name);
    Scene a = loadScene(resolveScenePath(name), {{"/camera/width", 160}, {"/camera/height", 90}});
    a.projectors.clear();
    const std::string glb = (dir / (name + ".glb")).string();
    writeFileAtomic(glb, exportGlb(a, "shadowlab test").glb);
    const Scene b = loadScene(glb);
    for (const Light& l : a.lights) {
      const Frame fa = R->render(a, Method{}, l.name), fb = R->render(b, Method{}, l.name);
      EXPECT_EQ(shadowlab::testing::differingValues(fa, fb, name + " raster " + l.name), 0u);
    }
  }
}

}  // namespace raster_gltf_export_reference_test
