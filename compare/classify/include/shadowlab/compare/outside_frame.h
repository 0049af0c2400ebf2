#pragma once
// Frames rendered by another program (three.js, Babylon.js, Godot, an in-house engine): the door
// through which they come into compare (scenes/FRAME-CONTRACT.md is the renderer author's page).
// An outside frame is an image of the shadow term alone for the scene's camera, read here into a
// Frame like the rasterizer's (meta "kind": "outside"), so that everything after it (compare, the
// pictures, metrics.json, the gate) treats it as any other frame.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/declared_renderer.h"
#include "shadowlab/scenes/frame.h"

namespace shadowlab {

// The largest side of an outside image, pixels: a file cannot ask for more work than this.
constexpr int kMaxOutsideImageSide = 16384;

// The renderer JSON (`--renderer FILE.json`, scenes/FRAME-CONTRACT.md "The renderer JSON"), read
// through the one JSON reader (json_reader.h): syntax errors at file:line:col, everything else at
// its JSON pointer, unknown keys refused. Throws InputError.
DeclaredRenderer readDeclaredRenderer(const std::string& path);

// One channel of an image file, as floats, row 0 at the top.
struct ImagePlane {
  int width = 0, height = 0;
  std::string channel;        // the channel read ("Y", "R", ..., or the EXR channel's name)
  std::string description;    // "16-bit RGBA PNG", "EXR", for messages
  std::vector<float> values;  // width * height
};

// Reads one channel of a PNG (8 or 16 bits; grey "Y", grey+alpha "Y" "A", RGB "R" "G" "B", RGBA;
// a palette counts as RGB(A)) or an EXR (any channel, by name). PNG values are code / (2^bits - 1):
// linear, no sRGB or gAMA decoding, alpha not multiplied in. `channel` "" picks: a grey PNG's Y, an
// RGB(A) PNG's R when R = G = B at every pixel (else a colour image must name its channel), an
// EXR's "vis" or its only channel. Throws InputError naming `path` and the channel: no such
// channel, an unreadable file, a side beyond kMaxOutsideImageSide, and (EXR) a value that is not
// finite, named at its first pixel. `checkSize(width, height)`, when given, is called as soon as
// the size is known (a PNG: from its header, before any pixel is decoded) and may throw.
ImagePlane readImagePlane(const std::string& path, const std::string& channel,
                          const std::function<void(int, int)>& checkSize = {});

// Writes `values` (width * height, row 0 at the top, each in [0, 1]) as a 16-bit grey PNG, code =
// round(v * 65535), atomically: an outside frame as a renderer would write it (tests, adapters).
void writeGreyPng16(const std::string& path, int width, int height, const std::vector<float>& values);

// Whether `compare` takes this file as a frame from outside: a .png, or an .exr that does not
// carry shadowlab's frame metadata (the "shadowlab:meta" attribute every shadowlab frame has).
bool isOutsideFrameFile(const std::string& path);

// What the coverage image means (scenes/FRAME-CONTRACT.md "Coverage").
struct CoverageRule {
  // Not set: a mask (alpha): a surface where the value is > 0.5. Set: a depth image: no surface
  // where the value equals `far` (1 for a depth buffer cleared to the far plane, 0 for reversed-Z).
  std::optional<float> far;
};

// The outside Frame for the truth's scene and camera: light.LIGHT.vis from `vis` (0 where the
// frame has no surface, as frame.h says), hit from `coverage` where one is given, else the truth's
// own hit (meta "coverage": "assumed"), object_id the truth's where both hit (an outside renderer
// has no ids: a geometry mismatch then means coverage disagreement only), meta kind "outside",
// "renderer" (declared name), "light", and the truth's scene, scene_hash, camera_hash, lights.
// Checks the values: vis in [0, 1] (InputError naming `visFile`, its channel, the first pixel),
// a mask coverage in [0, 1]; sizes must be the camera's (the caller refuses others first).
Frame makeOutsideFrame(const Frame& truth, const std::string& light, const ImagePlane& vis, const std::string& visFile,
                       const ImagePlane* coverage, const std::string& coverageFile, const CoverageRule& rule,
                       const DeclaredRenderer& declared);

// Contact (the blind leak rule, compare/METRICS.md "Frames from other renderers"): a true occluder
// within this many texels of the declared map (its world size at the receiver) plus the declared
// normal bias, times CompareOptions::leakBiasFactor, of the receiver. A renderer's depth bias that
// removes acne on sloped receivers spans a few texels, so a shadow it loses there is peter panning.
// A filterable map (VSM, MSM) has no depth bias: its shadows are lost either through the moments'
// slack right at contact (leak) or by light bleeding (bleed), and the shorter distance is the one
// that separates the two best (bench/blind_agreement_bench.cpp).
constexpr float kContactTexels = 2.0f;
constexpr float kContactTexelsFilterable = 0.6f;
// in_map: a point this many texels inside a declared layer's edge counts as outside it. A lookup
// there reads clamped texels (a filter kernel's reach, a normal offset the frame does not declare),
// so the map does not hold the point reliably: a wrong pixel there is coverage.
constexpr float kMapEdgeTexels = 3.0f;

// The one place where the evidence of an outside frame is filled in before it is compared: from
// the truth with the All channels (P, N, occluder_dist, ...), the outside Frame (meta kind
// "outside") and what its renderer declared. Sets options.blind (the blind rule of classify.h)
// and options.declaredFilterable (a declared filter of a filterable map: vsm, evsm2, evsm4, msm,
// "VSM", "VSMShadowMap"). With a declared map (light matrices and map size) it adds to `outside`
// the planes light.L.in_map (the truth's point inside some declared layer), light.L.m (the texel
// footprint of the first layer holding the point, from the truth's points of the neighbouring
// pixels in its tangent plane: the boundary band in texels) and light.L.contact_world (the contact
// distance above); meta "boundary_band" says "texels". Without one, the band is read in pixels
// ("boundary_band": "pixels") and coverage and leak are not proven. Throws InputError when the
// truth lacks a channel it needs (P, N, hit, object_id with a declared map).
void prepareOutsideComparison(const Frame& truthAll, Frame& outside, const DeclaredRenderer& declared,
                              CompareOptions& options);

}  // namespace shadowlab
