#pragma once
// Each subcommand lives in app/cmd_<name>.cpp and registers itself with a static Registrar:
//
//   static shadowlab::app::Registrar reg{"reference", [](CLI::App& app) {
//     auto* sub = app.add_subcommand("reference", "Trace the Embree ground truth");
//     auto opts = std::make_shared<Options>();
//     sub->add_option(...);
//     return std::function<int()>([opts] { return run(*opts); });
//   }};
//
// The returned function runs when that subcommand was chosen; it returns the exit code.
// It throws InputError (-> 2) or DriverError (-> 3); main prints what() and maps the code.
// Exit codes: 0 ok, 1 gate failed, 2 bad input or usage, 3 internal/driver failure.
#include <signal.h>

#include <cerrno>
#include <climits>
#include <cstdlib>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "shadowlab/reference/reference.h"

namespace shadowlab::app {

using Setup = std::function<std::function<int()>(CLI::App&)>;

struct CommandEntry {
  std::string name;
  Setup setup;
};

std::vector<CommandEntry>& commandRegistry();

struct Registrar {
  Registrar(const std::string& name, Setup setup) { commandRegistry().push_back({name, std::move(setup)}); }
};

// The version line: the CMake project version and, where the source was a git checkout at
// configure time, `git describe` ("shadowlab 0.1.0 (git aeb9bea-dirty)"). `shadowlab --version`,
// `-V` and `shadowlab version` print it.
std::string versionString();

// -q/--quiet and -v/--verbose of the long commands (kLongCommands; main adds the flags, so every
// long command has them the same way). -q: errors only (main points stdout and stderr at /dev/null
// for the command and writes its error line to the real stderr). -v: more detail, where a command
// has some to give (verbose()).
inline constexpr const char* kLongCommands[] = {"run", "stability", "sweep", "tune"};
enum class Verbosity { Quiet, Normal, Verbose };
Verbosity verbosity();
inline bool verbose() { return verbosity() == Verbosity::Verbose; }

// SIGINT/SIGTERM call `handler` once (SA_RESETHAND): the first Ctrl-C asks a long command (sweep,
// tune) for a clean stop after the configuration in progress; a second one kills the process the
// default way (rows already appended are safe either way).
inline void installStopHandlers(void (*handler)(int)) {
  struct sigaction sa {};
  sa.sa_handler = handler;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// A count option (--spp, --light-samples): text that is no int names the range ("--light-samples:
// got 1e9; expected an integer 1..4096 (...)") where CLI11 alone says "Could not convert". A
// validator runs on the text, before the conversion; an int outside lo..hi passes on to the
// command's own check (checkSpp, checkLightSamples), whose message is the same.
inline CLI::Validator integerRange(long long lo, long long hi, const std::string& what) {
  return CLI::Validator(
      [lo, hi, what](std::string& text) -> std::string {
        errno = 0;
        char* end = nullptr;
        const long long v = std::strtoll(text.c_str(), &end, 10);
        if (text.empty() || *end != '\0' || errno != 0 || v < INT_MIN || v > INT_MAX)
          return "got " + text + "; expected an integer " + std::to_string(lo) + ".." + std::to_string(hi) + " (" +
                 what + ")";
        return "";
      },
      "");
}

// What the commands that run many configurations through the pipeline (sweep, tune) share: the
// base method, the output folder, the light, the reference's samples, its cache and the device.
// --gpu-timeout-s, on every command that renders (the same help everywhere; checkGpuTimeout in
// raster.h validates it before any output).
inline CLI::Option* addGpuTimeoutOption(CLI::App* sub, double* seconds) {
  return sub->add_option("--gpu-timeout-s", *seconds,
                         "Seconds a GPU pass may take before the command ends with exit 3 (a technique that never "
                         "returns; default: $SHADOWLAB_GPU_TIMEOUT_S, else 120)");
}

struct StudyOptions {
  std::string methodFile;
  std::string outDir;
  std::string light;
  std::optional<int> spp;  // not given: the sweep file's, else 1
  std::optional<int> lightSamples;  // not given: the sweep file's, else kDefaultLightSamples
  std::string cacheDir;
  std::string device;
  std::optional<double> gpuTimeoutS;  // not given: the sweep file's, else 0 (the default)
  std::optional<int> timingRepetitions;  // not given: kDefaultTimingRepetitions (sweep.h)
};

// Registers them on `sub`; `what` names the command's run in the help ("sweep", "tune").
inline void addStudyOptions(CLI::App* sub, StudyOptions& o, const std::string& what) {
  sub->add_option("--method", o.methodFile, "Base method file (JSON, see raster/METHODS.md)");
  sub->add_option("-o,--out", o.outDir, "Output folder (running again continues an interrupted " + what + ")")
      ->required();
  sub->add_option("--light", o.light, "Light to render and compare (default: each scene's first)");
  sub->add_option("--spp", o.spp, "Reference samples per pixel, 1..1024 (default 1)")
      ->check(integerRange(kMinSpp, kMaxSpp, "reference samples per pixel"));
  sub->add_option("--light-samples", o.lightSamples,
                  "Reference samples of a sized light per pixel sample, 1..4096 (default 64)")
      ->check(integerRange(kMinLightSamples, kMaxLightSamples, "samples of a sized light per pixel sample"));
  sub->add_option("--cache", o.cacheDir,
                  "Reference cache folder (default: $SHADOWLAB_CACHE, else .shadowlab-cache beside the output folder)");
  sub->add_option("--device", o.device, "Vulkan device name substring (default: lavapipe)");
  sub->add_option("--gpu-timeout-s", o.gpuTimeoutS,
                  "Seconds a GPU pass may take before the command ends with exit 3 (a technique that never "
                  "returns; default: the sweep file's gpu_timeout_s, $SHADOWLAB_GPU_TIMEOUT_S, else 120)");
  sub->add_option("--timing-repetitions", o.timingRepetitions,
                  "Timed runs of the method for the rows whose time decides a ranking (near a scene's Pareto "
                  "front, or quoted by tune), reported as their median and range; 0: every row keeps its render's "
                  "own single timing (default 3; compare/TIMINGS.md)")
      ->check(CLI::Range(0, 99));
}

}  // namespace shadowlab::app
