// LagoInitialization (protocol/lago_initialization.h): exact on noise-free
// graphs whatever the initial headings (including loops that turn by 2 pi
// and initial values wrong by whole turns), leaves what it cannot reach
// alone, says what is missing; and on the public datasets, a batch solve
// from it reaches the optimum of docs/PROTOCOL.md (and w20000's, which
// Gauss-Newton from odometry does not reach) in a few iterations.
#include "protocol/lago_initialization.h"

#include <ceres/loss_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include "backends/builtins.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/prior_factor.h"
#include "protocol/thesis_protocol.h"
#include "tests/testing/test_data.h"

namespace hamal {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Matrix3d information(double xy, double th, double cross = 0) {
  Eigen::Matrix3d m;
  m << xy, cross, 0, cross, 2 * xy, 0.1 * cross, 0, 0.1 * cross, th;
  return m;
}

void addBetween(Graph* g, const Values& truth, int a, int b, const Eigen::Matrix3d& info) {
  g->add(std::make_shared<BetweenFactor>(X(a), X(b), truth.pose(X(a)).between(truth.pose(X(b))),
                                         info));
}

double angleError(double a, double b) { return std::fabs(wrapAngle(a - b)); }

// A robot driving a spiral that turns several full circles, odometry plus
// loop closures between laps, measured without noise.
TEST(LagoInitialization, RecoversNoiseFreeGraphsFromWrongHeadings) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const int n = 200;
  Values truth;
  for (int i = 0; i < n; ++i) {
    const double a = 0.15 * i;  // about 4.8 turns
    truth.insert(X(i), Pose2((5 + 0.02 * i) * std::cos(a), (5 + 0.02 * i) * std::sin(a),
                             wrapAngle(a + kPi / 2)));
  }
  Graph graph;
  for (int i = 1; i < n; ++i) addBetween(&graph, truth, i - 1, i, information(100, 400, 3));
  for (int i = 42; i < n; i += 5) addBetween(&graph, truth, i - 42, i, information(50, 900));
  Values initial;
  initial.insert(X(0), truth.pose(X(0)));
  for (int i = 1; i < n; ++i)  // far off, and headings off by whole turns
    initial.insert(X(i),
                   Pose2(u(rng) * 30, u(rng) * 30, wrapAngle(u(rng) * kPi) + 2 * kPi * (i % 3)));

  const LagoResult r = lagoInitialization(graph, initial);
  EXPECT_EQ(r.poses, static_cast<std::size_t>(n));
  EXPECT_EQ(r.edges, graph.factors.size());
  for (int i = 0; i < n; ++i) {
    const Pose2 p = r.values.pose(X(i)), t = truth.pose(X(i));
    EXPECT_NEAR(p.x, t.x, 1e-8) << i;
    EXPECT_NEAR(p.y, t.y, 1e-8) << i;
    EXPECT_LT(angleError(p.theta, t.theta), 1e-9) << i;
    EXPECT_LE(std::fabs(p.theta), kPi) << "angles come wrapped";
  }
  EXPECT_LT(chi2(graph.factors, r.values), 1e-12);
}

TEST(LagoInitialization, AnchorsAtTheFirstPoseMovesLandmarksWithTheirPoseLeavesTheRest) {
  Values truth;
  for (int i = 0; i < 6; ++i) truth.insert(X(i), Pose2(i, 0.5 * i, 0.3 * i));
  truth.insert(L(0), Point2(1, 1));
  Graph graph;
  addBetween(&graph, truth, 0, 1, information(10, 10));
  addBetween(&graph, truth, 1, 2, information(10, 10));
  addBetween(&graph, truth, 0, 2, information(10, 10));
  addBetween(&graph, truth, 4, 5, information(10, 10));  // not connected to x0
  // L0 seen from x2 (first) and x1: it follows x2 to its new place.
  const Point2 seen = Point2(0.7, -0.2);
  graph.add(std::make_shared<PosePointFactor>(X(2), L(0), seen, Eigen::Matrix2d::Identity()));
  graph.add(std::make_shared<PosePointFactor>(X(1), L(0), seen, Eigen::Matrix2d::Identity()));
  // L1 only seen from x4, which LAGO does not place: unchanged.
  graph.add(std::make_shared<PosePointFactor>(X(4), L(1), seen, Eigen::Matrix2d::Identity()));
  Values initial;
  initial.insert(X(0), Pose2(1, 2, 0.4));  // the anchor: held where it is
  for (int i = 1; i < 6; ++i) initial.insert(X(i), Pose2(0, 0, 0));
  initial.insert(L(0), Point2(7, 7));
  initial.insert(L(1), Point2(8, 8));

  const LagoResult r = lagoInitialization(graph, initial);
  EXPECT_EQ(r.poses, 3u);
  EXPECT_EQ(r.edges, 3u);
  const Pose2 anchor = r.values.pose(X(0));
  EXPECT_DOUBLE_EQ(anchor.x, 1);
  EXPECT_DOUBLE_EQ(anchor.y, 2);
  EXPECT_DOUBLE_EQ(anchor.theta, 0.4);
  // x1, x2 placed relative to the anchor by the measurements.
  const Pose2 expect2 = anchor.compose(truth.pose(X(0)).between(truth.pose(X(2))));
  EXPECT_NEAR(r.values.pose(X(2)).x, expect2.x, 1e-9);
  EXPECT_NEAR(r.values.pose(X(2)).y, expect2.y, 1e-9);
  EXPECT_NEAR(r.values.pose(X(2)).theta, expect2.theta, 1e-9);
  for (int i = 4; i < 6; ++i) {  // other component and the isolated pose: unchanged
    EXPECT_EQ(r.values.pose(X(i)).x, 0);
    EXPECT_EQ(r.values.pose(X(i)).theta, 0);
  }
  EXPECT_EQ(r.followed, 1u);
  const Pose2 x2 = r.values.pose(X(2));
  const Point2 l0 = r.values.point(L(0));
  EXPECT_NEAR(l0.x(), x2.x + std::cos(x2.theta) * seen.x() - std::sin(x2.theta) * seen.y(), 1e-12);
  EXPECT_NEAR(l0.y(), x2.y + std::sin(x2.theta) * seen.x() + std::cos(x2.theta) * seen.y(), 1e-12);
  EXPECT_EQ(r.values.point(L(1)).x(), 8);
}

// A factor kind between poses that does not say what it measures (a plugin's
// edge, a max-mixture): LAGO cannot use it and must say so.
class OpaqueEdge : public BetweenFactor {
 public:
  using BetweenFactor::BetweenFactor;
  std::string tag() const override { return "TEST_OPAQUE"; }
  std::optional<RelativePose> relativePose() const override { return std::nullopt; }
};

TEST(LagoInitialization, ListsTheFactorsItCouldNotUseAndIgnoresThem) {
  Values truth;
  for (int i = 0; i < 8; ++i) truth.insert(X(i), Pose2(i, 0.3 * i * i, 0.4 * i));
  Graph clean;
  for (int i = 1; i < 8; ++i) addBetween(&clean, truth, i - 1, i, information(10, 20));
  addBetween(&clean, truth, 0, 7, information(10, 20));
  Values initial;
  for (int i = 0; i < 8; ++i) initial.insert(X(i), i == 0 ? truth.pose(X(0)) : Pose2(-i, 3, 1));
  initial.insert(X(9), Pose2(5, 5, 0));
  initial.insert(X(10), Pose2(6, 5, 0));

  // The same graph with edges LAGO must not use, all of them wrong.
  Graph noisy = clean;
  const Pose2 wrong(3, -2, 1.5);
  auto robust = std::make_shared<BetweenFactor>(X(1), X(5), wrong, information(10, 20));
  robust->setLoss(std::make_shared<ceres::CauchyLoss>(1.0));
  noisy.add(robust);
  noisy.add(std::make_shared<OpaqueEdge>(X(2), X(6), wrong, information(10, 20)));
  noisy.add(std::make_shared<BetweenFactor>(X(9), X(10), wrong, information(10, 20)));  // apart
  noisy.add(std::make_shared<PriorFactor>(X(3), wrong, information(10, 20)));  // not between poses

  const LagoResult expect = lagoInitialization(clean, initial);
  const LagoResult r = lagoInitialization(noisy, initial);
  EXPECT_TRUE(expect.unused.empty());
  EXPECT_EQ(r.edges, expect.edges);
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(r.values.pose(X(i)).x, truth.pose(X(i)).x, 1e-9) << i;
    EXPECT_NEAR(r.values.pose(X(i)).theta, truth.pose(X(i)).theta, 1e-9) << i;
  }
  ASSERT_EQ(r.unused.size(), 3u);
  EXPECT_EQ(r.unused[0].factor, robust);
  EXPECT_NE(r.unused[0].reason.find("robust loss"), std::string::npos) << r.unused[0].reason;
  EXPECT_EQ(r.unused[1].factor->tag(), "TEST_OPAQUE");
  EXPECT_NE(r.unused[1].reason.find("relative-pose"), std::string::npos) << r.unused[1].reason;
  EXPECT_NE(r.unused[2].reason.find("not connected"), std::string::npos) << r.unused[2].reason;
  const std::string line = describe(r);
  EXPECT_NE(line.find("used 8 of 11"), std::string::npos) << line;
  EXPECT_NE(line.find("1 TEST_OPAQUE"), std::string::npos) << line;
}

TEST(LagoInitialization, SaysWhichPoseHasNoInitialValue) {
  Values truth;
  for (int i = 0; i < 3; ++i) truth.insert(X(i), Pose2(i, 0, 0));
  Graph graph;
  addBetween(&graph, truth, 0, 1, information(1, 1));
  addBetween(&graph, truth, 1, 2, information(1, 1));
  Values initial;
  initial.insert(X(0), Pose2());
  initial.insert(X(1), Pose2());
  try {
    lagoInitialization(graph, initial);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x2"), std::string::npos) << e.what();
  }
}

struct Dataset {
  const char* file;
  const char* format;
  double optimum;      // docs/PROTOCOL.md, "Reference optima"
  int max_iterations;  // Gauss-Newton iterations allowed to get within 0.1%
};

class LagoOnPublicData : public ::testing::TestWithParam<Dataset> {};

TEST_P(LagoOnPublicData, CholeskyFromLagoReachesTheOptimumInFewIterations) {
  const Dataset d = GetParam();
  HAMAL_REQUIRE_DATA(path, d.file);
  Registry registry;
  registerBuiltins(registry);
  const Graph graph = readGraph(path, registry, parseFormat(d.format));
  Step batch = ThesisProtocol(graph).batch();
  const double odometry = chi2(graph.factors, batch.new_values);
  batch.new_values = lagoInitialization(batch.new_factors, batch.new_values).values;
  const double lago = chi2(graph.factors, batch.new_values);
  EXPECT_LT(lago, 3 * d.optimum) << "LAGO alone is near the optimum";
  EXPECT_LT(lago, 1e-3 * odometry);

  auto backend =
      registry.makeBackend("cholesky:max_iterations=" + std::to_string(d.max_iterations));
  backend->update(batch);  // w20000's LM is still creeping at 1e-6 after 50: status not_converged
  const double solved = chi2(graph.factors, backend->estimate());
  EXPECT_NEAR(solved, d.optimum, 1e-3 * d.optimum) << d.file;
}

INSTANTIATE_TEST_SUITE_P(PublicData, LagoOnPublicData,
                         ::testing::Values(Dataset{"M3500.toro", "auto", 137.91295, 4},
                                           Dataset{"intel.g2o", "auto", 44.41781, 4},
                                           Dataset{"manhattan.g2o", "auto", 3533.4585, 4},
                                           Dataset{"city10000.g2o", "auto", 511.98516, 4},
                                           Dataset{"CSAIL.g2o", "auto", 61.14297, 6},
                                           Dataset{"w20000.txt", "gtsam", 37.52, 20}),
                         [](const ::testing::TestParamInfo<Dataset>& info) {
                           return ::hamal::testing::testName(info.param.file);
                         });

}  // namespace
}  // namespace hamal
