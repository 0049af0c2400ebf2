// A key given twice in any JSON file the binary reads is bad input: one reader (json_reader.h)
// refuses it in every file, not only in scenes and methods. Each tests/bad_input file below goes
// through the real binary: exit 2, nothing on stdout, one line on stderr that starts with the file
// path and contains the file's "// expect: " line (the key's JSON pointer), never nlohmann's own
// exception text, and no output written.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "support/cli.h"

namespace json_bad_input_test {

namespace fs = std::filesystem;
using shadowlab::testing::CliRun;
using shadowlab::testing::runShadowlab;
using shadowlab::testing::slurp;

namespace {

const std::string kBadInput = std::string(SHADOWLAB_SOURCE_DIR) + "/tests/bad_input/";
const std::string kGoodMetrics = kBadInput + "assets/metrics_ok.json";

class JsonBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shadowlab_json_bad_input_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `args` and checks the rejection of `file` (a name in tests/bad_input).
  void expectRejected(const std::string& file, const std::string& args) {
    const std::string path = kBadInput + file;
    std::smatch match;
    const std::string text = slurp(path);
    ASSERT_TRUE(std::regex_search(text, match, std::regex("// expect: ([^\n]*)"))) << file << " has no // expect: line";
    const CliRun r = runShadowlab(args, dir_);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.rfind(path + ": ", 0), 0u) << "message must start with the file path:\n" << r.err;
    EXPECT_NE(r.err.find(match[1].str()), std::string::npos) << "got:      " << r.err << "expected: " << match[1].str();
    EXPECT_EQ(r.err.find("json.exception"), std::string::npos) << "nlohmann's raw text reached the user:\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line per error:\n" << r.err;
    EXPECT_EQ(r.out, "");
  }

  fs::path dir_;
};

}  // namespace

TEST_F(JsonBadInput, ToleranceFileWithAKeyTwice) {
  const std::string out = (dir_ / "gate.json").string();
  expectRejected("tolerances_duplicate_key.json", "gate '" + kGoodMetrics + "' --baseline '" + kGoodMetrics +
                                                      "' --tolerances '" + kBadInput +
                                                      "tolerances_duplicate_key.json' --json '" + out + "'");
  EXPECT_FALSE(fs::exists(out)) << "nothing written on bad input";
}

TEST_F(JsonBadInput, ResultsFileWithAKeyTwice) {
  expectRejected("results_duplicate_key.json",
                 "gate '" + kBadInput + "results_duplicate_key.json' --baseline '" + kGoodMetrics + "'");
}

TEST_F(JsonBadInput, MetricsBaselineWithAKeyTwice) {
  // The baseline side: --update-baseline must not rewrite it either.
  const std::string before = slurp(kBadInput + "metrics_duplicate_key.json");
  expectRejected("metrics_duplicate_key.json", "gate '" + kGoodMetrics + "' --baseline '" + kBadInput +
                                                   "metrics_duplicate_key.json' --update-baseline");
  EXPECT_EQ(slurp(kBadInput + "metrics_duplicate_key.json"), before);
}

TEST_F(JsonBadInput, SweepFileWithAKeyTwice) {
  const fs::path out = dir_ / "sweep";
  expectRejected("sweep_duplicate_key.json",
                 "sweep --sweep '" + kBadInput + "sweep_duplicate_key.json' --no-report -o '" + out.string() + "'");
  EXPECT_FALSE(fs::exists(out)) << "nothing written on bad input";
}

TEST_F(JsonBadInput, RendererFileWithAKeyTwice) {
  // The renderer JSON is read before the frame: the frame need not exist for the error.
  const fs::path out = dir_ / "cmp";
  expectRejected("renderer_duplicate_key.json", "compare grazing '" + (dir_ / "frame.png").string() + "' --renderer '" +
                                                    kBadInput + "renderer_duplicate_key.json' -o '" + out.string() +
                                                    "'");
  EXPECT_FALSE(fs::exists(out)) << "nothing written on bad input";
}

// A file that is no JSON at all (a pull request can name any file as a scene, a method or a
// baseline): the message says where it stopped being JSON and never quotes what it read there.
TEST_F(JsonBadInput, AFileThatIsNoJsonIsNeverQuoted) {
  const fs::path secret = dir_ / "passwd";
  std::ofstream(secret) << "root-secret-7f3a:x:0:0:root:/root:/bin/bash\n";
  for (const std::string& args :
       {"reference '" + secret.string() + "' -o '" + (dir_ / "ref").string() + "'",
        "gate '" + kGoodMetrics + "' --baseline '" + secret.string() + "'",
        "run sphere_on_plane --method '" + secret.string() + "' -o '" + (dir_ / "run").string() + "'",
        "compare grazing '" + (dir_ / "frame.png").string() + "' --renderer '" + secret.string() + "' -o '" +
            (dir_ / "cmp").string() + "'"}) {
    const CliRun r = runShadowlab(args, dir_);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(secret.string() + ":1:1: error: "), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("root"), std::string::npos) << "the file's bytes reached the message:\n" << r.err;
    EXPECT_EQ(r.err.find("secret"), std::string::npos) << r.err;
  }
}

}  // namespace json_bad_input_test
