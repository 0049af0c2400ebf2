#pragma once
// The door through which frames come into compare from files: every path that reads a frame to
// compare it (`shadowlab compare`, the reference cache) reads it with readFrameToCompare, so that
// a frame from any renderer meets the same value rules before a pixel is classified. Without them
// a NaN or out-of-range value is classified confidently wrong: a raster `vis` of NaN or -1 counts
// as acne, one of 2 or Inf as lit, a NaN in the reference's `hit` as a geometry mismatch.
//
// The rules, per channel (frame.h, reference/README.md), every value also finite:
//   hit, light.L.vis, light.L.in_map, proj.P.coverage, proj.P.reverse   in [0, 1]
//   light.L.vis_sigma                                                    in [0, 1]
//   object_id, prim_id, light.L.occluder_id, light.L.occluder_prim,
//   light.L.cascade                                                      an integer in [0, 2^24]
//   light.L.occluder_dist                                                -1 or >= 0
//   light.L.m, proj.P.R|G|B                                              >= 0
//   any other channel (P, N, depths, biases, moments, u|v, a renderer's own)  finite
#include <string>

#include "shadowlab/scenes/frame.h"

namespace shadowlab {

// One pass over every plane. Throws InputError
//   "<file>: <channel> pixel (x, y): error: got V; expected R (first of N such pixels)"
// naming the first offending pixel in row order (row 0 at the top).
void checkFrameValues(const Frame& frame, const std::string& file);

// readFrameExr(path) followed by checkFrameValues(frame, path).
Frame readFrameToCompare(const std::string& path);

}  // namespace shadowlab
