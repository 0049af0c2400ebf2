#pragma once
// How good the blind rule is (compare/METRICS.md "Frames from other renderers", "How good the
// blind classes are"): a shadowlab raster frame classified twice, with all its evidence and as a
// frame from another renderer would come (its `vis` alone, with the light layers and map size the
// rasterizer used declared beside it), and the wrong pixels counted by both classes.
// bench/blind_agreement_bench.cpp prints the matrix over the main job; a test holds its floor.
#include <cstdint>
#include <string>

#include "shadowlab/compare/compare.h"
#include "shadowlab/compare/declared_renderer.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/method.h"

namespace shadowlab {

struct ClassConfusion {
  // [full class][blind class], indexed by class code: the wrong pixels (an error class under the
  // full rule; the blind rule sees the same decisions, so the same pixels are wrong).
  PerPixelClass<PerPixelClass<uint64_t>> counts{};
  uint64_t wrong() const;     // every counted pixel
  uint64_t agreeing() const;  // on the diagonal
  uint64_t ofFull(PixelClass full) const;
  // The largest share of one full class's pixels that the blind rule puts in one other class, and
  // which pair (0 when nothing is counted).
  double worstConfusion(PixelClass* full = nullptr, PixelClass* blind = nullptr) const;
  void add(const ClassConfusion& other);
  // A Markdown table: full rows, blind columns, the classes that occur, each cell a count and
  // the row's share.
  std::string markdown() const;
};

// What the rasterizer declares for its last render of `method` (the light's layers and the map
// size; the filter by name), as an outside renderer's JSON would.
DeclaredRenderer declaredByRaster(const Rasterizer& rasterizer, const Method& method);

// `raster` as an outside renderer would hand it over: hit, object_id and the light's vis only
// (meta kind "outside", light), so that both ways see the same surfaces and decisions.
Frame blindCopy(const Frame& raster, const std::string& light);

// Classifies `raster` against `truthAll` (every reference channel) both ways and adds the wrong
// pixels to `out`. Returns the full rule's metrics.
Metrics addBlindAgreement(const Frame& truthAll, const Frame& raster, const DeclaredRenderer& declared,
                          ClassConfusion& out, const CompareOptions& options = {});

}  // namespace shadowlab
