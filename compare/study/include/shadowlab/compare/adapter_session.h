#pragma once
// Frames from an outside renderer's adapter (adapters/README.md): a batch of configurations of one
// scene is written as one request, the adapter's command renders them in one process, and each
// frame it wrote is read, checked, aligned and scored against the truth. A failure is the
// adapter's (AdapterError, exit 3): named with the adapter and the configuration, the command's
// output kept in its log, nothing scored for that frame.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shadowlab/compare/compare.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/frame.h"
#include "shadowlab/scenes/method.h"
#include "shadowlab/scenes/scene.h"

namespace shadowlab {

// The adapter failed (exit 3): a nonzero exit, a time-out, a missing, short, NaN or out-of-range
// frame, an error.txt, a misaligned frame.
class AdapterError : public DriverError {
 public:
  using DriverError::DriverError;
};

struct AdapterFrame {
  std::string config;  // the configuration's name (messages, the request)
  Method method;       // renderer= set; one batch shares one renderer
};

struct AdapterOutcome {
  bool ok = false;
  std::string error;  // !ok: the whole message of the AdapterError
  Metrics metrics;
  Classification classification;
  Frame frame;  // as compared (an outside frame or the adapter's raster.exr)
  // renderer_frame_ms (the renderer's own), adapter_ms (the batch's wall time per frame, start-up
  // included), adapter_decode_ms (reading and checking this frame's files), compare_ms.
  nlohmann::json timings = nlohmann::json::object();
  nlohmann::json renderer = nlohmann::json::object();  // what renderer.json declared: name, filter, settings
  std::string frameDir;                                // where the adapter wrote it
  void throwIfFailed() const {
    if (!ok) throw AdapterError(error);
  }
};

class AdapterSession {
 public:
  // `workDir`: request and frame folders (created as needed), `cacheDir`: exported scenes
  // (adapter-scenes/<scene hash>.glb).
  AdapterSession(std::string workDir, std::string cacheDir);
  ~AdapterSession();
  // Renders `frames` of `scene` under `light` in one run of their adapter's command and scores
  // each. `reference`: the scene's reference as the built-in path compares it (a `shadowlab` frame
  // is compared against it); a `png` frame against the truth traced with every channel (traced here
  // once per scene). Outcomes in the order of `frames`; never throws for a frame's failure.
  std::vector<AdapterOutcome> render(const Scene& scene, const std::string& light,
                                     const std::vector<AdapterFrame>& frames, const Frame& reference);
  // The truth a `png` frame of the last scene was scored against (every channel); empty before.
  const Frame& truth() const;
  // The last batch's folder (request.json, frame-N/, adapter.log).
  std::string lastBatchDir() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A renderer's adapter is a program: a bundled one (renderer=NAME) runs from anywhere, another
// (renderer=path/adapter.json) only when the command line named it (--set, --grid, --fixed), never
// because a method or sweep file did (such files come from anywhere, a pull request's too).
// InputError prefixed by `origin` otherwise.
void checkAdapterMayRun(const Method& method, const std::string& origin);

// The adapter's command, run in its manifest's folder with `request` for {request}, its output into
// `logPath`, killed (its process group) after `timeoutS`: "" when it exited 0, else what happened
// ("exited with status 3", "timed out after 12 s", "could not start: ..."). For tests and benches.
std::string runAdapterCommand(const struct AdapterManifest& manifest, const std::string& request,
                              const std::string& logPath, double timeoutS);

}  // namespace shadowlab
