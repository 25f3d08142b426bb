// Bad input as a hostile user gives it, one table row per kind,
// run through every executable and, where a back-end is chosen, every
// registered back-end (the example plugin's included): each is a clear
// "program: error: file:line: reason" with exit status 1, before any work is
// done, in a message that fits a terminal (no raw control bytes, a bounded
// length); a numerical failure is exit status 2, never an abort; an "ok"
// never comes with a chi2 that is not finite.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
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
      {"nul_in_number.g2o",
       std::string(kChain) + "EDGE_SE2 0 2 1" + std::string(1, '\0') + "99 0 0 1 0 0 1 0 1\n",
       ":6: dx is '1\\x0099', not a number"},
      {"dth_1e150.g2o", std::string(kChain) + "EDGE_SE2 0 2 2 0 1e150 1 0 0 1 0 1\n",
       ":6: dth is '1e150': an angle beyond 1e6 rad cannot be wrapped"},
      {"theta_1e7.g2o", std::string(kChain) + "VERTEX_SE2 3 3 0 -1e7\n",
       ":6: theta is '-1e7': an angle beyond 1e6 rad cannot be wrapped"},
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

// A command line of one program and what its error must say.
struct ToolCase {
  std::string program, arguments, expected;
};

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

  // Each case an error of its program naming `expected`, before any work.
  // A message that names a chi2 option is matched whole (expectError takes
  // "chi2" in the output for work done).
  void expectErrors(const std::vector<ToolCase>& cases) const {
    for (const ToolCase& c : cases) {
      const std::string command = app(c.program) + " " + c.arguments;
      const CommandResult r = run(command);
      if (contains(c.expected, "chi2")) {
        EXPECT_EQ(r.status, 1) << command << "\n" << r.output;
        EXPECT_EQ(r.output, c.program + ": error: " + c.expected + "\n") << command;
      } else {
        expectError(r, c.program, c.expected, command);
      }
    }
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
      {"hamal_solve", good + " --backend cholesky:robust=gnc-tls",
       good + ": no loop closure (a factor between poses whose ids differ by more than one): "
              "robust=gnc-tls has nothing to decide"},
      {"hamal_solve", good + " --backend cholesky:robust=often",
       "cholesky: option robust=often is not one of"},
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

// What a tool's output path names: a character device, a FIFO, a file.
bool isCharDevice(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}
bool isFifo(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Every output of every tool, as "@" in its arguments; `list` says that the
// node is the false-edge list beside hamal_spoil's --output "@".
struct OutputCase {
  std::string program, arguments;
  bool list = false;
};

class Outputs : public BadInput {
 protected:
  void SetUp() override {
    BadInput::SetUp();
    std::ofstream(file("chain.g2o")) << kChain;
    const CommandResult world =
        run(app("hamal_generate") + " --poses 100 --output " + file("world.g2o"));
    ASSERT_EQ(world.status, 0) << world.output;
    const CommandResult spoiled = run(app("hamal_spoil") + " --data " + file("world.g2o") +
                                      " --outliers 3 --output " + file("spoiled.g2o"));
    ASSERT_EQ(spoiled.status, 0) << spoiled.output;
  }

  std::vector<OutputCase> cases() const {
    const std::string robust = "--data " + file("spoiled.g2o") + " --backend cholesky ";
    return {
        {"hamal_solve", file("chain.g2o") + " --backend cholesky --output @"},
        {"hamal_generate", "--poses 20 --output @"},
        {"hamal_generate", "--poses 20 --output " + file("w.g2o") + " --truth @"},
        {"hamal_bench", "--generate 50 --backend cholesky --rows @"},
        {"hamal_bench", "--generate 50 --backend cholesky --summary @"},
        {"hamal_flag", "world office --output @"},
        {"hamal_robust", robust + "--rows @"},
        {"hamal_robust", robust + "--summary @"},
        {"hamal_robust", robust + "--weights @"},
        {"hamal_robust", robust + "--output @"},
        {"hamal_spoil", "--data " + file("world.g2o") + " --outliers 3 --output @"},
        {"hamal_spoil", "--data " + file("world.g2o") + " --outliers 3 --output @", true},
    };
  }

  // The command of `c` writing to `node` (or to its graph when `c.list`).
  static std::string command(const OutputCase& c, const std::string& node) {
    std::string arguments = c.arguments;
    const std::string out = c.list ? node.substr(0, node.size() - 6) : node;
    arguments.replace(arguments.find('@'), 1, out);
    return app(c.program) + " " + arguments;
  }
  static std::string nodeName(const OutputCase& c, int i) {
    return "node" + std::to_string(i) + (c.list ? ".g2o.false" : "");
  }

  // A character device twin of /dev/null (minor 3) or /dev/full (minor 7):
  // renaming over the real node would destroy it. Only root may make one.
  bool makeDevice(const std::string& path, unsigned minor) const {
    return ::mknod(path.c_str(), S_IFCHR | 0666, makedev(1, minor)) == 0;
  }

  // Every output of every tool into a twin of /dev/null (minor 3) or
  // /dev/full (minor 7): the exit status, the message after "program: error:
  // <node>" (if any), and the node still a device.
  void throughDevices(unsigned minor, int status, const std::string& message) const {
    const auto all = cases();
    for (std::size_t i = 0; i < all.size(); ++i) {
      const std::string node = file(nodeName(all[i], int(i)));
      if (!makeDevice(node, minor)) GTEST_SKIP() << "mknod needs root";
      const std::string c = command(all[i], node);
      const CommandResult r = run(c);
      EXPECT_EQ(r.status, status) << c << "\n" << r.output;
      if (!message.empty())
        EXPECT_TRUE(contains(r.output, all[i].program + ": error: " + node + message)) << c << "\n"
                                                                                       << r.output;
      EXPECT_TRUE(isCharDevice(node)) << c << ": the device was replaced";
    }
    expectNoTemporaries();
  }

  // No temporary left behind in the scratch directory.
  void expectNoTemporaries() const {
    for (const auto& entry : std::filesystem::directory_iterator(dir_))
      EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
};

TEST_F(Outputs, ADeviceIsWrittenInPlaceNeverReplaced) { throughDevices(3, 0, ""); }

TEST_F(Outputs, AFullDeviceIsAnErrorNamingThePathAndTheReason) {
  throughDevices(7, 1, ": writing failed: No space left on device");
}

TEST_F(Outputs, AFifoIsWrittenInPlaceNeverReplaced) {
  const auto all = cases();
  for (std::size_t i = 0; i < all.size(); ++i) {
    const std::string node = file(nodeName(all[i], int(i)));
    ASSERT_EQ(::mkfifo(node.c_str(), 0666), 0);
    const std::string received = file("received" + std::to_string(i));
    // A reader on the other end (bounded, should the tool never open it).
    const std::string c = command(all[i], node);
    const CommandResult r = run("{ timeout 5 cat '" + node + "' > '" + received + "' & " + c +
                                "; s=$?; wait; exit $s; }");
    EXPECT_EQ(r.status, 0) << c << "\n" << r.output;
    EXPECT_TRUE(isFifo(node)) << c << ": the FIFO was replaced";
    EXPECT_FALSE(readAll(received).empty()) << c << ": nothing came through the FIFO";
  }
  expectNoTemporaries();
}

TEST_F(Outputs, TwoOutputsOnOnePathAreRefusedBeforeAnyWork) {
  const std::string x = file("x"), dot_x = dir_ + "/./x";
  struct Case {
    std::string program, arguments, expected;
  };
  const std::vector<Case> cases = {
      {"hamal_bench", "--generate 50 --backend cholesky --rows " + x + " --summary " + dot_x,
       "--summary " + dot_x + " names the same file as --rows " + x},
      {"hamal_generate", "--poses 20 --output " + x + " --truth " + dot_x,
       "--truth " + dot_x + " names the same file as --output " + x},
      {"hamal_robust",
       "--data " + file("spoiled.g2o") + " --backend cholesky --rows " + x + " --summary " + x,
       "--summary " + x + " names the same file as --rows " + x},
      {"hamal_flag", "run --trajectory " + x + " --landmarks_out " + x,
       "--landmarks_out " + x + " names the same file as --trajectory " + x},
      {"hamal_spoil", "--data " + file("world.g2o") + " --outliers 3 --output " + x + ".false", ""},
  };
  for (const Case& c : cases) {
    const std::string command = app(c.program) + " " + c.arguments;
    const CommandResult r = run(command);
    if (c.expected.empty()) {  // OUT.false beside OUT.false is a path of its own
      EXPECT_EQ(r.status, 0) << command << "\n" << r.output;
      continue;
    }
    expectError(r, c.program, c.expected, command);
    EXPECT_FALSE(std::filesystem::exists(x)) << command;
  }
  // Devices may be shared: each output is written there in turn.
  const CommandResult shared = run(app("hamal_bench") +
                                   " --generate 50 --backend cholesky --rows /dev/null"
                                   " --summary /dev/null");
  EXPECT_EQ(shared.status, 0) << shared.output;
}

TEST_F(Outputs, ARowsFileIsWholeOrUntouched) {
  // Beyond a file size limit (SIGXFSZ ignored, so the write fails with
  // EFBIG): the old file is kept, no temporary is left.
  const std::string rows = file("rows.csv");
  for (const std::string& c :
       {app("hamal_bench") + " --generate 300 --backend cholesky --rows " + rows,
        app("hamal_robust") + " --data " + file("spoiled.g2o") + " --backend cholesky --rows " +
            rows}) {
    std::ofstream(rows) << "old\n";
    const CommandResult r = run("{ trap '' XFSZ; ulimit -f 2; " + c + "; }");
    EXPECT_EQ(r.status, 1) << c << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, rows + ": writing failed: File too large")) << c << "\n"
                                                                               << r.output;
    EXPECT_EQ(readAll(rows), "old\n") << c;
  }
  expectNoTemporaries();
}

// An output that is one of the run's inputs (the same inode, through a
// symbolic link too) would be replaced before or while it is read: refused
// before any work, the input untouched.
TEST_F(Outputs, AnOutputThatIsAnInputIsRefusedBeforeAnyWork) {
  const std::string chain = file("chain.g2o"), world = file("world.g2o");
  const std::string spoiled = file("spoiled.g2o"), list = spoiled + ".false";
  const std::string plan = file("box.plan"), log = file("l_points.csv");
  std::ofstream(plan) << "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n"
                         "START 1 1 0\nROUTE 9 1\n";
  std::ofstream(log) << "ODOM 0 0 0 0 0 0 0 x 0\n";
  std::filesystem::create_symlink(chain, file("link.g2o"));
  std::filesystem::create_symlink(list, file("link.false"));
  const std::string robust = "--data " + spoiled + " --backend cholesky ";
  struct Case {
    std::string program, arguments, output, input;
  };
  const std::vector<Case> cases = {
      {"hamal_solve", chain + " --backend cholesky --output " + chain, chain, chain},
      {"hamal_solve", chain + " --backend cholesky --output " + file("link.g2o"), file("link.g2o"),
       chain},
      {"hamal_solve", "--data " + chain + " --output " + file("link.g2o"), file("link.g2o"),
       "--data " + chain},
      {"hamal_spoil", "--data " + world + " --outliers 3 --output " + world, world, world},
      {"hamal_spoil", "--data " + chain + " --outliers 0 --output " + file("link.g2o"),
       file("link.g2o"), chain},
      {"hamal_robust", robust + "--output " + spoiled, spoiled, spoiled},
      {"hamal_robust", robust + "--weights " + list, list, list},
      {"hamal_robust", robust + "--rows " + file("link.false"), file("link.false"), list},
      {"hamal_robust", robust + "--summary " + spoiled, spoiled, spoiled},
      {"hamal_bench", "--data " + world + " --backend cholesky --rows " + world, world, world},
      {"hamal_bench", "--data " + world + " --backend cholesky --summary " + world, world, world},
      {"hamal_flag", "run --world " + plan + " --trajectory " + plan, plan, plan},
      {"hamal_flag", "run --world " + plan + " --landmarks_out " + plan, plan, plan},
      {"hamal_log", "--data " + log + " --output " + file("l"), log, log},
  };
  for (const Case& c : cases) {
    std::map<std::string, std::string> before;
    for (const std::string& f : {chain, world, spoiled, list, plan, log}) before[f] = readAll(f);
    const std::string command = app(c.program) + " " + c.arguments;
    const CommandResult r = run(command);
    expectError(r, c.program, c.output + " is the input ", command);
    EXPECT_TRUE(contains(r.output, c.input + " (the same file)")) << command << "\n" << r.output;
    for (const auto& [f, content] : before) EXPECT_EQ(readAll(f), content) << command << ": " << f;
  }
  expectNoTemporaries();
}

// A run's outputs are put in place together, or none of them: an output
// that fails (a full device, written in place) leaves the others as they
// were, and hamal_spoil's list is never made beside a graph it failed to
// write.
TEST_F(Outputs, ARunsOutputsAreAllOrNone) {
  const std::string graph = file("g.g2o"), points = file("l_points.csv");
  std::ofstream(graph) << "old\n";
  std::ofstream(points) << "old\n";
  std::filesystem::create_symlink("/dev/full", file("l_trajectory.csv"));
  std::ofstream(file("robot.log")) << "ODOM 0 0 0 0 0 0 1 h 1\nODOM 1 0 0 0 0 0 2 h 2\n"
                                      "FLASER 3 1 1 1 0 0 0 0 0 0 3 h 3\n";
  struct Case {
    std::string command, kept;
  };
  const std::vector<Case> cases = {
      {app("hamal_generate") + " --poses 20 --output " + graph + " --truth /dev/full", graph},
      {app("hamal_log") + " --data " + file("robot.log") + " --output " + file("l"), points},
  };
  for (const Case& c : cases) {
    const CommandResult r = run(c.command);
    EXPECT_EQ(r.status, 1) << c.command << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, "writing failed: No space left on device")) << c.command << "\n"
                                                                               << r.output;
    EXPECT_EQ(readAll(c.kept), "old\n") << c.command << ": replaced by a run that failed";
  }
  const std::string node = file("full");
  if (!makeDevice(node, 7)) GTEST_SKIP() << "mknod needs root";
  const CommandResult r =
      run(app("hamal_spoil") + " --data " + file("world.g2o") + " --outliers 3 --output " + node);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_FALSE(std::filesystem::exists(node + ".false")) << r.output;
  expectNoTemporaries();
}

// Bad input found on a worker thread (trials are built on a pool) is an
// error of the program, not std::terminate.
TEST_F(BadInput, AnErrorOnAWorkerThreadIsAnErrorNotAnAbort) {
  for (const std::string world : {"CORRIDOR", "SQUARE"}) {
    const std::string command = app("hamal_moss") + " experiment --world " + world +
                                " --poses 1 --sizes 1 --threads 2 --output " + file(world);
    expectError(run(command), "hamal_moss", "need at least 2 poses", command);
  }
}

// Options of every tool: a negative count (gflags would read -1 as 2^64 - 1
// for an unsigned flag, and hamal_moss took a negative one as its default),
// seeds past 2^64 - 1, an option opening a ';' entry of a back-end list:
// each an error naming the option, before any work.
TEST_F(BadInput, CountsSeedsAndSpecListsAreCheckedByName) {
  std::ofstream(file("chain.g2o")) << kChain;
  const std::string chain = file("chain.g2o");
  expectErrors({
      {"hamal_generate", "--poses -5 --output " + file("w.g2o"),
       "--poses -5: must be a non-negative integer"},
      {"hamal_generate", "--poses 20 --seed=-1 --output " + file("w.g2o"),
       "--seed -1: must be a non-negative integer"},
      {"hamal_bench", "--generate 50 --backend cholesky --max_steps ' -1'",
       "--max_steps  -1: must be a non-negative integer"},
      {"hamal_spoil", "--data " + chain + " --outliers -3 --output " + file("s.g2o"),
       "--outliers -3: must be a non-negative integer"},
      {"hamal_robust", "-chi2_every=-1 --data " + chain + " --backend cholesky",
       "--chi2_every -1: must be a non-negative integer"},
      {"hamal_flag", "trials dynamic --trials=-1", "--trials -1: must be a non-negative integer"},
      {"hamal_flag", "trials dynamic --trials 0", "--trials must be at least 1"},
      // Refused whatever the seed: with the default one it used to run on
      // without end, filling its temporary file.
      {"hamal_flag", "trials dynamic --trials 18446744073709551615",
       "--trials 18446744073709551615: at most 1000000 trials per run"},
      {"hamal_flag", "trials dynamic --trials 18446744073709551615 --seed 2",
       "--trials 18446744073709551615: at most 1000000 trials per run"},
      {"hamal_flag", "trials static --seed 18446744073709551615 --trials 2",
       "the last seed would exceed 2^64 - 1"},
      {"hamal_moss", "experiment --poses -1 --output " + file("m"),
       "--poses -1: must be a non-negative integer"},
      {"hamal_moss", "experiment --map_poses -4 --output " + file("m"),
       "--map_poses -4: must be a non-negative integer"},
      {"hamal_moss", "experiment --threads -2 --output " + file("m"),
       "--threads -2: must be a non-negative integer"},
      {"hamal_moss", "experiment --seed -2 --output " + file("m"),
       "--seed -2: must be a non-negative integer"},
      {"hamal_bench", "--generate 50 --backend 'ceres:max_iterations=5;;every=2'",
       "'every=2' is an option without a back-end name before it"},
      {"hamal_moss", "experiment --sizes 0 --output " + file("m"),
       "--sizes: C = 0: a map keeps at least 1 node"},
      {"hamal_moss", "experiment --information nosuch --output " + file("m"),
       "--information: unknown scan matcher information 'nosuch'; expected hessian or censi"},
  });
}

// A loop closure of 1e151 m over 1 m odometry: the optimum's chi2 (3.3e301)
// is finite, but no estimate is resolved against it. Every back-end says
// so (exit 2), batch or incremental; ceres and aprilsam called it ok.
TEST_F(BadInput, ACostBeyondWhatRoundingResolvesIsNeverOk) {
  std::ofstream(file("far.g2o")) << kChain << "EDGE_SE2 0 2 1e151 0 0 1 0 0 1 0 1\n";
  for (const std::string& backend : allBackends()) {
    for (const std::string mode : {"", " --incremental"}) {
      const std::string command = app("hamal_solve") + " --plugin " + plugin() + " --backend " +
                                  backend + " " + file("far.g2o") + mode;
      const CommandResult r = run(command);
      EXPECT_EQ(r.status, 2) << command << "\n" << r.output;
      EXPECT_TRUE(contains(r.output, "numerical_failure")) << command << "\n" << r.output;
    }
  }
}

// A max-mixture's null hypothesis, whichever input makes it (a back-end
// option of hamal_robust, hamal_flag's flags, a graph file's fields), is
// held to one rule, worded alike.
TEST_F(BadInput, ANullHypothesisIsCheckedAlikeByEveryTool) {
  std::ofstream(file("chain.g2o")) << kChain;
  const std::string chain = file("chain.g2o");
  std::ofstream(file("mm.g2o")) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n"
                                << "EDGE_MAXMIX 0.1 5 EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n";
  const std::string scale = "is 5: a null hypothesis' information scale must be in (0, 1]";
  const std::string weight = "is 1: a null hypothesis' weight must be in (0, 1)";
  expectErrors({
      {"hamal_robust", "--data " + chain + " --backend 'cholesky:robust=maxmix,null_scale=5'",
       "cholesky: null_scale " + scale},
      {"hamal_flag", "trials static --trials 1 --max_mixture --null_scale 5",
       "--null_scale " + scale},
      {"hamal_solve", file("mm.g2o") + " --backend cholesky",
       "mm.g2o:3: EDGE_MAXMIX: scale_null " + scale},
      {"hamal_robust", "--data " + chain + " --backend 'cholesky:robust=maxmix,null_weight=1'",
       "cholesky: null_weight " + weight},
      {"hamal_flag", "trials static --trials 1 --max_mixture --null_weight 1",
       "--null_weight " + weight},
  });
}

// A comparison in which no back-end got through is not a success.
TEST_F(BadInput, BenchFailsWhenEveryBackEndFailed) {
  std::ofstream(file("far.g2o")) << kChain << "EDGE_SE2 0 2 1e150 0 0 1e150 0 0 1e150 0 1e150\n";
  const std::string command =
      app("hamal_bench") + " --data " + file("far.g2o") + " --backend cholesky --reference none";
  const CommandResult r = run(command);
  EXPECT_EQ(r.status, 2) << command << "\n" << r.output;
  EXPECT_TRUE(contains(r.output, "hamal_bench: every back-end failed")) << r.output;
  // With a reference from odometry, its retry from LAGO failing is a note.
  const CommandResult referenced =
      run(app("hamal_bench") + " --data " + file("far.g2o") + " --backend cholesky");
  EXPECT_EQ(referenced.status, 2) << referenced.output;
  EXPECT_TRUE(contains(referenced.output,
                       "nor from lago: LAGO initialisation: the orientation "
                       "system has no finite solution"))
      << referenced.output;
  std::ofstream(file("chain.g2o")) << kChain;
  const CommandResult good = run(app("hamal_bench") + " --data " + file("chain.g2o") +
                                 " --backend cholesky --reference none");
  EXPECT_EQ(good.status, 0) << good.output;
}

// Input that is not a text file: a line without end (/dev/zero) is cut at
// 16 MiB with its file and line, not read until memory runs out; a read
// error is one (not an "empty file"); a directory is said to be one.
TEST_F(BadInput, NonTextInputIsAnErrorWithFileAndLine) {
  std::ofstream(file("chain.g2o")) << kChain;
  const std::string zero = "/dev/zero:1: a line longer than 16 MiB: not a text file";
  expectErrors({
      {"hamal_solve", "/dev/zero --backend cholesky", zero},
      {"hamal_bench", "--data /dev/zero --backend cholesky", zero},
      {"hamal_flag", "run --world /dev/zero", zero},
      {"hamal_moss", "world /dev/zero", zero},
      {"hamal_robust",
       "--data " + file("chain.g2o") + " --false_edges /dev/zero --backend cholesky", zero},
      {"hamal_robust",
       "--data " + file("chain.g2o") + " --false_edges " + dir_ + " --backend cholesky",
       dir_ + ": is a directory, not a file"},
      {"hamal_solve", "/proc/self/mem --backend cholesky",
       "/proc/self/mem: read error: Input/output error"},
      {"hamal_solve", file("chain.g2o") + " " + file("other.g2o"),
       "more than one input ('" + file("chain.g2o") + "', '" + file("other.g2o") +
           "'): hamal_solve solves one graph"},
  });
}

}  // namespace
}  // namespace hamal
