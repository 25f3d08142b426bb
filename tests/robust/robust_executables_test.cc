// hamal_spoil and hamal_robust as a user (and the sweep runner) runs them:
// a spoiled file and its list that hamal_robust grades, the same file for the
// same seed, the spec options listed as the sweep runner reads them, and
// errors that say what is wrong (exit 1), not a hang, for impossible requests.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "apps/robust/false_edge_list.h"
#include "apps/robust/robust_evaluation.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

using testing::CommandResult;
CommandResult run(const std::string& command_line) { return testing::runCommand(command_line); }

std::string app(const std::string& name) { return testing::buildPath("apps/" + name); }

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class RobustExecutables : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/robust_exe_" + std::to_string(getpid());
    ASSERT_EQ(run("mkdir -p " + dir_).status, 0);
    apps::ManhattanWorldOptions w;
    w.poses = 200;
    const auto world = apps::generateManhattanWorld(w);
    clean_ = dir_ + "/clean.g2o";
    writeG2o(clean_, world.graph.initial, world.graph.factors);
  }
  void TearDown() override { run("rm -rf " + dir_); }
  std::string dir_, clean_;
};

TEST_F(RobustExecutables, SpoilThenGrade) {
  const std::string out = dir_ + "/s.g2o";
  const std::string spoil = app("hamal_spoil") + " --data " + clean_ +
                            " --outliers 20 --policy local-group --seed 4 --output ";
  auto r = run(spoil + out);
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string first = slurp(out), first_list = slurp(out + ".false");
  r = run(spoil + dir_ + "/again.g2o");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(slurp(dir_ + "/again.g2o"), first);
  EXPECT_NE(first_list.find("policy=local-group"), std::string::npos);

  r = run(app("hamal_robust") + " --data " + out + " --backend aprilsam:robust=maxmix --rows " +
          dir_ + "/rows.csv --summary " + dir_ + "/summary.json --output " + dir_ + "/est.g2o");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto s = nlohmann::json::parse(slurp(dir_ + "/summary.json"));
  // --output: the run's estimate with the spoiled graph's factors, false
  // edges too; over the true edges it has the summary's chi2.
  Registry reg;
  apps::setUpRegistry(reg, {});
  const Graph spoiled = readGraph(out, reg), written = readGraph(dir_ + "/est.g2o", reg);
  ASSERT_EQ(written.factors.size(), spoiled.factors.size());
  const apps::FalseEdgeList list = apps::readFalseEdges(out + ".false");
  EXPECT_NEAR(chi2(apps::cleanFactors(written, list.edges), written.initial),
              s["chi2_true"].get<double>(), 1e-6 * s["chi2_true"].get<double>());
  EXPECT_EQ(s["false_edges"], 20);
  EXPECT_EQ(s["robust"]["model"], "maxmix");
  EXPECT_EQ(s["mode"], "incremental");
  EXPECT_EQ(s["spoiling"]["seed"], "4");
  for (const char* k : {"ate_translation", "recall", "true_switched_off_share", "chi2_true",
                        "tls_objective", "tls_objective_clean", "seconds"})
    EXPECT_TRUE(s[k].is_number()) << k;
  EXPECT_NE(slurp(dir_ + "/rows.csv").find("aprilsam:robust=maxmix"), std::string::npos);

  r = run(app("hamal_robust") + " --data " + out + " --backend cholesky --batch --summary " + dir_ +
          "/b.json");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ + "/b.json"))["mode"], "batch");
}

// hamal_solve takes the loop-closure models too, for a file with no list of
// false edges: it counts the closures the model rejected, the same ones
// hamal_robust grades on the same file.
TEST_F(RobustExecutables, SolveCountsTheClosuresTheModelRejected) {
  const std::string out = dir_ + "/s.g2o";
  auto r =
      run(app("hamal_spoil") + " --data " + clean_ + " --outliers 20 --seed 2 --output " + out);
  ASSERT_EQ(r.status, 0) << r.output;
  r = run(app("hamal_robust") + " --data " + out + " --backend cholesky:robust=gnc-tls --batch " +
          "--summary " + dir_ + "/g.json");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto s = nlohmann::json::parse(slurp(dir_ + "/g.json"));
  const int rejected = s["true_switched_off"].get<int>() + s["false_switched_off"].get<int>();
  ASSERT_GT(rejected, 0);
  r = run(app("hamal_solve") + " --data " + out + " --backend cholesky:robust=gnc-tls");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("robust:      gnc-tls, " + std::to_string(rejected) + " of "),
            std::string::npos)
      << r.output;
}

TEST_F(RobustExecutables, FixedVariablesStayFixedInTheSpoiledFile) {
  apps::ManhattanWorldOptions w;
  w.poses = 100;
  const auto world = apps::generateManhattanWorld(w);
  const std::string fixed = dir_ + "/fixed.g2o", out = dir_ + "/fixed-spoiled.g2o";
  writeG2o(fixed, world.graph.initial, world.graph.factors, {X(0)});
  const auto r = run(app("hamal_spoil") + " --data " + fixed + " --outliers 5 --output " + out);
  ASSERT_EQ(r.status, 0) << r.output;
  Registry registry;
  apps::setUpRegistry(registry, {});
  const Graph back = readGraph(out, registry);
  EXPECT_EQ(back.fixed, std::set<Key>{X(0)});
  EXPECT_EQ(back.factors.size(), world.graph.factors.size() + 5);
}

TEST_F(RobustExecutables, ListsTheModelOptionsAsTheSweepRunnerReadsThem) {
  const auto r = run(app("hamal_robust") + " --list_backends");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("\ncholesky\n"), std::string::npos);
  EXPECT_NE(r.output.find("\n    robust=none    "), std::string::npos);
  EXPECT_NE(r.output.find("\n    null_weight=0.01    "), std::string::npos);
}

TEST_F(RobustExecutables, ImpossibleRequestsAreErrors) {
  auto r = run(app("hamal_spoil") + " --data " + clean_ + " --outliers 100000 --output " + dir_ +
               "/x.g2o");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("hamal_spoil: error:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("free pose pairs"), std::string::npos) << r.output;
  r = run(app("hamal_spoil") + " --data " + clean_ + " --policy nearby --output " + dir_ +
          "/x.g2o");
  EXPECT_EQ(r.status, 1);
  // A graph without its list is not graded as if it were clean.
  r = run(app("hamal_robust") + " --data " + clean_ + " --backend cholesky --batch");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("clean.g2o.false"), std::string::npos) << r.output;
  r = run(app("hamal_robust") + " --data " + clean_ + " --backend cholesky:robust=tukey");
  EXPECT_EQ(r.status, 1);
}

std::string python() {
  for (const char* p : {"/usr/bin/python3", "/usr/local/bin/python3"})
    if (access(p, X_OK) == 0) return p;
  return "";
}

// Writes a sweep spec over `clean` with the given "spoil" and "models"
// entries and one cholesky batch run; returns the sweep command line into
// `results` (the flags after it are the caller's).
std::string sweepCommand(const std::string& py, const std::string& clean, const std::string& spec,
                         const std::string& spoil, const std::string& models,
                         const std::string& results) {
  std::ofstream out(spec);
  out << R"({"datasets": {"w": {"data": ")" << clean << R"("}}, "spoil": )" << spoil
      << R"(, "models": )" << models
      << R"(, "runs": [{"backend": "cholesky", "mode": "batch"}], "timeout": 60})";
  return py + " " + std::string(HAMAL_ROBUST_SCRIPTS) + "/hamal_robust_sweep.py " + spec +
         " --results " + results + " --bin_dir " + testing::buildPath("apps") + " --quiet";
}

// The sweep through the house runner: spoiled files and runs made once, a
// second call runs nothing, and the report has a row per cell and method.
TEST_F(RobustExecutables, SweepResumesAndReports) {
  const std::string py = python();
  if (py.empty()) GTEST_SKIP() << "no python3";
  const std::string results = dir_ + "/results";
  const std::string sweep =
      sweepCommand(py, clean_, dir_ + "/spec.json",
                   R"({"outliers": [0, 5], "policies": ["random", "local"], "seeds": [1, 2]})",
                   R"(["none", "maxmix"])", results);
  auto r = run(sweep);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("10 runs, 0 already done"), std::string::npos) << r.output;
  const std::string list = slurp(results + "/spoiled/w-local-5-s2.g2o.false");
  EXPECT_NE(list.find("seed=2"), std::string::npos) << list;
  r = run(sweep);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("10 runs, 10 already done, 0 to run"), std::string::npos) << r.output;

  r = run(py + " " + std::string(HAMAL_ROBUST_SCRIPTS) + "/hamal_robust_report.py " + results);
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string table = slurp(results + "/report/robust_table.csv");
  // Rows: clean x 2 models, (random, local) x 2 models; the seeds averaged.
  int rows = -1;
  for (char c : table) rows += c == '\n';
  EXPECT_EQ(rows, 6) << table;
  EXPECT_NE(table.find("w,local,5,maxmix,cholesky,batch,2,"), std::string::npos) << table;
  // One table per dataset, a row per policy, N, model and back-end.
  const std::string report = slurp(results + "/report/robust_report.md");
  EXPECT_NE(report.find("| random | 5 | maxmix | cholesky (batch) | 2 |"), std::string::npos)
      << report;
}

// --seeds replaces the spec's seeds: one command spoils and runs every cell
// once per seed given, and a list that is not seeds is an error.
TEST_F(RobustExecutables, SweepSeedsOverrideTheSpec) {
  const std::string py = python();
  if (py.empty()) GTEST_SKIP() << "no python3";
  const std::string results = dir_ + "/results";
  const std::string sweep =
      sweepCommand(py, clean_, dir_ + "/spec.json",
                   R"({"outliers": [5], "policies": ["random"], "seeds": [1]})", R"(["maxmix"])",
                   results) +
      " --seeds ";
  auto r = run(sweep + "3,4");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("2 runs, 0 already done"), std::string::npos) << r.output;
  EXPECT_NE(slurp(results + "/spoiled/w-random-5-s3.g2o.false").find("seed=3"), std::string::npos);
  EXPECT_NE(slurp(results + "/spoiled/w-random-5-s4.g2o.false").find("seed=4"), std::string::npos);
  EXPECT_EQ(access((results + "/spoiled/w-random-5-s1.g2o").c_str(), F_OK), -1);
  for (const char* bad : {"x", "1,,-2", "3,3", "\"\""}) {
    r = run(sweep + bad);
    EXPECT_NE(r.status, 0) << bad;
    EXPECT_NE(r.output.find("--seeds"), std::string::npos) << bad << ": " << r.output;
  }
}

}  // namespace
}  // namespace hamal
