// Bad input as a hostile user gives it, one table row per kind,
// run through every executable and, where a back-end is chosen, every
// registered back-end (the example plugin's included): each is a clear
// "program: error: file:line: reason" with exit status 1, before any work is
// done, in a message that fits a terminal (no raw control bytes, a bounded
// length); a numerical failure is exit status 2, never an abort; an "ok"
// never comes with a chi2 that is not finite.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "backends/builtins.h"
#include "core/plugin.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

using testing::CommandResult;
CommandResult run(const std::string& command_line) { return testing::runCommand(command_line); }

std::string app(const std::string& name) { return testing::buildPath("apps/" + name); }
std::string plugin() { return testing::buildPath("plugins/libhamal_example_plugin.so"); }

bool contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

// Printable ASCII and line breaks only.
bool fitsATerminal(const std::string& text) {
  for (unsigned char c : text)
    if ((c < 0x20 && c != '\n') || c >= 0x7f) return false;
  return true;
}

// Every back-end the executables offer with the example plugin loaded.
std::vector<std::string> allBackends() {
  Registry registry;
  registerBuiltins(registry);
  loadPlugin(plugin(), registry);
  std::vector<std::string> names;
  for (const BackendInfo* info : registry.backends()) names.push_back(info->name);
  return names;
}

const char* kChain =
    "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n"
    "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n";

struct BadFile {
  std::string name;  // the file's name in the scratch directory ("" = a directory)
  std::string content;
  std::string expected;  // what the message must say, after "<path>"
};

std::vector<BadFile> badFiles() {
  std::string garbage =
      "\x7f"
      "ELF\x02\x01\x01";
  garbage += std::string(1, '\0') + "\x1b[31m\xff\xfe 1 2\n";
  return {
      {"self_edge.g2o", std::string(kChain) + "EDGE_SE2 1 1 0 0 0 1 0 0 1 0 1\n",
       ":6: EDGE_SE2 names pose 1 twice: a factor's variables must be distinct"},
      {"dx_1e300.g2o", std::string(kChain) + "EDGE_SE2 0 2 1e300 0 0 1 0 0 1 0 1\n",
       ":6: dx is '1e300': out of range"},
      {"info_1e300.g2o", std::string(kChain) + "EDGE_SE2 0 2 2 0 0 1e300 0 0 1e300 0 1e300\n",
       ":6: I11 is '1e300': out of range"},
      {"overflow.g2o", std::string(kChain) + "EDGE_SE2 0 2 1e400 0 0 1 0 0 1 0 1\n",
       ":6: dx is '1e400': out of range"},
      {"nan.g2o", std::string(kChain) + "EDGE_SE2 0 2 nan 0 0 1 0 0 1 0 1\n",
       ":6: dx is 'nan': NaN and infinity are not accepted"},
      {"long_token.g2o",
       std::string(kChain) + "EDGE_SE2 0 2 " + std::string(1 << 20, '9') + "q 0 0 1 0 0 1 0 1\n",
       ":6: dx is '9999999999999999999999999999999999999999...' (1048577 bytes), not a number"},
      {"garbage.g2o", garbage, ":1: unknown tag '\\x7fELF\\x02\\x01\\x01\\x00\\x1b[31m\\xff\\xfe'"},
      {"truncated.g2o", std::string(kChain) + "EDGE_SE2 0 2 1 0\n",
       ":6: EDGE_SE2 line is truncated"},
      {"not_spd.g2o", std::string(kChain) + "EDGE_SE2 0 2 2 0 0 1 0 0 -1 0 1\n",
       ":6: the information matrix is not symmetric positive definite"},
      {"unknown_tag.g2o", std::string(kChain) + "EDGE_FOO 0 2\n", ":6: unknown tag 'EDGE_FOO'"},
      {"extra_field.g2o", std::string(kChain) + "EDGE_SE2 0 2 2 0 0 1 0 0 1 0 1 7\n",
       ":6: EDGE_SE2 line has 12 fields, expected 11 (extra: '7')"},
      {"no_vertex.g2o", std::string(kChain) + "EDGE_SE2 0 9 2 0 0 1 0 0 1 0 1\n",
       ":6: EDGE_SE2 refers to pose 9, which no VERTEX line defines"},
      {"duplicate.g2o", std::string(kChain) + "VERTEX_SE2 1 5 5 0\n",
       ":6: duplicate vertex id 1: line 2 already defines it"},
      {"negative_id.g2o", std::string(kChain) + "EDGE_SE2 0 -2 2 0 0 1 0 0 1 0 1\n",
       ":6: pose b is '-2', not a non-negative integer id"},
      {"ambiguous.txt", "EDGE2 0 1 1 0 0 1 0 1 1 0 0\n", ":1: EDGE2 lines are ambiguous"},
      {"empty.g2o", "# only a comment\n", ": empty file: no vertex and no factor"},
      {"missing.g2o", "", ": file does not exist"},
      {"", "", ": is a directory, not a file"},
  };
}

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/hamal_bad_input_XXXXXX";
    ASSERT_NE(mkdtemp(dir_.data()), nullptr);
  }
  void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }

  // Writes the bad file (except "missing") and returns its path.
  std::string make(const BadFile& bad) const {
    if (bad.name.empty()) return dir_;
    const std::string path = dir_ + "/" + bad.name;
    if (bad.name != "missing.g2o") std::ofstream(path, std::ios::binary) << bad.content;
    return path;
  }
  std::string file(const std::string& name) const { return dir_ + "/" + name; }

  // An error of `program`, exit status 1, naming `expected`, fit to print.
  void expectError(const CommandResult& r, const std::string& program, const std::string& expected,
                   const std::string& command) const {
    EXPECT_EQ(r.status, 1) << command << "\n" << r.output.substr(0, 2000);
    EXPECT_EQ(r.signal, 0) << command;
    EXPECT_TRUE(contains(r.output, program + ": error: ")) << command << "\n"
                                                           << r.output.substr(0, 2000);
    EXPECT_TRUE(contains(r.output, expected)) << command << "\nexpected: " << expected << "\n"
                                              << r.output.substr(0, 2000);
    EXPECT_TRUE(fitsATerminal(r.output)) << command;
    EXPECT_LT(r.output.size(), 3000u) << command;
    // Nothing was solved before the error.
    EXPECT_FALSE(contains(r.output, "chi2")) << command << "\n" << r.output.substr(0, 2000);
  }

  std::string dir_;
};

TEST_F(BadInput, EveryBadFileThroughEveryExecutableAndBackend) {
  const std::vector<std::string> backends = allBackends();
  ASSERT_GE(backends.size(), 7u);
  for (const BadFile& bad : badFiles()) {
    const std::string path = make(bad);
    for (const std::string& backend : backends) {
      const std::string solve = app("hamal_solve") + " --plugin " + plugin() + " --backend " +
                                backend + " '" + path + "'";
      expectError(run(solve), "hamal_solve", path + bad.expected, solve);
      const std::string bench = app("hamal_bench") + " --plugin " + plugin() + " --backend " +
                                backend + " --data '" + path + "'";
      expectError(run(bench), "hamal_bench", path + bad.expected, bench);
    }
  }
}

TEST_F(BadInput, OptionsAndOutputPathsAreCheckedBeforeAnyWork) {
  // A bad option value is reported before the input is even looked at (the
  // input here does not exist), and before hamal_bench's reference solve.
  const std::string missing = file("missing.g2o");
  std::ofstream(file("chain.g2o")) << kChain;
  const std::string good = file("chain.g2o");
  struct Case {
    std::string program, arguments, expected;
  };
  const std::vector<Case> cases = {
      {"hamal_solve", missing + " --backend aprilsam:delta_t=abc",
       "aprilsam: option delta_t=abc is not a finite number"},
      {"hamal_bench", "--data " + missing + " --backend aprilsam:delta_t=abc",
       "aprilsam: option delta_t=abc is not a finite number"},
      {"hamal_bench", "--data " + missing + " --backend cholesky --reference ceres:threads=0",
       "ceres: option threads must be >= 1"},
      {"hamal_solve", good + " --output " + dir_, "--output " + dir_ + ": is a directory"},
      {"hamal_solve", good + " --output " + file("no/such/dir/x.g2o"),
       "--output " + file("no/such/dir/x.g2o") + ": directory " + file("no/such/dir") +
           " does not exist"},
      {"hamal_bench", "--generate 50 --backend cholesky --rows " + dir_,
       "--rows " + dir_ + ": is a directory"},
      {"hamal_bench", "--generate 50 --backend cholesky --summary " + file("none/s.json"),
       "--summary " + file("none/s.json") + ": directory " + file("none") + " does not exist"},
      {"hamal_generate", "--poses 20 --output " + dir_, "--output " + dir_ + ": is a directory"},
      {"hamal_generate", "--poses 20 --output " + file("w.g2o") + " --truth " + dir_,
       "--truth " + dir_ + ": is a directory"},
  };
  for (const Case& c : cases) {
    const std::string command = app(c.program) + " " + c.arguments;
    const CommandResult r = run(command);
    expectError(r, c.program, c.expected, command);
    EXPECT_FALSE(contains(r.output, "batch optimum")) << command << "\n" << r.output;
    EXPECT_FALSE(contains(r.output, "synthetic Manhattan world")) << command << "\n" << r.output;
  }
}

TEST_F(BadInput, AnEmptyPluginEntryIsAnError) {
  for (const std::string program : {"hamal_solve", "hamal_bench", "hamal_generate"}) {
    for (const std::string& list : std::vector<std::string>{",,", plugin() + ",", "," + plugin()}) {
      const std::string command = app(program) + " --plugin '" + list + "' --list-backends";
      expectError(run(command), program,
                  "--plugin '" + list + "' has an empty entry; give one path per entry", command);
    }
  }
  // The rule for HAMAL_PLUGIN_PATH's directories is in --help.
  const CommandResult help = run(app("hamal_solve") + " --help");
  EXPECT_EQ(help.status, 0);
  EXPECT_TRUE(contains(help.output, "lib*.so is loaded")) << help.output;
  EXPECT_TRUE(contains(help.output, "skipped")) << help.output;
}

TEST_F(BadInput, NumericalTroubleIsAStatusNeverAnAbortNorAnInfiniteOk) {
  // Accepted by the reader (each number's square fits a double), trouble
  // for the solvers: an information of 1e12 on one loop closure
  // (ill-conditioned), and a loop closure of 1e150 m with information 1e150
  // (chi2 beyond a double wherever the solve starts).
  std::string ill;
  for (int i = 0; i < 50; ++i)
    ill += "VERTEX_SE2 " + std::to_string(i) + " " + std::to_string(i) + " 0 0\n";
  for (int i = 0; i + 1 < 50; ++i)
    ill += "EDGE_SE2 " + std::to_string(i) + " " + std::to_string(i + 1) + " 1 0 0 1 0 0 1 0 1\n";
  ill += "EDGE_SE2 0 49 49.5 0.3 0.1 1e12 0 0 1e12 0 1e12\n";
  std::string far = kChain;
  far += "EDGE_SE2 0 2 1e150 0 0 1e150 0 0 1e150 0 1e150\n";
  std::ofstream(file("ill.g2o")) << ill;
  std::ofstream(file("far.g2o")) << far;
  for (const std::string& backend : allBackends()) {
    for (const std::string name : {"ill.g2o", "far.g2o"}) {
      for (const std::string mode : {"", " --incremental"}) {
        const std::string command = app("hamal_solve") + " --plugin " + plugin() + " --backend " +
                                    backend + " " + file(name) + mode;
        const CommandResult r = run(command);
        EXPECT_EQ(r.signal, 0) << command << "\n" << r.output;
        EXPECT_TRUE(r.status == 0 || r.status == 2) << command << "\n" << r.output;
        EXPECT_TRUE(fitsATerminal(r.output)) << command;
        if (r.status == 0) {
          EXPECT_FALSE(contains(r.output, "chi2 after:  inf")) << command << "\n" << r.output;
          EXPECT_FALSE(contains(r.output, "chi2 after:  nan")) << command << "\n" << r.output;
        }
        if (name == std::string("far.g2o") && mode[0] == '\0') {
          EXPECT_EQ(r.status, 2) << command << "\n" << r.output;
        }
      }
    }
  }
  const CommandResult cholesky = run(app("hamal_solve") + " --backend cholesky " + file("ill.g2o"));
  EXPECT_TRUE(contains(cholesky.output,
                       "ill-conditioned, not unconstrained: factor EDGE_SE2 on "
                       "x0, x49"))
      << cholesky.output;
}

TEST_F(BadInput, BenchSaysWhyTheReferenceGivesNoRatio) {
  // Forced to one iteration, the reference converges neither from odometry
  // nor from LAGO: the table says n/a, and why, instead of a ratio.
  const std::string command = app("hamal_bench") +
                              " --generate 300 --backend cholesky --chi2_every 0 "
                              "--reference cholesky:max_iterations=1";
  const CommandResult r = run(command);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "       n/a  ")) << r.output;
  EXPECT_TRUE(
      contains(r.output, "chi2/opt: n/a: no optimum: the reference did not converge from odometry"))
      << r.output;
}

}  // namespace
}  // namespace hamal
