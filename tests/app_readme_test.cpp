// Every `shadowlab` command line (and `node adapters/...` line) of README.md's command blocks, as written, in order, in a fresh
// folder (the README's out/ paths relative to it): a README line that no longer works fails here,
// not in a reader's terminal.
//
// What the test adds around the lines, each what the README itself assumes:
//   - `./build/app/shadowlab` and `$B` are the built binary;
//   - the shared filesystem's absolute `/shared/` (section "Many machines") is a folder in the
//     temporary one, so the test writes nothing outside it;
//   - `$EDITOR mine.glsl` is the user's own technique: examples/techniques/pcf.glsl copied there;
//   - a gate line whose --baseline file does not exist yet ("an earlier run's metrics",
//     last_week/) gets a copy of the current file as that baseline, so the gate runs (exit 0);
//   - a `--shard 0/N` line stands for one command per machine: the test runs the other N - 1
//     shards too before the merge.
//   - a `compare SCENE FRAME.png` line whose PNG no line wrote (section "Score your own renderer":
//     the user's own engine renders it) gets the frame an engine that gets everything right would
//     write: the truth's own visibility of the scene's first light, as a 16-bit grey PNG;
//   - an `export` line, where this build has no `shadowlab export` subcommand, is skipped with the
//     reason printed.
// Lines that need what a build tree cannot give are skipped with the reason printed: the device
// bundle's launcher `shadowlab/shadowlab` (scripts/device-bundle.sh builds it), and `--submit`
// where `sbatch` is on PATH (it would submit to a cluster; CTest `slurm_loopback` runs that path).
// Without sbatch, `--submit` must exit 2 "no Slurm installed", as the README says. No line needs
// Chromium (report.html is written without a browser; tests/report_chromium_test.cpp opens it).
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shadowlab/compare/outside_frame.h"
#include "shadowlab/reference/reference.h"
#include "shadowlab/scenes/loader.h"

namespace app_readme_test {

namespace {

namespace fs = std::filesystem;

struct ReadmeLine {
  int lineNo = 0;       // README.md line where the command starts
  std::string command;  // the command, continuation lines joined, comment removed
};

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A `#` after whitespace, outside quotes, starts a comment.
std::string withoutComment(const std::string& line) {
  char quote = 0;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ')) {
      std::string kept = line.substr(0, i);
      while (!kept.empty() && kept.back() == ' ') kept.pop_back();
      return kept;
    }
  }
  return line;
}

bool isShadowlabLine(const std::string& command) {
  for (const char* prefix : {"$B ", "./build/app/shadowlab ", "shadowlab/shadowlab ", "node adapters/"})
    if (command.rfind(prefix, 0) == 0) return true;
  return false;
}

std::vector<ReadmeLine> readmeCommands() {
  std::istringstream in(slurp(fs::path(SHADOWLAB_SOURCE_DIR) / "README.md"));
  std::vector<ReadmeLine> out;
  std::string line;
  bool inBlock = false;
  int no = 0;
  ReadmeLine pending;
  while (std::getline(in, line)) {
    ++no;
    if (line.rfind("```", 0) == 0) {
      inBlock = !inBlock && line.rfind("```sh", 0) == 0;
      continue;
    }
    if (!inBlock) continue;
    std::string text = withoutComment(line);
    const bool continues = !text.empty() && text.back() == '\\';
    if (continues) text.pop_back();
    if (pending.command.empty()) {
      size_t start = text.find_first_not_of(' ');
      if (start == std::string::npos) continue;
      pending.lineNo = no;
      pending.command = text.substr(start);
    } else {
      pending.command += " " + text.substr(std::min(text.size(), text.find_first_not_of(' ')));
    }
    if (continues) continue;
    while (!pending.command.empty() && pending.command.back() == ' ') pending.command.pop_back();
    if (isShadowlabLine(pending.command)) out.push_back(pending);
    pending = ReadmeLine{};
  }
  return out;
}

bool onPath(const std::string& tool) { return std::system(("command -v " + tool + " >/dev/null 2>&1").c_str()) == 0; }

struct Ran {
  int code = -1;
  std::string out;  // stdout and stderr
  double seconds = 0;
};

Ran runIn(const fs::path& dir, const std::string& command) {
  const fs::path log = dir / ".readme_test.log", script = dir / ".readme_test.sh";
  std::ofstream(script) << "cd '" << dir.string() << "' || exit 99\nB='" << SHADOWLAB_BINARY
                        << "'\nexport SHADOWLAB_CACHE='" << (dir / ".cache").string() << "'\n"
                        << command << "\n";
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(("bash '" + script.string() + "' >'" + log.string() + "' 2>&1").c_str());
  Ran r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(log);
  return r;
}

// The value after `flag ` in a command ("" when absent).
std::string argumentOf(const std::string& command, const std::string& flag) {
  std::smatch m;
  if (std::regex_search(command, m, std::regex("(?:^| )" + flag + "[ =]([^ ]+)"))) return m[1];
  return "";
}

TEST(Readme, EveryShadowlabLineRunsAsWritten) {
  const std::vector<ReadmeLine> lines = readmeCommands();
  ASSERT_GE(lines.size(), 20u) << "README.md's command blocks lost their shadowlab lines";
  const fs::path dir = fs::temp_directory_path() / ("shadowlab_readme_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Without a Vulkan device the render lines cannot run: a loud skip, and under CI=true a failure.
  const Ran probe = runIn(dir, "$B raster grazing --set scene:/camera/width=48 --set scene:/camera/height=32 -o probe");
  if (probe.code == 3) {
    const bool ci = std::getenv("CI") && std::string(std::getenv("CI")) == "true";
    if (ci) FAIL() << "no Vulkan device under CI=true: " << probe.out;
    std::printf("\n*** SKIPPING: no Vulkan device for the README's render lines: %s ***\n\n", probe.out.c_str());
    GTEST_SKIP() << "no Vulkan device";
  }
  fs::remove_all(dir / "probe");
  const bool sbatch = onPath("sbatch");
  const bool hasExport = runIn(dir, "$B export --help").code == 0;
  // The three.js adapter's lines (and the lines that read its frame) need node, its npm packages
  // and chromium: a loud skip without them, a failure under CI=true (the install script installs them).
  const fs::path adapters = fs::path(SHADOWLAB_SOURCE_DIR) / "adapters";
  std::string noThree;
  if (!onPath("node")) noThree = "no node on PATH";
  else if (!fs::exists(adapters / "three/node_modules/three/package.json")) noThree = "adapters/three has no node_modules (npm ci)";
  else if (!fs::exists("/usr/bin/chromium") && !std::getenv("CHROMIUM")) noThree = "no chromium";
  const bool ci = std::getenv("CI") && std::string(std::getenv("CI")) == "true";
  if (!noThree.empty() && ci) ADD_FAILURE() << "CI=true and the three.js adapter cannot run: " << noThree;
  double total = 0;
  for (const ReadmeLine& l : lines) {
    std::string command = l.command;
    const std::string where = "README.md:" + std::to_string(l.lineNo) + ": " + l.command;
    if (command.rfind("shadowlab/shadowlab ", 0) == 0) {
      std::printf("*** SKIPPED %s: the device bundle's launcher (scripts/device-bundle.sh builds it)\n", where.c_str());
      continue;
    }
    if (command.find("--submit") != std::string::npos && sbatch) {
      std::printf(
          "*** SKIPPED %s: sbatch is on PATH and would submit to a cluster (CTest slurm_loopback runs "
          "--submit)\n",
          where.c_str());
      continue;
    }
    if (command.rfind("$B export ", 0) == 0 && !hasExport) {
      std::printf("*** SKIPPED %s: this build has no `shadowlab export` subcommand\n", where.c_str());
      continue;
    }
    if (command.rfind("node adapters/", 0) == 0) {
      if (!noThree.empty()) {
        std::printf("*** SKIPPED %s: %s\n", where.c_str(), noThree.c_str());
        continue;
      }
      // node adapters/SCRIPT ARGS, with SCRIPT under the checkout (the test runs in a temporary folder).
      const std::string rest = command.substr(std::string("node adapters/").size());
      const size_t space = rest.find(' ');
      command = "node '" + (adapters / rest.substr(0, space)).string() + "'" +
                (space == std::string::npos ? "" : rest.substr(space));
    } else if ((command.find("out/three") != std::string::npos || command.find("renderer=three") != std::string::npos) &&
               !noThree.empty()) {
      std::printf("*** SKIPPED %s: it reads the three.js adapter's frame (%s)\n", where.c_str(), noThree.c_str());
      continue;
    }
    // The frame the reader's own engine renders: the truth's visibility, as a right frame would be.
    std::smatch outside;
    if (std::regex_search(command, outside, std::regex("^\\$B compare ([^ ]+) ([^ ]+\\.png) ")) &&
        !fs::exists(dir / outside[2].str())) {
      using namespace shadowlab;
      const Scene scene = loadScene(resolveScenePath(outside[1].str()));
      ReferenceOptions options;
      options.channels = ReferenceChannels::Compare;
      const Frame truth = renderReference(scene, options);
      fs::create_directories((dir / outside[2].str()).parent_path());
      writeGreyPng16((dir / outside[2].str()).string(), truth.width, truth.height,
                     truth.get("light." + scene.lightOrDefault("") + ".vis"));
    }
    const std::string binary = "./build/app/shadowlab ";
    if (command.rfind(binary, 0) == 0) command = "$B " + command.substr(binary.size());
    command = std::regex_replace(command, std::regex(" /shared/"), " shared/");
    // The README's own technique file, as `$EDITOR mine.glsl` would have left it.
    if (command.find("technique=mine.glsl") != std::string::npos && !fs::exists(dir / "mine.glsl"))
      fs::copy_file(fs::path(SHADOWLAB_SOURCE_DIR) / "examples/techniques/pcf.glsl", dir / "mine.glsl");
    // An earlier run's baseline the README assumes: the current file, copied.
    if (command.rfind("$B gate ", 0) == 0 && command.find("--update-baseline") == std::string::npos) {
      const std::string current = argumentOf(command, "gate"), baseline = argumentOf(command, "--baseline");
      if (!baseline.empty() && !fs::exists(dir / baseline)) {
        fs::create_directories((dir / baseline).parent_path());
        fs::copy_file(dir / current, dir / baseline);
      }
    }
    const Ran r = runIn(dir, command);
    total += r.seconds;
    std::printf("%6.1f s  exit %d  %s\n", r.seconds, r.code, where.c_str());
    std::fflush(stdout);
    if (command.find("--submit") != std::string::npos) {
      EXPECT_EQ(r.code, 2) << where << "\n" << r.out;
      EXPECT_NE(r.out.find("no Slurm installed"), std::string::npos) << where << "\n" << r.out;
      continue;
    }
    EXPECT_EQ(r.code, 0) << where << "\n" << r.out;
    // One command per machine: the other shards of a --shard I/N line, before the merge.
    std::smatch shard;
    if (std::regex_search(command, shard, std::regex("--shard 0/([0-9]+)")))
      for (int i = 1; i < std::stoi(shard[1]); ++i) {
        const std::string other =
            std::regex_replace(command, std::regex("--shard 0/"), "--shard " + std::to_string(i) + "/");
        const Ran o = runIn(dir, other);
        total += o.seconds;
        EXPECT_EQ(o.code, 0) << other << "\n" << o.out;
      }
  }
  std::printf("README.md: %zu lines in %.1f s\n", lines.size(), total);
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace

}  // namespace app_readme_test
