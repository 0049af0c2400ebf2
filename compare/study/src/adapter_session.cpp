// An outside renderer's frames through its adapter (adapter_session.h, adapters/README.md).
#include "shadowlab/compare/adapter_session.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "shadowlab/compare/frame_check.h"
#include "shadowlab/compare/outside_alignment.h"
#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/compare/timings.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/adapter_manifest.h"
#include "shadowlab/scenes/gltf_export.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/json_reader.h"
#include "shadowlab/scenes/number_text.h"

extern char** environ;

namespace shadowlab {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

std::string selfExecutable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("shadowlab") : p.string();
}

std::string replaceAll(std::string s, const std::string& what, const std::string& with) {
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + with.size()))
    s.replace(at, what.size(), with);
  return s;
}

// The first line of an adapter's error.txt, at most 200 bytes (printableText makes it safe to print).
std::string firstLine(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  if (line.size() > 200) line = line.substr(0, 200) + "...";
  return line.empty() ? std::string("(no reason given)") : line;
}

bool isFile(const std::string& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

}  // namespace

void checkAdapterMayRun(const Method& method, const std::string& origin) {
  if (method.renderer.empty() || method.rendererFromCommandLine) return;
  if (resolveAdapterPath(method.renderer) != method.renderer) return;  // a bundled adapter's name
  throw InputError(formatError(origin, "renderer",
                               "got " + method.renderer +
                                   " from a file; expected a bundled adapter's name (" +
                                   [] {
                                     std::string names;
                                     for (const std::string& n : bundledAdapterNames())
                                       names += (names.empty() ? "" : ", ") + n;
                                     return names;
                                   }() +
                                   "), or the path on the command line (--set renderer=" + method.renderer +
                                   "): an adapter is a program, and a method or sweep file does not start one"));
}

std::string runAdapterCommand(const AdapterManifest& manifest, const std::string& request, const std::string& logPath,
                              double timeoutS) {
  std::vector<std::string> args;
  for (const std::string& a : manifest.command)
    args.push_back(replaceAll(replaceAll(a, "{request}", request), "{shadowlab}", selfExecutable()));
  // A first word with a '/' is the manifest folder's; a bare name is looked up on PATH.
  if (args[0].find('/') != std::string::npos && args[0].front() != '/') args[0] = manifest.dir + "/" + args[0];
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  const int logFd = ::open(logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (logFd < 0) return "could not write its log " + logPath + ": " + std::strerror(errno);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, logFd, 1);
  posix_spawn_file_actions_adddup2(&actions, logFd, 2);
  posix_spawn_file_actions_addchdir_np(&actions, manifest.dir.c_str());
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  // Its own process group (a time-out stops the whole of it: a browser and its helpers), no signal
  // blocked (the CLI's signal thread blocks them in every other thread) and the default actions.
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  for (int s : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGQUIT}) sigaddset(&defaults, s);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setpgroup(&attr, 0);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  pid_t pid = -1;
  const int rc = ::posix_spawnp(&pid, argv[0], &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(logFd);
  if (rc != 0) return "could not start " + args[0] + ": " + std::strerror(rc);

  const auto t0 = Clock::now();
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) return std::string("could not wait for it: ") + std::strerror(errno);
    if (msSince(t0) > timeoutS * 1000.0) {
      ::kill(-pid, SIGKILL);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      return "timed out after " + numberText(timeoutS) + " s (timeout_s in " + manifest.path + ")";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(-pid, SIGKILL);  // whatever it left running in its group
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return "was killed by signal " + std::to_string(WTERMSIG(status));
  return "ended abnormally";
}

struct AdapterSession::Impl {
  std::string workDir, cacheDir;
  size_t batches = 0;
  // The truth with every channel (a png frame's evidence comes from it), for the last scene.
  std::string truthHash, truthLight;
  Frame truthAll;

  std::string exportScene(const Scene& scene) {
    const std::string dir = cacheDir + "/adapter-scenes";
    makeDirs(dir);
    const std::string path = fs::absolute(dir + "/" + scene.hash + ".glb").lexically_normal().string();
    if (!isFile(path)) writeFileAtomic(path, exportGlb(scene, "shadowlab").glb);
    return path;
  }

  const Frame& truthFor(const Scene& scene) {
    if (truthHash != scene.hash || truthAll.pixelCount() == 0) {
      ReferenceOptions options;
      options.channels = ReferenceChannels::All;
      truthAll = renderReference(scene, options);
      truthHash = scene.hash;
    }
    return truthAll;
  }

  // One frame the adapter wrote: read, checked and scored. Throws InputError or AdapterError.
  void score(const AdapterManifest& a, const Scene& scene, const std::string& light, const std::string& dir,
             const Frame& reference, AdapterOutcome& o) {
    const auto d0 = Clock::now();
    const std::string rendererJson = dir + "/renderer.json";
    if (isFile(dir + "/error.txt")) throw AdapterError("could not render it: " + firstLine(dir + "/error.txt"));
    if (!isFile(rendererJson)) throw AdapterError("wrote no renderer.json in " + dir + " (the frame is not complete)");
    const DeclaredRenderer declared = readDeclaredRenderer(rendererJson);
    if (!declared.frameMs)
      throw InputError(
          formatError(rendererJson, "/frame_ms", "missing; expected the renderer's own time for the frame"));
    o.renderer = {{"name", declared.name}, {"filter", declared.filter}, {"settings", declared.settings}};
    CompareOptions options;
    options.light = light;
    if (a.frame == AdapterManifest::FrameKind::Shadowlab) {
      const std::string exr = dir + "/raster.exr";
      if (!isFile(exr)) throw AdapterError("wrote no raster.exr in " + dir);
      o.frame = readFrameToCompare(exr);
      if (o.frame.width != reference.width || o.frame.height != reference.height)
        throw InputError(formatError(exr, "",
                                     "a " + std::to_string(o.frame.width) + "x" + std::to_string(o.frame.height) +
                                         " frame; expected the camera's " + std::to_string(reference.width) + "x" +
                                         std::to_string(reference.height)));
      o.timings[timing::kAdapterDecodeMs] = msSince(d0);
      options.referenceName = scene.path + " (reference)";
      options.rasterName = exr;
      const auto c0 = Clock::now();
      o.metrics = compareFrames(reference, o.frame, options, &o.classification);
      o.timings[timing::kCompareMs] = msSince(c0);
    } else {
      std::string visPath = dir + "/vis.png";
      if (!isFile(visPath) && isFile(dir + "/vis.exr")) visPath = dir + "/vis.exr";
      if (!isFile(visPath)) throw AdapterError("wrote no vis.png in " + dir);
      auto sized = [&scene](const std::string& file) {
        return [&scene, file](int width, int height) { checkOutsideSize(width, height, scene.camera, file); };
      };
      const ImagePlane vis = readImagePlane(visPath, "", sized(visPath));
      const std::string coveragePath = dir + "/coverage.png";
      std::optional<ImagePlane> coverage;
      if (isFile(coveragePath)) coverage = readImagePlane(coveragePath, "", sized(coveragePath));
      const double decodeMs = msSince(d0);
      const Frame& truth = truthFor(scene);
      Frame outside = makeOutsideFrame(truth, light, vis, visPath, coverage ? &*coverage : nullptr, coveragePath,
                                       CoverageRule{}, declared);
      ReferenceOptions traceOptions;
      traceOptions.channels = ReferenceChannels::All;
      checkOutsideAlignment(scene, truth, outside, coverage.has_value(), light, visPath, traceOptions);
      o.timings[timing::kAdapterDecodeMs] = decodeMs;
      options.referenceName = scene.path + " (traced)";
      options.rasterName = visPath;
      prepareOutsideComparison(truth, outside, declared, options);
      const auto c0 = Clock::now();
      o.metrics = compareFrames(truth, outside, options, &o.classification);
      o.timings[timing::kCompareMs] = msSince(c0);
      o.frame = std::move(outside);
    }
    o.timings[timing::kRendererFrameMs] = *declared.frameMs;
  }
};

AdapterSession::AdapterSession(std::string workDir, std::string cacheDir) : impl_(std::make_unique<Impl>()) {
  std::error_code ec;
  impl_->workDir = fs::absolute(workDir, ec).lexically_normal().string();
  impl_->cacheDir = fs::absolute(cacheDir, ec).lexically_normal().string();
}

AdapterSession::~AdapterSession() = default;

const Frame& AdapterSession::truth() const { return impl_->truthAll; }

std::string AdapterSession::lastBatchDir() const {
  return impl_->batches == 0 ? std::string() : impl_->workDir + "/batch-" + std::to_string(impl_->batches - 1);
}

std::vector<AdapterOutcome> AdapterSession::render(const Scene& scene, const std::string& light,
                                                   const std::vector<AdapterFrame>& frames, const Frame& reference) {
  std::vector<AdapterOutcome> out(frames.size());
  if (frames.empty()) return out;
  for (const AdapterFrame& f : frames) checkAdapterMayRun(f.method, "configuration " + f.config);
  const AdapterManifest& a = *rendererManifest(frames.front().method);
  const std::string batchDir = impl_->workDir + "/batch-" + std::to_string(impl_->batches++);
  std::error_code ec;
  fs::remove_all(batchDir, ec);
  makeDirs(batchDir);
  nlohmann::json request = {{"shadowlab_adapter_request", kAdapterProtocol},
                            {"scene", impl_->exportScene(scene)},
                            {"light", light},
                            {"width", scene.camera.width},
                            {"height", scene.camera.height}};
  nlohmann::json overrides = nlohmann::json::array();
  for (const auto& [pointer, value] : scene.overridesGiven)
    overrides.push_back({{"pointer", pointer}, {"value", nlohmann::json::parse(value, nullptr, false)}});
  request["source_scene"] = {{"path", fs::absolute(scene.path, ec).lexically_normal().string()},
                             {"overrides", overrides}};
  nlohmann::json list = nlohmann::json::array();
  std::vector<std::string> dirs;
  for (size_t i = 0; i < frames.size(); ++i) {
    dirs.push_back(batchDir + "/frame-" + std::to_string(i));
    makeDirs(dirs.back());
    list.push_back({{"id", std::to_string(i)},
                    {"config", frames[i].config},
                    {"out", dirs.back()},
                    {"keys", adapterKeyValues(frames[i].method)}});
  }
  request["frames"] = list;
  const std::string requestPath = batchDir + "/request.json";
  writeJsonAtomic(requestPath, request);
  const std::string logPath = batchDir + "/adapter.log";
  const auto t0 = Clock::now();
  const std::string failed =
      runAdapterCommand(a, requestPath, logPath, a.startTimeoutS + a.perFrameTimeoutS * double(frames.size()));
  const double perFrameMs = msSince(t0) / double(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    AdapterOutcome& o = out[i];
    o.frameDir = dirs[i];
    const std::string who = "renderer " + a.name + " (" + a.path + "), configuration " + frames[i].config + ": error: ";
    const std::string log = " (its output: " + logPath + ")";
    if (!failed.empty() && !isFile(dirs[i] + "/renderer.json")) {
      o.error = who + "the adapter " + failed + log;
      continue;
    }
    try {
      impl_->score(a, scene, light, dirs[i], reference, o);
      o.timings[timing::kAdapterMs] = perFrameMs;
      o.ok = true;
    } catch (const AdapterError& e) {
      o.error = who + e.what() + log;
    } catch (const InputError& e) {
      // The frame it wrote is wrong (size, NaN, range, alignment): the adapter's failure.
      o.error = who + "its frame is refused: " + e.what() + log;
    }
  }
  return out;
}

}  // namespace shadowlab
