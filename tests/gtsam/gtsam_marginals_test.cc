// hamal_gtsam_marginals (plugins/gtsam/marginals_native.cc): GTSAM's
// Marginals at values hamal wrote give the covariance hamal's cholesky gives
// at the same point (core/marginals.h), once rotated into hamal's
// world-frame tangent. The graph has anisotropic, correlated information,
// headings far from zero and its first pose (the protocol's prior) away from
// the origin, so a wrong frame or permutation in the harness shows; its
// measurements agree, so every residual is zero at the optimum and GTSAM's
// BetweenFactor Jacobian (which leaves out the derivative of Local(), exact
// only at zero residual) is exact there.
//
// The harness is built whenever GTSAM 4.2 or newer is found; without it these
// tests are skipped, saying so (HAMAL_GTSAM_MARGINALS, its path, is defined
// by plugins/CMakeLists.txt).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "backends/builtins.h"
#include "core/graph_io.h"
#include "core/marginals.h"
#include "factors/between_factor.h"
#include "factors/range_bearing_factor.h"
#include "protocol/thesis_protocol.h"
#include "testing/command.h"

namespace hamal {
namespace {

#ifdef HAMAL_GTSAM_MARGINALS
#define HAMAL_REQUIRE_GTSAM_MARGINALS()
const char* const kHarness = HAMAL_GTSAM_MARGINALS;
#else
#define HAMAL_REQUIRE_GTSAM_MARGINALS() \
  GTEST_SKIP() << "built without GTSAM (plugins/gtsam/README.md)"
const char* const kHarness = "";
#endif

// Twelve poses on a turning path from (1, 2, 0.7), each seen from the
// previous one, with two loop closures.
Graph turningGraph() {
  std::vector<Pose2> truth = {Pose2(1, 2, 0.7)};
  for (int i = 1; i < 12; ++i)
    truth.push_back(truth.back().compose(Pose2(1.0 + 0.1 * i, 0.2, 0.35)));
  Eigen::Matrix3d information;
  information << 90, 25, 4, 25, 30, -3, 4, -3, 400;
  Graph g;
  g.source = "turning";
  auto between = [&](int a, int b) {
    g.add(std::make_shared<BetweenFactor>(X(a), X(b), truth[a].inverse().compose(truth[b]),
                                          information, BetweenResidual::kMeasurementFrame));
  };
  for (int i = 0; i + 1 < 12; ++i) between(i, i + 1);
  between(0, 9);
  between(3, 11);
  for (int i = 0; i < 12; ++i) g.initial.insert(X(i), truth[i]);
  return g;
}

// The 3 x 3 "name" of the harness' JSON output.
Eigen::Matrix3d matrixFrom(const std::string& output, const std::string& name) {
  const std::size_t begin = output.find("\"" + name + "\"");
  const std::size_t end = output.find("]]", begin);
  if (begin == std::string::npos || end == std::string::npos) {
    ADD_FAILURE() << "no " << name << " in:\n" << output;
    return Eigen::Matrix3d::Zero();
  }
  std::string numbers = output.substr(begin + name.size() + 3, end - begin - name.size() - 3);
  std::replace_if(
      numbers.begin(), numbers.end(), [](char c) { return c == '[' || c == ']' || c == ','; }, ' ');
  std::istringstream in(numbers);
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) in >> m(r, c);
  EXPECT_TRUE(in) << name << " is not 3 x 3 in:\n" << output;
  return m;
}

TEST(GtsamMarginals, LastPoseCovarianceIsCholeskys) {
  HAMAL_REQUIRE_GTSAM_MARGINALS();
  const std::string dir = ::testing::TempDir();
  const std::string graph_path = dir + "/gtsam_marginals_graph.g2o";
  const std::string values_path = dir + "/gtsam_marginals_values.g2o";
  const Graph written = turningGraph();
  writeG2o(graph_path, written.initial, written.factors);

  Registry registry;
  registerBuiltins(registry);
  Graph graph = readGraph(graph_path, registry);
  setBetweenResidual(graph, BetweenResidual::kMeasurementFrame);
  const ThesisProtocol protocol(graph);
  auto backend = registry.makeBackend("cholesky");
  ASSERT_TRUE(backend->update(protocol.batch()).status.ok());
  auto* marginals = dynamic_cast<MarginalCovariances*>(backend.get());
  ASSERT_NE(marginals, nullptr);
  const Key last = protocol.pose(protocol.size() - 1);
  Eigen::MatrixXd hamal_covariance;
  ASSERT_TRUE(marginals->marginalCovariance(last, &hamal_covariance).ok());
  writeG2o(values_path, backend->estimate(), {});

  const testing::CommandResult run = testing::runCommand(
      std::string(kHarness) + " --repeat 1 --data " + graph_path + " --values " + values_path);
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("\"key\": \"" + last.str() + "\""), std::string::npos) << run.output;
  const Eigen::Matrix3d world = matrixFrom(run.output, "covariance_world");
  const Eigen::Matrix3d body = matrixFrom(run.output, "covariance_body");
  const double scale = hamal_covariance.cwiseAbs().maxCoeff();
  EXPECT_LT((world - hamal_covariance).cwiseAbs().maxCoeff(), 1e-9 * scale) << "GTSAM:\n"
                                                                            << world << "\nhamal:\n"
                                                                            << hamal_covariance;
  // The body-frame block differs (the last pose heads 4.55 rad): the
  // rotation is not a no-op here.
  EXPECT_GT((body - hamal_covariance).cwiseAbs().maxCoeff(), 1e-3 * scale);
}

TEST(GtsamMarginals, OtherFactorsAndMissingValuesAreErrors) {
  HAMAL_REQUIRE_GTSAM_MARGINALS();
  const std::string dir = ::testing::TempDir();
  Graph g = turningGraph();
  const std::string values_path = dir + "/gtsam_marginals_values_all.g2o";
  writeG2o(values_path, g.initial, {});
  Values partial = g.initial;
  partial.erase(X(11));
  const std::string partial_path = dir + "/gtsam_marginals_values_partial.g2o";
  writeG2o(partial_path, partial, {});
  const std::string graph_path = dir + "/gtsam_marginals_graph_ok.g2o";
  writeG2o(graph_path, g.initial, g.factors);

  const testing::CommandResult missing = testing::runCommand(
      std::string(kHarness) + " --data " + graph_path + " --values " + partial_path);
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("no value for x11"), std::string::npos) << missing.output;

  g.initial.insert(L(100), Point2(3, 3));
  g.add(std::make_shared<RangeBearingFactor>(X(2), L(100), 2.0, 0.3, Eigen::Matrix2d::Identity()));
  const std::string landmark_path = dir + "/gtsam_marginals_graph_landmark.g2o";
  writeG2o(landmark_path, g.initial, g.factors);
  const testing::CommandResult other = testing::runCommand(
      std::string(kHarness) + " --data " + landmark_path + " --values " + values_path);
  EXPECT_NE(other.status, 0);
  EXPECT_NE(other.output.find("is not a between edge"), std::string::npos) << other.output;
}

}  // namespace
}  // namespace hamal
