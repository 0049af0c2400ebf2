#pragma once
// What a single long command checks and shows before and while it works: an estimate of the
// memory it will need, refused above --max-memory before anything starts (a 16384x16384 camera
// once traced for 109 s and then wrote a multi-gigabyte EXR), and a progress line on a terminal.
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "shadowlab/raster/raster.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab::app {

// A job's peak memory, estimated from its image and map sizes (bytes), with the terms named.
// Measured against the peak resident set (GNU time's maxrss) on lavapipe: reference grazing at
// 4096x4096, estimate 1.62 GiB, measured 1.55; run grazing at 3000x3000, estimate 1.60 GiB,
// measured 1.56. On a GPU the device images live in its memory and the estimate errs high.
struct MemoryEstimate {
  double bytes = 0;
  std::string breakdown;  // e.g. "reference frame 2.1 GiB x 2 while the EXR is written + ..."
  void add(double termBytes, const std::string& what);
};

// The reference's frame with the channels written (`shadowlab reference`: Compare, or All with
// --all-channels), twice while the EXR is interleaved, plus its pictures.
MemoryEstimate referenceJobMemory(const Scene& scene, ReferenceChannels channels);
// The raster frame (twice while written), the device's images (camera targets and map layers).
MemoryEstimate rasterJobMemory(const Scene& scene, const Method& method);
// run, stability and each sweep row: reference and raster frames in memory together, the
// device's images, the classification and its pictures.
MemoryEstimate compareJobMemory(const Scene& scene, const Method& method);

// --max-memory GiB on `sub` (default 0: 80 % of this machine's physical memory).
void addMaxMemoryOption(CLI::App* sub, double* maxMemoryGiB);

// Throws InputError (exit 2) naming the estimate, its terms and the limit when the job cannot
// fit; prints the estimate on stderr when it is 1 GiB or more, so a large job says so first.
void checkMemory(const std::string& command, const MemoryEstimate& estimate, double maxMemoryGiB);

// Refuses (InputError, exit 2) a request whose device images do not fit the device (its largest
// allocation, its layers; on a GPU its device-local heap: raster/device_memory.h), before any work;
// with -v prints the images and the limits.
void checkDeviceMemory(const std::string& command, const Rasterizer& rasterizer, const Scene& scene,
                       const Method& method, const std::string& light);

// "\r<label> 42%" on stderr, updated as the fraction grows, when stderr is a terminal; an empty
// function otherwise (logs and pipes stay quiet, as sweeps already do).
std::function<void(double)> terminalProgress(const std::string& label);

}  // namespace shadowlab::app
