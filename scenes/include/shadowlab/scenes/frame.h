#pragma once
// The per-pixel output contract between the renderers and compare.
//
// A Frame is width x height pixels with named float32 channels (row 0 at the top) and a JSON
// metadata object. It round-trips through EXR (one EXR channel per Frame channel, read back by
// name: EXR sorts channels) with the metadata stored as the string attribute "shadowlab:meta".
// Ids are stored as floats: exact below 2^24.
//
// Channel names (LIGHT and PROJ are the scene's light/projector names):
//   both renderers
//     hit                      1 where the camera ray hits geometry, else 0
//     object_id                Object::id of the visible surface, 0 where no hit
//     prim_id                  triangle index within that object, 0 where no hit (reference: All set only)
//     light.LIGHT.vis          visibility of LIGHT at the visible point in [0, 1] (1 = lit);
//                              for spot lights 0 outside the cone. 0 where no hit.
//     proj.PROJ.coverage       projector coverage in [0, 1]: in front of it, inside its frustum,
//                              unoccluded from it
//     proj.PROJ.R|G|B          projected color (0 where not covered)
//   reference only (reference/); P, N and u|v only in its All channel set (reference/README.md)
//     P.x P.y P.z              world-space hit point
//     N.x N.y N.z              unit geometric normal, facing the camera
//     light.LIGHT.occluder_dist  world distance from the point to the nearest occluder along the
//                              shadow ray, -1 where unoccluded (for spp > 1: of the center sample;
//                              for a sized light: of the ray toward the light's center)
//     light.LIGHT.vis_sigma    sized lights only (Light::sized()): the standard error of vis, a
//                              conservative bound (reference/README.md, "Sized lights"); 0 where
//                              vis is exact (no hit, outside a spot's cone, inside the light)
//     proj.PROJ.u|v            projective texture coordinate (before the frustum test)
//   rasterizer only (raster/), for the one light it rendered
//     light.LIGHT.receiver_depth  the visible point's depth in the light's map space, [0,1]
//     light.LIGHT.map_depth    depth stored in the map at the center texel of the lookup
//     light.LIGHT.occluder_id  object id that wrote the center texel (0: nothing, cleared texel)
//     light.LIGHT.occluder_prim  primitive id that wrote the center texel (0 in a partial frame
//                              whose meta says "occluder_prim": "unresolved")
//     light.LIGHT.in_map       1 where the lookup falls inside the map (and in front of the light)
//     light.LIGHT.m            texel footprint: largest extent of one map texel on screen, pixels
//     light.LIGHT.bias_depth   total effective bias at this pixel in map depth units (compare bias
//                              + rasterizer depth bias + normal offset's depth change)
//     light.LIGHT.bias_world   the same bias as a world-space distance along the light ray
//     light.LIGHT.cascade      the cascade (map layer) the lookup used, 0-based, picked by the
//                              point's view depth (fit=cascades); 0 for every other fit and light
//                              type, and where no hit
//     proj.PROJ.reverse        1 where the point is behind the projector (w < 0) but its divided
//                              coordinates land in [0,1]^2: what reverse projection would colour
//
// Metadata keys (meta): "kind" ("reference" | "raster" | "outside": a frame rendered by another
// program, scenes/FRAME-CONTRACT.md, with "renderer" and "coverage"), "scene" (name), "scene_hash",
// "camera_hash", "width", "height", "lights" (names), "projectors" (names); raster adds
// "light" (the light it rendered), "method" (resolved method JSON), "device"; frames rendered with
// evidence on demand (raster.h) add "evidence" ("partial" when only the listed pixels' evidence is
// there), "evidence_pixels" and "evidence_group" (the configurations whose hit, ids, m and cascade
// planes are the same: compare's CompareContext keys on it).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace shadowlab {

struct Frame {
  int width = 0;
  int height = 0;
  std::vector<std::string> names;        // channel names, in insertion order
  std::vector<std::vector<float>> data;  // one width*height plane per name
  nlohmann::json meta = nlohmann::json::object();

  bool has(const std::string& name) const;
  // Adds a channel filled with `fill` (or returns the existing one) and returns its plane, valid until the next add().
  std::vector<float>& add(const std::string& name, float fill = 0.0f);
  // Throws InputError "frame has no channel NAME" when absent.
  const std::vector<float>& get(const std::string& name) const;
  std::vector<float>& get(const std::string& name);
  size_t pixelCount() const { return size_t(width) * size_t(height); }
};

// EXR (float32 channels, ZIPS compression at zlib level 1; any EXR reads back), written atomically. Throws InputError
// naming the path on failure.
void writeFrameExr(const Frame& frame, const std::string& path);
Frame readFrameExr(const std::string& path);

// How a PNG's rows are prepared for zlib. Adaptive: libpng picks one of five filters per row
// (OpenImageIO's default; best for shaded pictures such as raster.png). Unfiltered: none, for
// pictures of flat colour areas (errors.png, the triptychs): a sweep report's 5792x1256 triptych
// is written in 76 ms instead of 194 ms, at about the same size (148 KB against 152 KB; a calmer
// one 52 KB against 38 KB; compare/SWEEPS.md, "The report's time"). The pixels are the same.
enum class PngRows { Adaptive, Unfiltered };

// 8-bit sRGB-ish picture writer (PNG by extension), atomic. rgb is width*height*3 bytes.
void writeRgbPng(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb,
                 PngRows rows = PngRows::Adaptive);

// For a command sure to read or write images soon (the sweep runner, for its references): starts
// loading the image library on a thread of its own where it is a module loaded on first use
// (OpenImageIO for EXR too: -DSHADOWLAB_IMAGE_IO_MODULE=ON without OpenEXR and libpng,
// scenes/src/image_io_module.cpp); nothing to do where EXR and PNG are linked (the default).
void preloadImageLibrary();

}  // namespace shadowlab
