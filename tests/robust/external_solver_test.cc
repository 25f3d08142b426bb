// A solver outside hamal (plugins/risam's riSAM) is graded as hamal's own
// models are (apps/robust/external_solver.h): the edges it is given, the
// decisions file it hands back and its errors, and hamal_robust --estimate,
// which must give an estimate and its decisions the grades the run that made
// them got. Nothing here needs GTSAM.
#include "apps/robust/external_solver.h"

#include <ceres/loss_function.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "backends/robust/loop_closure.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "factors/between_factor.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

using apps::ExternalDecision;

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class ExternalSolver : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/external_solver_" + std::to_string(getpid());
    ASSERT_EQ(testing::runCommand("mkdir -p " + dir_).status, 0);
    apps::setUpRegistry(registry_, {});
    apps::ManhattanWorldOptions w;
    w.poses = 150;
    graph_ = apps::generateManhattanWorld(w).graph;
    graph_.source = "world.g2o";
  }
  void TearDown() override { testing::runCommand("rm -rf " + dir_); }
  Graph read(const std::string& text) {
    std::istringstream in(text);
    return readGraph(in, "g.g2o", registry_, Format::kG2o);
  }
  // One decision per loop closure of graph_, closure k rejected when k is odd.
  std::vector<ExternalDecision> decisions() const {
    std::vector<ExternalDecision> out;
    for (std::size_t i = 0; i < graph_.factors.size(); ++i) {
      if (!robust::isLoopClosure(*graph_.factors[i])) continue;
      const auto& k = graph_.factors[i]->keys();
      out.push_back({i, k[0].index(), k[1].index(), 0.25 + out.size(), out.size() % 2 == 1});
    }
    return out;
  }
  std::string expectError(const std::string& text) {
    const std::string path = dir_ + "/d.txt";
    std::ofstream(path) << text;
    try {
      apps::readExternalDecisions(path, graph_);
    } catch (const Error& e) {
      return e.what();
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return "";
  }
  std::string dir_;
  Registry registry_;
  Graph graph_;
};

TEST_F(ExternalSolver, EdgesAreTheGraphsFactorsInOrder) {
  const auto edges = apps::externalEdges(graph_);
  ASSERT_EQ(edges.size(), graph_.factors.size());
  std::size_t closures = 0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const auto& f = dynamic_cast<const BetweenFactor&>(*graph_.factors[i]);
    EXPECT_EQ(edges[i].factor, i);
    EXPECT_EQ(X(edges[i].from), f.keys()[0]);
    EXPECT_EQ(X(edges[i].to), f.keys()[1]);
    EXPECT_EQ(edges[i].measurement.x, f.measurement().x);
    EXPECT_EQ(edges[i].measurement.theta, f.measurement().theta);
    EXPECT_EQ(edges[i].information, f.information());
    EXPECT_EQ(edges[i].loop_closure, robust::isLoopClosure(f));
    closures += edges[i].loop_closure;
  }
  EXPECT_GT(closures, 0u);
}

TEST_F(ExternalSolver, EdgesRefuseWhatAnOutsideSolverIsNotGiven) {
  const std::string poses =
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n";
  try {
    apps::externalEdges(read(poses + "VERTEX_XY 2 1 1\nEDGE_SE2_XY 1 2 0 1 1 0 1\n"));
    ADD_FAILURE() << "a landmark was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("g.g2o: factor 1 (EDGE_SE2_XY x1 l2)"), std::string::npos)
        << e.what();
  }
  try {
    apps::externalEdges(read(poses + "FIX 0\n"));
    ADD_FAILURE() << "a FIX line was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("g.g2o: FIX lines (x0"), std::string::npos) << e.what();
  }
  Graph lossy = read(poses);
  lossy.factors[0]->setLoss(std::make_shared<ceres::CauchyLoss>(1.0));
  EXPECT_THROW(apps::externalEdges(lossy), Error);
}

TEST_F(ExternalSolver, DecisionsRoundTrip) {
  const std::string path = dir_ + "/d.txt";
  const auto written = decisions();
  ASSERT_GE(written.size(), 2u);
  apps::writeExternalDecisions(path, "solver", "world.g2o", written);
  const apps::ModelDecisions read = apps::readExternalDecisions(path, graph_);
  ASSERT_EQ(read.rejected.size(), graph_.factors.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < graph_.factors.size(); ++i) {
    if (!robust::isLoopClosure(*graph_.factors[i])) {
      EXPECT_EQ(read.rejected[i], -1);
      EXPECT_TRUE(std::isnan(read.weight[i]));
      continue;
    }
    EXPECT_EQ(read.rejected[i], written[k].rejected ? 1 : 0);
    EXPECT_EQ(read.weight[i], written[k].weight);
    ++k;
  }
  // A solver without weights writes nan.
  auto unweighted = written;
  unweighted[0].weight = NAN;
  apps::writeExternalDecisions(path, "solver", "world.g2o", unweighted);
  EXPECT_TRUE(std::isnan(apps::readExternalDecisions(path, graph_).weight[written[0].factor]));
}

TEST_F(ExternalSolver, BadDecisionsNameTheLineAndTheReason) {
  const auto all = decisions();
  std::ostringstream good;
  for (std::size_t k = 1; k < all.size(); ++k)
    good << all[k].factor << " " << all[k].from << " " << all[k].to << " 1 0\n";
  const auto& d = all[0];
  const std::string head = "# solver\nfactor from to weight rejected\n";
  const std::string ids = std::to_string(d.factor) + " " + std::to_string(d.from) + " ";
  const std::string line = ids + std::to_string(d.to) + " 1 0\n";
  std::string e = expectError(head + good.str());
  EXPECT_NE(e.find("no decision on factor " + std::to_string(d.factor)), std::string::npos) << e;
  e = expectError(head + line + line + good.str());
  EXPECT_NE(e.find("d.txt:4: factor " + std::to_string(d.factor) + " twice"), std::string::npos)
      << e;
  e = expectError(head + ids + std::to_string(d.to + 1) + " 1 0\n" + good.str());
  EXPECT_NE(e.find("d.txt:3: factor"), std::string::npos) << e;
  EXPECT_NE(e.find("is not an edge"), std::string::npos) << e;
  e = expectError(head + "0 0 1 1 0\n");
  EXPECT_NE(e.find("d.txt:3: factor 0 (EDGE_SE2 x0 x1) of world.g2o is not a loop closure"),
            std::string::npos)
      << e;
  e = expectError(head + "99999 0 1 1 0\n");
  EXPECT_NE(e.find("world.g2o has only"), std::string::npos) << e;
  e = expectError(head + ids + std::to_string(d.to) + " 1 2\n");
  EXPECT_NE(e.find("d.txt:3: rejected must be 0 or 1"), std::string::npos) << e;
  e = expectError(head + ids + std::to_string(d.to) + " heavy 1\n");
  EXPECT_NE(e.find("d.txt:3"), std::string::npos) << e;
  e = expectError(head + ids + std::to_string(d.to) + " 1\n");
  EXPECT_NE(e.find("d.txt:3"), std::string::npos) << e;
  e = expectError("factor from to group\n" + line);
  EXPECT_NE(e.find("d.txt:1: expected the column line 'factor from to weight rejected'"),
            std::string::npos)
      << e;
}

// hamal_robust --estimate grades files as it grades the run that wrote them:
// an incremental GNC run's estimate (--output) and verdicts (--weights, as a
// decisions file) get the run's ATE and counts.
TEST_F(ExternalSolver, HamalRobustGradesAnEstimateAsTheRunThatMadeIt) {
  const std::string clean = dir_ + "/clean.g2o", spoiled = dir_ + "/s.g2o";
  writeG2o(clean, graph_.initial, graph_.factors);
  const std::string robust = testing::buildPath("apps/hamal_robust");
  auto r = testing::runCommand(testing::buildPath("apps/hamal_spoil") + " --data " + clean +
                               " --outliers 20 --seed 3 --output " + spoiled);
  ASSERT_EQ(r.status, 0) << r.output;
  r = testing::runCommand(robust + " --data " + spoiled + " --backend aprilsam:robust=gnc " +
                          "--summary " + dir_ + "/run.json --output " + dir_ +
                          "/est.g2o --weights " + dir_ + "/w.csv");
  ASSERT_EQ(r.status, 0) << r.output;
  // The run's weights CSV (factor,from,to,false,weight,chi2,rejected) as a decisions file.
  std::ifstream weights(dir_ + "/w.csv");
  std::ofstream decisions(dir_ + "/est.decisions");
  decisions << "factor from to weight rejected\n";
  std::string line;
  std::getline(weights, line);
  while (std::getline(weights, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream f(line);
    std::string factor, from, to, is_false, weight, chi2, rejected;
    f >> factor >> from >> to >> is_false >> weight >> chi2 >> rejected;
    decisions << factor << " " << from.substr(1) << " " << to.substr(1) << " " << weight << " "
              << rejected << "\n";
  }
  decisions.close();
  r = testing::runCommand(robust + " --data " + spoiled + " --estimate " + dir_ +
                          "/est.g2o --decisions " + dir_ + "/est.decisions --summary " + dir_ +
                          "/graded.json");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto run = nlohmann::json::parse(slurp(dir_ + "/run.json"));
  const auto graded = nlohmann::json::parse(slurp(dir_ + "/graded.json"));
  EXPECT_EQ(graded["mode"], "external");
  EXPECT_TRUE(graded["seconds"].is_null());
  EXPECT_NEAR(graded["ate_translation"].get<double>(), run["ate_translation"].get<double>(), 1e-9);
  EXPECT_NEAR(graded["chi2_true"].get<double>(), run["chi2_true"].get<double>(),
              1e-9 * run["chi2_true"].get<double>());
  for (const char* k : {"false_switched_off", "true_switched_off", "false_accepted"})
    EXPECT_EQ(graded[k], run[k]) << k;
  EXPECT_EQ(graded["false_edges"], 20);
  EXPECT_GT(run["false_switched_off"].get<int>(), 0);

  // The grades are the file's verdicts: accepting every closure keeps every false edge.
  {
    std::ifstream in(dir_ + "/est.decisions");
    std::ofstream all(dir_ + "/accept_all.decisions");
    std::getline(in, line);
    all << line << "\n";
    while (std::getline(in, line)) all << line.substr(0, line.rfind(' ')) << " 0\n";
  }
  r = testing::runCommand(robust + " --data " + spoiled + " --estimate " + dir_ +
                          "/est.g2o --decisions " + dir_ + "/accept_all.decisions --summary " +
                          dir_ + "/all.json");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto all = nlohmann::json::parse(slurp(dir_ + "/all.json"));
  EXPECT_EQ(all["false_accepted"], 20);
  EXPECT_EQ(all["true_switched_off"], 0);

  // Without --decisions the max-mixture rule grades the closures; the ATE is the same.
  r = testing::runCommand(robust + " --data " + spoiled + " --estimate " + dir_ +
                          "/est.g2o --summary " + dir_ + "/rule.json");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NEAR(nlohmann::json::parse(slurp(dir_ + "/rule.json"))["ate_translation"].get<double>(),
              run["ate_translation"].get<double>(), 1e-9);

  // What cannot be meant is an error, before any work.
  for (const std::string& bad :
       {" --estimate " + dir_ + "/est.g2o --backend aprilsam:robust=gnc",
        " --decisions " + dir_ + "/est.decisions --backend aprilsam:robust=gnc",
        " --estimate " + dir_ + "/est.g2o --batch",
        " --estimate " + dir_ + "/est.g2o --rows " + dir_ + "/rows.csv",
        " --estimate " + dir_ + "/missing.g2o"}) {
    r = testing::runCommand(robust + " --data " + spoiled + bad);
    EXPECT_EQ(r.status, 1) << bad << "\n" << r.output;
    EXPECT_EQ(r.output.find("clean optimum"), std::string::npos) << bad << "\n" << r.output;
  }
}

}  // namespace
}  // namespace hamal
