// Every file in tests/bad_input/scene_*.json goes through the real binary
// (`shadowlab scenes --check FILE`): it must exit 2, print nothing on stdout, and print on stderr
// a message that starts with the file path and contains the file's "// expect: " line (which
// names the place: line:col for syntax errors, the JSON pointer otherwise). Where the fault is in
// a file the scene names (an OBJ's line), the expect line starts with that file's path relative to
// the scene ("assets/x.obj:3: error: ..."), and the message must start with it.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <filesystem>
#include <regex>

#include "shadowlab/scenes/error.h"
#include "shadowlab/scenes/io.h"
#include "shadowlab/scenes/loader.h"

namespace scenes_bad_input_test {

namespace fs = std::filesystem;

namespace {

struct RunResult {
  int exitCode = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs the binary with stdout and stderr captured separately (through files beside the test's
// temp folder), so a test can check both streams from one run.
RunResult run(const std::string& args) {
  static int counter = 0;
  fs::path dir = fs::temp_directory_path() / ("shadowlab_scenes_bad_input_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fs::path out = dir / ("out" + std::to_string(counter) + ".txt"),
           err = dir / ("err" + std::to_string(counter) + ".txt");
  ++counter;
  std::string cmd =
      std::string("'") + SHADOWLAB_BINARY + "' " + args + " >'" + out.string() + "' 2>'" + err.string() + "'";
  int status = std::system(cmd.c_str());
  RunResult r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = shadowlab::readFile(out.string());
  r.err = shadowlab::readFile(err.string());
  fs::remove(out);
  fs::remove(err);
  return r;
}

std::vector<fs::path> badScenes() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(std::string(SHADOWLAB_SOURCE_DIR) + "/tests/bad_input"))
    if (e.path().filename().string().rfind("scene_", 0) == 0 && e.path().extension() == ".json")
      files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

TEST(ScenesBadInput, EveryCaseExitsTwoWithFileAndPlace) {
  auto files = badScenes();
  ASSERT_GE(files.size(), 30u) << "the bad-input corpus shrank";
  for (const auto& f : files) {
    std::string text = shadowlab::readFile(f.string());
    std::smatch match;
    ASSERT_TRUE(std::regex_search(text, match, std::regex("// expect: ([^\n]*)"))) << f << " has no // expect: line";
    std::string expected = match[1].str();
    RunResult r = run("scenes --check '" + f.string() + "'");
    EXPECT_EQ(r.exitCode, 2) << f.filename() << ": " << r.err;
    const bool inNamedFile = expected.rfind("assets/", 0) == 0;
    const std::string start = inNamedFile ? (f.parent_path() / expected).string() : f.string();
    EXPECT_EQ(r.err.rfind(start, 0), 0u) << "message must start with " << start << ":\n" << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos)
        << f.filename() << "\n  got:      " << r.err << "  expected: " << expected;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line per error:\n" << r.err;
    EXPECT_EQ(shadowlab::printableText(r.err.substr(0, r.err.size() - 1)), r.err.substr(0, r.err.size() - 1))
        << "raw bytes that are not UTF-8, or control characters, in:\n"
        << r.err;
    EXPECT_EQ(r.out, "") << "nothing on stdout for a rejected file";
  }
}

// The corpus must cover each bad-input case listed below; a renamed or deleted file fails here.
TEST(ScenesBadInput, CorpusCoversTheRequiredCases) {
  std::set<std::string> names;
  for (const auto& f : badScenes()) names.insert(f.stem().string());
  for (const char* required : {"scene_syntax",
                               "scene_unknown_key",
                               "scene_unknown_object_type",
                               "scene_missing_obj",
                               "scene_missing_mtl",
                               "scene_missing_texture",
                               "scene_missing_map_d",
                               "scene_infinite",
                               "scene_huge_scale",
                               "scene_zero_size",
                               "scene_negative_radius",
                               "scene_camera_look_at_position",
                               "scene_camera_up_parallel",
                               "scene_zero_light_direction",
                               "scene_resolution_too_big",
                               "scene_resolution_zero",
                               "scene_fov_180",
                               "scene_near_ge_far",
                               "scene_no_light",
                               "scene_obj_nan_vertex",
                               "scene_obj_overflow_uv",
                               "scene_obj_two_corner_face",
                               "scene_obj_two_number_vertex",
                               "scene_obj_empty_face",
                               "scene_obj_index_out_of_range",
                               "scene_obj_utf16",
                               "scene_obj_folder",
                               "scene_obj_only_points",
                               "scene_obj_self_intersecting",
                               "scene_latin1_token"})
    EXPECT_TRUE(names.count(required)) << required;
}

TEST(ScenesCli, BundledScenesCheckAndList) {
  RunResult names = run("scenes --names");
  EXPECT_EQ(names.exitCode, 0);
  std::string expected;
  for (const auto& n : shadowlab::bundledSceneNames()) expected += n + "\n";
  EXPECT_EQ(names.out, expected);
  EXPECT_EQ(names.out,
            "sphere_on_plane\ngrazing\ncontact\nthin_wall\nalpha_fence\nprojector\nbunny\nlong_view\n"
            "stacked_occluders\ngltf_cards\nsoft_post\n");

  RunResult list = run("scenes");
  EXPECT_EQ(list.exitCode, 0);
  EXPECT_NE(list.out.find("thin_wall  "), std::string::npos) << list.out;
  EXPECT_NE(list.out.find("leak"), std::string::npos) << "descriptions are shown:\n" << list.out;

  std::string all;
  for (const auto& n : shadowlab::bundledSceneNames()) all += " " + n;
  RunResult check = run("scenes --check" + all);
  EXPECT_EQ(check.exitCode, 0) << check.out;
  EXPECT_NE(check.out.find("bunny: ok: 2 objects, 27866 triangles"), std::string::npos) << check.out;
}

TEST(ScenesCli, StopsAtTheFirstBadFileAndRejectsUsageErrors) {
  std::string bad = std::string(SHADOWLAB_SOURCE_DIR) + "/tests/bad_input/scene_zero_size.json";
  RunResult r = run("scenes --check sphere_on_plane '" + bad + "' grazing");
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.out.find("sphere_on_plane: ok"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("grazing: ok"), std::string::npos) << "must stop at the first bad file";
  EXPECT_NE(r.err.find("scene_zero_size.json: /objects/0/size/0: error:"), std::string::npos) << r.err;
  EXPECT_EQ(run("scenes --check").exitCode, 2);
  RunResult missing = run("scenes --check no_such_scene");
  EXPECT_EQ(missing.exitCode, 2);
  EXPECT_NE(missing.err.find("no_such_scene.json: error: cannot open scene file: no such file"), std::string::npos)
      << missing.err;
}

}  // namespace scenes_bad_input_test
