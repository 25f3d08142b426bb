// The executables as a user runs them (apps/hamal_*.cc): a generated world
// solved and written as g2o that reads back, listings of what is registered,
// plugins, and errors that say what is wrong ("hamal_x: error: ...", exit 1).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "backends/builtins.h"
#include "core/graph_io.h"
#include "factors/max_mixture_factor.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

using testing::CommandResult;
CommandResult run(const std::string& command_line) { return testing::runCommand(command_line); }

std::string app(const std::string& name) { return testing::buildPath("apps/" + name); }
std::string plugin() { return testing::buildPath("plugins/libhamal_example_plugin.so"); }

class Executables : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/hamal_apps_XXXXXX";
    ASSERT_NE(mkdtemp(dir_.data()), nullptr);
  }
  void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }
  std::string file(const std::string& name) const { return dir_ + "/" + name; }
  std::string dir_;
};

bool contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

TEST_F(Executables, BatchSolvesFromLagoAndSayBadInitialisations) {
  const CommandResult gen =
      run(app("hamal_generate") + " --poses 400 --seed 3 --output " + file("w.g2o"));
  ASSERT_EQ(gen.status, 0) << gen.output;
  const CommandResult solve =
      run(app("hamal_solve") + " " + file("w.g2o") + " --backend cholesky --init lago");
  ASSERT_EQ(solve.status, 0) << solve.output;
  EXPECT_TRUE(contains(solve.output, "from LAGO's initial values")) << solve.output;
  EXPECT_TRUE(contains(solve.output, "status:      ok")) << solve.output;

  const CommandResult bench = run(app("hamal_bench") + " --generate 300 --backend cholesky " +
                                  "--batch --init lago --reference cholesky");
  ASSERT_EQ(bench.status, 0) << bench.output;
  EXPECT_TRUE(contains(bench.output, "batch optimum (cholesky, from lago)")) << bench.output;
  EXPECT_TRUE(contains(bench.output, "(from LAGO:")) << bench.output;

  for (const std::string& bad :
       {app("hamal_solve") + " " + file("w.g2o") + " --init spanning",
        app("hamal_solve") + " " + file("w.g2o") + " --init lago --incremental",
        app("hamal_bench") + " --generate 50 --batch --init spanning"}) {
    const CommandResult r = run(bad);
    EXPECT_EQ(r.status, 1) << bad << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, "error:")) << r.output;
  }
}

TEST_F(Executables, GenerateThenSolveWritesReadableG2o) {
  const CommandResult gen = run(app("hamal_generate") + " --poses 150 --seed 4 --output " +
                                file("w.g2o") + " --truth " + file("t.g2o"));
  ASSERT_EQ(gen.status, 0) << gen.output;
  EXPECT_TRUE(contains(gen.output, "150 poses, 149 odometry edges")) << gen.output;

  const CommandResult solve = run(app("hamal_solve") + " --data " + file("w.g2o") +
                                  " --backend cholesky --output " + file("out.g2o"));
  ASSERT_EQ(solve.status, 0) << solve.output;
  EXPECT_TRUE(contains(solve.output, "chi2 before:")) << solve.output;
  EXPECT_TRUE(contains(solve.output, "chi2 after:")) << solve.output;
  EXPECT_TRUE(contains(solve.output, "status:      ok")) << solve.output;

  Registry registry;
  registerBuiltins(registry);
  const Graph input = readGraph(file("w.g2o"), registry);
  const Graph result = readGraph(file("out.g2o"), registry);
  EXPECT_EQ(result.factors.size(), input.factors.size());
  EXPECT_EQ(result.initial.size(), 150u);
  const Graph truth = readGraph(file("t.g2o"), registry);
  EXPECT_EQ(truth.initial.size(), 150u);

  // The incremental mode and a positional input work too.
  const CommandResult incremental =
      run(app("hamal_solve") + " " + file("w.g2o") + " --backend ceres --incremental");
  ASSERT_EQ(incremental.status, 0) << incremental.output;
  EXPECT_TRUE(contains(incremental.output, "incremental (thesis protocol, 150 steps)"))
      << incremental.output;
}

// A g2o user's robust file: a FIX line and a false loop closure wrapped in
// EDGE_MAXMIX. Every back-end keeps the fixed pose where the file puts it
// and switches the false edge off; --output writes both back.
TEST_F(Executables, FixAndMaxMixtureLinesSolveAndRoundTrip) {
  {
    std::ofstream out(file("robust.g2o"));
    out << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\nVERTEX_SE2 3 3 0 0\n"
           "FIX 0\n";
    for (int i = 0; i < 3; ++i)
      out << "EDGE_SE2 " << i << " " << i + 1 << " 1.02 0.01 0.01 100 0 0 100 0 400\n";
    out << "EDGE_MAXMIX 0.01 1e-9 EDGE_SE2 0 3 3.0 0.0 0.0 100 0 0 100 0 400\n"
        << "EDGE_MAXMIX 0.01 1e-9 EDGE_SE2 0 2 -4.0 6.0 2.0 100 0 0 100 0 400\n";
  }
  Registry registry;
  registerBuiltins(registry);
  const Graph input = readGraph(file("robust.g2o"), registry);
  for (const std::string backend : {"cholesky", "ceres", "aprilsam"}) {
    for (const std::string mode : {"", " --incremental"}) {
      SCOPED_TRACE(backend + mode);
      const std::string out = file("out_" + backend + ".g2o");
      const CommandResult solve = run(app("hamal_solve") + " " + file("robust.g2o") +
                                      " --backend " + backend + mode + " --output " + out);
      ASSERT_EQ(solve.status, 0) << solve.output;
      const Graph result = readGraph(out, registry);
      EXPECT_EQ(result.fixed, std::set<Key>{X(0)});
      EXPECT_EQ(result.initial.pose(X(0)).x, 0.0);
      EXPECT_EQ(result.initial.pose(X(0)).theta, 0.0);
      ASSERT_EQ(result.factors.size(), input.factors.size());
      const auto* truth = dynamic_cast<const MaxMixtureFactor*>(result.factors[3].get());
      const auto* outlier = dynamic_cast<const MaxMixtureFactor*>(result.factors[4].get());
      ASSERT_TRUE(truth && outlier);
      EXPECT_EQ(truth->activeComponent(result.initial), 0u);
      EXPECT_EQ(outlier->activeComponent(result.initial), 1u);
      EXPECT_NEAR(result.initial.pose(X(3)).x, 3.04, 0.03);
    }
  }
}

TEST_F(Executables, UnknownBackEndListsTheRegisteredOnes) {
  const CommandResult r = run(app("hamal_solve") + " --data nothing.g2o --backend nosuch");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "hamal_solve: error: unknown back-end 'nosuch'")) << r.output;
  EXPECT_TRUE(contains(r.output, "ceres")) << r.output;
  EXPECT_TRUE(contains(r.output, "cholesky")) << r.output;
}

TEST_F(Executables, UnknownOptionListsTheKnownKeys) {
  const CommandResult r =
      run(app("hamal_bench") + " --generate 20 --backend cholesky:no_such_key=1");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "hamal_bench: error:")) << r.output;
  EXPECT_TRUE(contains(r.output, "no_such_key")) << r.output;
  EXPECT_TRUE(contains(r.output, "max_iterations")) << r.output;
}

// The old spellings of renamed flags work for a release and say what to use
// instead; both spellings at once are an error naming them.
TEST_F(Executables, OldFlagSpellingsWorkAndNameTheNewOne) {
  ASSERT_EQ(run(app("hamal_generate") + " --poses 30 --output " + file("w.g2o")).status, 0);
  const CommandResult now = run(app("hamal_solve") + " --data " + file("w.g2o"));
  ASSERT_EQ(now.status, 0) << now.output;
  EXPECT_FALSE(contains(now.output, "old spelling")) << now.output;
  for (const std::string old : {" --input ", " --input=", " -input "}) {
    const CommandResult r = run(app("hamal_solve") + old + file("w.g2o"));
    ASSERT_EQ(r.status, 0) << old << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, "hamal_solve: --input is an old spelling; use --data"))
        << r.output;
    EXPECT_TRUE(contains(r.output, "status:      ok")) << r.output;
  }
  const CommandResult both =
      run(app("hamal_solve") + " --input " + file("w.g2o") + " --data " + file("w.g2o"));
  EXPECT_EQ(both.status, 1) << both.output;
  EXPECT_TRUE(contains(both.output, "--input is an old spelling of --data; give --data only"))
      << both.output;

  // hamal_bench's --backends is --backend, which takes one or several specs.
  const CommandResult old_list =
      run(app("hamal_bench") + " --generate 30 --backends \"cholesky;ceres\" --reference none");
  ASSERT_EQ(old_list.status, 0) << old_list.output;
  EXPECT_TRUE(
      contains(old_list.output, "hamal_bench: --backends is an old spelling; use --backend"))
      << old_list.output;
  const CommandResult new_list =
      run(app("hamal_bench") + " --generate 30 --backend \"cholesky;ceres\" --reference none");
  ASSERT_EQ(new_list.status, 0) << new_list.output;
  const CommandResult repeated = run(
      app("hamal_bench") + " --generate 30 --backend cholesky --backend ceres --reference none");
  ASSERT_EQ(repeated.status, 0) << repeated.output;
  for (const CommandResult* r : {&old_list, &new_list, &repeated}) {
    EXPECT_TRUE(contains(r->output, "cholesky")) << r->output;
    EXPECT_TRUE(contains(r->output, "ceres")) << r->output;
  }
}

TEST_F(Executables, MissingInputIsAnErrorNamingTheFile) {
  const CommandResult r = run(app("hamal_solve") + " --data " + file("missing.g2o"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_TRUE(contains(r.output, "hamal_solve: error:")) << r.output;
  EXPECT_TRUE(contains(r.output, "missing.g2o")) << r.output;
}

TEST_F(Executables, ListBackendsAndFactors) {
  for (const char* name : {"hamal_solve", "hamal_bench", "hamal_generate"}) {
    const CommandResult r = run(app(name) + " --list-backends");
    ASSERT_EQ(r.status, 0) << name << r.output;
    EXPECT_TRUE(contains(r.output, "ceres\n")) << r.output;
    EXPECT_TRUE(contains(r.output, "cholesky\n")) << r.output;
  }
  const CommandResult f = run(app("hamal_solve") + " --list_factors");
  ASSERT_EQ(f.status, 0) << f.output;
  EXPECT_TRUE(contains(f.output, "EDGE_SE2")) << f.output;
}

TEST_F(Executables, PluginsByFlagAndBySearchPath) {
  const CommandResult by_flag =
      run(app("hamal_solve") + " --plugin " + plugin() + " --list-backends");
  ASSERT_EQ(by_flag.status, 0) << by_flag.output;
  EXPECT_TRUE(contains(by_flag.output, "dense-gauss-newton")) << by_flag.output;

  const CommandResult by_path = run("HAMAL_PLUGIN_PATH=" + testing::buildPath("plugins") + " " +
                                    app("hamal_bench") + " --list-factors");
  ASSERT_EQ(by_path.status, 0) << by_path.output;
  EXPECT_TRUE(contains(by_path.output, "EDGE_SE2_CAUCHY")) << by_path.output;

  // Both: the same plugin twice is a duplicate, reported, not a crash.
  const CommandResult twice =
      run("HAMAL_PLUGIN_PATH=" + testing::buildPath("plugins") + " " + app("hamal_solve") +
          " --plugin " + plugin() + " --list-backends");
  EXPECT_EQ(twice.status, 1) << twice.output;
  EXPECT_TRUE(contains(twice.output, "already registered")) << twice.output;

  const CommandResult bad =
      run(app("hamal_solve") + " --plugin " + file("nope.so") + " --list-backends");
  EXPECT_EQ(bad.status, 1) << bad.output;
  EXPECT_TRUE(contains(bad.output, "hamal_solve: error: plugin " + file("nope.so"))) << bad.output;
}

TEST_F(Executables, BenchWritesRowsAndSummary) {
  const CommandResult r =
      run(app("hamal_bench") + " --generate 80 --backend \"cholesky;ceres\" --rows " +
          file("rows.jsonl") + " --summary " + file("summary.json") + " --repeat 2");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(contains(r.output, "chi2/opt")) << r.output;
  // The repeats take turns: run 1 of each back-end, then run 2.
  const auto at = [&](const std::string& s) { return r.output.find(s); };
  ASSERT_NE(at("running cholesky (run 2 of 2)"), std::string::npos) << r.output;
  EXPECT_LT(at("running cholesky (run 1 of 2)"), at("running ceres (run 1 of 2)")) << r.output;
  EXPECT_LT(at("running ceres (run 1 of 2)"), at("running cholesky (run 2 of 2)")) << r.output;
  EXPECT_LT(at("running cholesky (run 2 of 2)"), at("running ceres (run 2 of 2)")) << r.output;
  std::ifstream summary_file(file("summary.json"));
  const auto summary = nlohmann::json::parse(summary_file);
  ASSERT_EQ(summary.size(), 2u);
  EXPECT_EQ(summary[0]["backend"], "cholesky");
  EXPECT_EQ(summary[1]["backend"], "ceres");
  for (const auto& s : summary) {
    EXPECT_EQ(s["steps"], 80);
    EXPECT_EQ(s["repeats"], 2);
    EXPECT_NEAR(s["chi2_ratio"].get<double>(), 1.0, 1e-4);
  }
  std::ifstream rows(file("rows.jsonl"));
  std::string line;
  int count = 0;
  while (std::getline(rows, line)) ++count, nlohmann::json::parse(line);
  EXPECT_EQ(count, 2 * 2 * 80);  // two back-ends, two runs each
}

// --batch (the scale study's batch figures): one solve per back-end from
// odometry, which reaches the reference's batch optimum.
TEST_F(Executables, BenchBatchSolvesOncePerBackEnd) {
  const CommandResult r =
      run(app("hamal_bench") + " --generate 200 --batch --backend \"cholesky;ceres\" --rows " +
          file("rows.csv") + " --summary " + file("summary.json"));
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream summary_file(file("summary.json"));
  const auto summary = nlohmann::json::parse(summary_file);
  ASSERT_EQ(summary.size(), 2u);
  for (const auto& s : summary) {
    EXPECT_EQ(s["steps"], 1);
    EXPECT_EQ(s["batch_steps"], 1);
    EXPECT_NEAR(s["chi2_ratio"].get<double>(), 1.0, 1e-4);
  }
  std::ifstream rows(file("rows.csv"));
  std::string line;
  int count = 0;
  while (std::getline(rows, line)) count += contains(line, ",199,") && contains(line, ",batch,");
  EXPECT_EQ(count, 2);
}

TEST_F(Executables, HelpDescribesTheFlags) {
  const CommandResult r = run(app("hamal_bench") + " --help");
  EXPECT_EQ(r.status, 0) << r.output;
  for (const char* flag : {"-backends", "-backend", "-data", "-generate", "-rows", "-summary",
                           "-repeat", "-max_steps", "-chi2_every", "-plugin", "-list_backends"})
    EXPECT_TRUE(contains(r.output, flag)) << flag << "\n" << r.output;
}

}  // namespace
}  // namespace hamal
