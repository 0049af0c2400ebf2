// shadowlab: builds the CLI from the registered subcommands, parses, dispatches. Every error line
// it prints has one of two forms (STYLE.md "Errors a user can act on"):
//   shadowlab <subcommand>: error: what was found; expected what
//   file: place: error: ...      (a file, or an option such as --spp, and the place in it)
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <future>
#include <thread>
#include <map>

#include <malloc.h>

#include <unistd.h>

#include "command.h"
#include "interrupt.h"
#include "shadowlab/compare/interrupt_cleanup.h"
#include "shadowlab/raster/raster.h"
#include "shadowlab/scenes/error.h"
#include "shadowlab_version.h"

namespace shadowlab::app {

std::vector<CommandEntry>& commandRegistry() {
  static std::vector<CommandEntry> registry;
  return registry;
}

namespace {
Verbosity gVerbosity = Verbosity::Normal;
}  // namespace

Verbosity verbosity() { return gVerbosity; }

std::string versionString() {
  const std::string describe = kGitDescribe;
  return std::string("shadowlab ") + kProjectVersion + (describe.empty() ? "" : " (git " + describe + ")");
}

void cleanUpOnSignal(const std::string& command) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  if (pthread_sigmask(SIG_BLOCK, &set, nullptr) != 0) return;
  // The command goes on once the thread waits in sigwait, which allocates nothing: a technique's
  // compile forks (raster/src/technique_compiler.cpp), and a fork while this thread is still
  // starting can copy an allocator lock it holds into the child, whose compile then never returns
  // (seen under AddressSanitizer, whose allocator has no fork handler).
  std::promise<void> waiting;
  std::future<void> started = waiting.get_future();
  std::thread([set, command, waiting = std::move(waiting)]() mutable {
    int signo = 0;
    waiting.set_value();
    if (sigwait(&set, &signo) != 0) return;
    const int removed = removeInterruptPaths();
    const std::string line = "shadowlab " + command + ": interrupted (" + (signo == SIGINT ? "SIGINT" : "SIGTERM") +
                             "): removed " + std::to_string(removed) +
                             (removed == 1 ? " unfinished output" : " unfinished outputs") + "\n";
    if (::write(STDERR_FILENO, line.data(), line.size()) < 0) _exit(128 + signo);
    _exit(128 + signo);  // no exit handlers: the other threads may be mid-trace
  }).detach();
  started.wait();
}

std::string firstMissingFolder(const std::string& dir) {
  std::error_code ec;
  std::filesystem::path p = std::filesystem::absolute(dir, ec), missing;
  if (ec) return "";
  while (!p.empty() && !std::filesystem::exists(p, ec)) {
    missing = p;
    if (p == p.parent_path()) break;
    p = p.parent_path();
  }
  return missing.string();
}

namespace {

// An error message as the user sees it: a message in one of the two forms passes as it is (an
// option is the place where the user wrote it: "--spp: error: got 0; ...", "--set: map.size:
// error: ..."); a bare one, or one that names no command ("shadowlab: error: ..."), gets the
// command's prefix.
std::string errorLine(const std::string& command, const std::string& what) {
  const std::string prefix = "shadowlab" + (command.empty() ? std::string() : " " + command) + ": error: ";
  const std::string unnamed = "shadowlab: error: ";
  if (what.rfind(unnamed, 0) == 0) return prefix + what.substr(unnamed.size());
  if (what.rfind("error: ", 0) == 0) return prefix + what.substr(7);
  if (what.find(": error: ") != std::string::npos) return what;
  return prefix + what;
}

std::string commandList(const std::vector<CommandEntry>& registry) {
  std::string names;
  for (const CommandEntry& e : registry) names += (names.empty() ? "" : ", ") + e.name;
  return names;
}

// The first argument that is not an option: the subcommand (the top level has only flags).
std::string subcommandArgument(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (argv[i][0] != '-') return argv[i];
  return "";
}

}  // namespace
}  // namespace shadowlab::app

int main(int argc, char** argv) {
  using namespace shadowlab;
  // A render hands out ~100 MB of channel planes (1080p) that are freed soon after: keep freed
  // memory in the heap for the next frame instead of returning it to the OS, where each reuse
  // page-faults every 4 KiB back in (~40 ms at 1080p). Process-wide, so the program sets it,
  // not the rasterizer library.
  mallopt(M_MMAP_THRESHOLD, 32 << 20), mallopt(M_TRIM_THRESHOLD, 1 << 30);
  CLI::App cli{"shadowlab: how wrong are your shadow maps, and why"};
  cli.set_version_flag("-V,--version", app::versionString(), "Print the version and exit");
  cli.require_subcommand(1);
  auto& registry = app::commandRegistry();
  // Registration order follows static initialisation order: sort for stable help text.
  std::sort(registry.begin(), registry.end(),
            [](const app::CommandEntry& a, const app::CommandEntry& b) { return a.name < b.name; });
  std::map<std::string, std::function<int()>> runners;
  for (auto& entry : registry) runners[entry.name] = entry.setup(cli);
  for (const char* name : app::kLongCommands) {
    CLI::App* sub = cli.get_subcommand(name);
    CLI::Option* quiet = sub->add_flag("-q,--quiet", "Print errors only (no progress, notes or summary)");
    sub->add_flag("-v,--verbose", "Print more detail (memory estimate, device images)")->excludes(quiet);
  }

  const std::string command = app::subcommandArgument(argc, argv);
  if (!command.empty() && runners.count(command) == 0) {
    std::fprintf(stderr, "shadowlab: error: unknown subcommand \"%s\"; expected one of %s\n", command.c_str(),
                 app::commandList(registry).c_str());
    return 2;
  }
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return cli.exit(e);  // --help, --version
    if (command.empty()) {
      std::fprintf(stderr, "shadowlab: error: no subcommand given; expected one of %s (shadowlab --help)\n",
                   app::commandList(registry).c_str());
      return 2;
    }
    std::fprintf(stderr, "shadowlab %s: error: %s (shadowlab %s --help)\n", command.c_str(), e.what(), command.c_str());
    return 2;
  }
  CLI::App* chosen = cli.get_subcommands().empty() ? nullptr : cli.get_subcommands().front();
  if (!chosen) return 2;
  const std::string name = chosen->get_name();
  // -q: the command's stdout and stderr go to /dev/null; its error line still reaches the user.
  int errorFd = STDERR_FILENO;
  if (chosen->get_option_no_throw("--quiet") && chosen->count("--quiet") > 0) {
    app::gVerbosity = app::Verbosity::Quiet;
    std::fflush(stdout), std::fflush(stderr);
    errorFd = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY);
    if (errorFd >= 0 && null >= 0) ::dup2(null, STDOUT_FILENO), ::dup2(null, STDERR_FILENO);
    if (null >= 0) ::close(null);
    if (errorFd < 0) errorFd = STDERR_FILENO;
  } else if (chosen->get_option_no_throw("--verbose") && chosen->count("--verbose") > 0) {
    app::gVerbosity = app::Verbosity::Verbose;
  }
  auto fail = [&](int code, const std::string& line) {
    std::fflush(stdout), std::fflush(stderr);
    const std::string text = line + "\n";
    if (::write(errorFd, text.data(), text.size()) < 0) return code;
    return code;
  };
  const int code = [&] {
    try {
      return runners.at(name)();
    } catch (const InputError& e) {
      return fail(2, app::errorLine(name, e.what()));
    } catch (const DriverError& e) {
      return fail(3, app::errorLine(name, e.what()));
    } catch (const std::exception& e) {
      return fail(3, app::errorLine(name, std::string("internal error: ") + e.what()));
    }
  }();
  // A device still running a shader that never returned (--gpu-timeout-s): the driver's exit
  // handlers would wait for its threads forever, so the process ends here, its outputs written or
  // removed already (every output is atomic).
  if (shadowlab::rasterDeviceHung()) {
    std::fflush(stdout);
    std::fflush(stderr);
    _exit(code);
  }
  return code;
}
