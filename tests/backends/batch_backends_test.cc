// The batch back-ends (ceres, cholesky; thesis sec. 3.5.1) on small graphs
// built in code: the incremental protocol ends where a batch solve ends,
// Point2 landmarks are handled, a singular system is a Status that names the
// variable and does not stop later updates, and options are checked.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "backends/ceres/register_ceres.h"
#include "backends/cholesky/register_cholesky.h"
#include "core/error.h"
#include "core/graph.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/landmark_prior_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/position_factor.h"
#include "factors/prior_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal {
namespace {

const char* const kBackends[] = {"ceres", "cholesky"};
// Tolerances tight enough that two solvers' optima agree to 1e-6 (the
// defaults stop within ~1e-5 m of it, which is plenty for chi2 figures).
const char* const kTight[] = {"ceres:function_tolerance=1e-14,parameter_tolerance=1e-12",
                              "cholesky:function_tolerance=1e-14"};

Registry makeRegistry() {
  Registry r;
  registerCeresBackend(r);
  registerCholeskyBackend(r);
  return r;
}

// Deterministic "noise" so that the graph has a non-zero optimum.
double noise(int i, int k) { return 0.03 * std::sin(1.7 * i + 2.3 * k + 0.5); }

// A robot driving twice around a square of 4 m, with loop closures to the
// first lap and noisy odometry: nonlinear (headings turn by pi/2).
Graph squareLoop() {
  Graph g;
  g.source = "square";
  const Eigen::Matrix3d info = Eigen::Vector3d(100, 100, 400).asDiagonal();
  const int per_lap = 16;
  for (int i = 0; i + 1 < 2 * per_lap; ++i) {
    const bool corner = (i % 4) == 3;
    const Pose2 z(1.0 + noise(i, 0), noise(i, 1), (corner ? M_PI / 2 : 0.0) + noise(i, 2));
    g.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), z, info));
  }
  for (int i = per_lap; i < 2 * per_lap; ++i)
    g.add(std::make_shared<BetweenFactor>(X(i - per_lap), X(i),
                                          Pose2(noise(i, 3), noise(i, 4), noise(i, 5)), info));
  return g;
}

// Poses along a line observing Point2 landmarks on both sides.
Graph landmarkLine() {
  Graph g;
  g.source = "landmarks";
  const Eigen::Matrix3d odo = Eigen::Vector3d(50, 50, 200).asDiagonal();
  Eigen::Matrix2d obs;
  obs << 40, 5, 5, 30;
  for (int i = 0; i < 12; ++i) {
    if (i > 0)
      g.add(std::make_shared<BetweenFactor>(X(i - 1), X(i),
                                            Pose2(1 + noise(i, 0), noise(i, 1), noise(i, 2)), odo));
    for (int l = std::max(0, i / 2 - 1); l <= i / 2 + 1 && l < 7; ++l) {
      // Landmark l sits at (2l, +-2); pose i at (i, 0, 0) in the truth.
      const Point2 truth(2.0 * l, l % 2 ? 2.0 : -2.0);
      g.add(std::make_shared<PosePointFactor>(
          X(i), L(l), Point2(truth.x() - i + noise(i, l), truth.y() + noise(l, i)), obs));
    }
  }
  return g;
}

Values solveBatch(const Registry& registry, const std::string& spec, const Graph& graph,
                  UpdateResult* result = nullptr) {
  ThesisProtocol protocol(graph);
  auto backend = registry.makeBackend(spec);
  const UpdateResult r = backend->update(protocol.batch());
  EXPECT_TRUE(r.status.ok()) << spec << ": " << r.status.message;
  EXPECT_EQ(r.kind, UpdateKind::kBatch) << spec;
  if (result) *result = r;
  return backend->estimate();
}

Values solveIncremental(const Registry& registry, const std::string& spec, const Graph& graph) {
  ThesisProtocol protocol(graph);
  auto backend = registry.makeBackend(spec);
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const UpdateResult r = backend->update(protocol.step(i, backend->estimate()));
    EXPECT_TRUE(r.status.ok()) << spec << " step " << i << ": " << r.status.message;
  }
  return backend->estimate();
}

void expectNear(const Values& a, const Values& b, double tol, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (Key k : a.keys()) {
    ASSERT_TRUE(b.contains(k)) << what << ": " << k;
    for (int d = 0; d < a.dim(k); ++d) {
      double diff = a.data(k)[d] - b.data(k)[d];
      if (d == 2 && a.type(k) == VariableType::kPose2) diff = wrapAngle(diff);
      EXPECT_NEAR(diff, 0.0, tol) << what << ": " << k << " component " << d;
    }
  }
}

TEST(BatchBackends, IncrementalEndsAtTheBatchOptimum) {
  const Registry registry = makeRegistry();
  const Graph graph = squareLoop();
  const double start = chi2(graph.factors, ThesisProtocol(graph).initialValues());
  for (const char* name : kTight) {
    const Values batch = solveBatch(registry, name, graph);
    const Values incremental = solveIncremental(registry, name, graph);
    const double optimum = chi2(graph.factors, batch);
    EXPECT_LT(optimum, 0.5 * start) << name;
    EXPECT_NEAR(chi2(graph.factors, incremental), optimum, 1e-6 * optimum) << name;
    expectNear(incremental, batch, 1e-6, name);
  }
  // Both back-ends minimise the same objective.
  expectNear(solveBatch(registry, kTight[0], graph), solveBatch(registry, kTight[1], graph), 1e-6,
             "ceres vs cholesky");
}

TEST(BatchBackends, Point2Landmarks) {
  const Registry registry = makeRegistry();
  const Graph graph = landmarkLine();
  const Values ceres = solveBatch(registry, kTight[0], graph);
  UpdateResult r;
  const Values cholesky = solveBatch(registry, kTight[1], graph, &r);
  EXPECT_EQ(ceres.size(), 12u + 7u);
  EXPECT_EQ(cholesky.type(L(3)), VariableType::kPoint2);
  // 12 poses x 3 + 7 landmarks x 2 scalar columns.
  EXPECT_EQ(r.columns_total, 12u * 3 + 7u * 2);
  EXPECT_EQ(r.columns_recomputed, r.columns_total);
  expectNear(ceres, cholesky, 1e-6, "landmarks, ceres vs cholesky");
  expectNear(solveIncremental(registry, kTight[1], graph), cholesky, 1e-6,
             "landmarks, incremental vs batch");
  EXPECT_NEAR(cholesky.point(L(3)).x(), 6.0, 0.2);
  EXPECT_NEAR(cholesky.point(L(3)).y(), 2.0, 0.2);
}

Step firstStep() {
  Step s;
  s.new_values.insert(X(0), Pose2(0, 0, 0));
  s.new_factors.push_back(
      std::make_shared<PriorFactor>(X(0), Pose2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e4));
  return s;
}

// The pivot check reads L's diagonal, laid out differently per CHOLMOD path.
class CholeskyFactorization : public ::testing::TestWithParam<const char*> {};
INSTANTIATE_TEST_SUITE_P(Paths, CholeskyFactorization,
                         ::testing::Values("cholesky:factorization=simplicial",
                                           "cholesky:factorization=supernodal"));

TEST_P(CholeskyFactorization, SingularSystemIsAStatusNamingTheVariable) {
  const Registry registry = makeRegistry();
  auto backend = registry.makeBackend(GetParam());
  ASSERT_TRUE(backend->update(firstStep()).status.ok());

  // x1 is seen only by a position measurement: its heading is free.
  Step s1;
  s1.index = 1;
  s1.new_values.insert(X(1), Pose2(1, 0, 0.3));
  s1.new_factors.push_back(
      std::make_shared<PositionFactor>(X(1), Point2(1, 0), Eigen::Matrix2d::Identity()));
  UpdateResult r = backend->update(s1);
  EXPECT_EQ(r.status.code, Status::kNumericalFailure);
  ASSERT_EQ(r.status.keys.size(), 1u);
  EXPECT_EQ(r.status.keys[0], X(1));
  EXPECT_NE(r.status.message.find("x1"), std::string::npos) << r.status.message;
  EXPECT_DOUBLE_EQ(backend->estimate().pose(X(1)).theta, 0.3);  // left as it was

  // Constraining it later repairs the system: updates go on.
  Step s2;
  s2.index = 2;
  s2.new_factors.push_back(
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), Eigen::Matrix3d::Identity()));
  r = backend->update(s2);
  EXPECT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_NEAR(backend->estimate().pose(X(1)).theta, 0.0, 1e-6);

  // A landmark that nothing observes.
  Step s3;
  s3.index = 3;
  s3.new_values.insert(L(7), Point2(3, 4));
  r = backend->update(s3);
  EXPECT_EQ(r.status.code, Status::kNumericalFailure);
  ASSERT_EQ(r.status.keys.size(), 1u);
  EXPECT_EQ(r.status.keys[0], L(7));
}

TEST_P(CholeskyFactorization, RankDeficientSystemIsAStatusNamingTheVariable) {
  // A pose seen only through one point measurement of a known landmark: two
  // equations for three unknowns, singular up to rounding (no zero pivot).
  const Registry registry = makeRegistry();
  auto backend = registry.makeBackend(GetParam());
  Step s;
  s.new_values.insert(L(0), Point2(2, 1));
  s.new_values.insert(X(0), Pose2(0.1, -0.2, 0.3));
  s.new_factors.push_back(
      std::make_shared<LandmarkPriorFactor>(L(0), Point2(2, 1), Eigen::Matrix2d::Identity() * 100));
  s.new_factors.push_back(std::make_shared<PosePointFactor>(X(0), L(0), Point2(1.7, 1.3),
                                                            Eigen::Matrix2d::Identity() * 10));
  const UpdateResult r = backend->update(s);
  EXPECT_EQ(r.status.code, Status::kNumericalFailure) << r.status.message;
  ASSERT_EQ(r.status.keys.size(), 1u);
  EXPECT_EQ(r.status.keys[0], X(0));
}

TEST(CholeskyBackend, RepeatedUpdateWithoutNewFactorsKeepsTheOptimum) {
  const Registry registry = makeRegistry();
  const Graph graph = squareLoop();
  ThesisProtocol protocol(graph);
  auto backend = registry.makeBackend(kTight[1]);
  ASSERT_TRUE(backend->update(protocol.batch()).status.ok());
  const Values before = backend->estimate();
  const UpdateResult r = backend->update(Step{});
  EXPECT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_EQ(r.iterations, 1);  // already converged: one solve, a negligible step
  expectNear(backend->estimate(), before, 1e-9, "second update");
}

TEST(CeresBackend, SolvesEveryKUpdatesAndReportsNoConvergence) {
  const Registry registry = makeRegistry();
  const Graph graph = squareLoop();
  ThesisProtocol protocol(graph);
  auto backend = registry.makeBackend("ceres:every=3");
  for (std::size_t i = 0; i < 6; ++i) {
    const UpdateResult r = backend->update(protocol.step(i, backend->estimate()));
    EXPECT_EQ(r.kind, (i + 1) % 3 == 0 ? UpdateKind::kBatch : UpdateKind::kNone) << i;
  }
  auto limited = registry.makeBackend("ceres:max_iterations=1");
  const UpdateResult r = limited->update(protocol.batch());
  EXPECT_EQ(r.status.code, Status::kNotConverged) << r.status.message;
}

TEST(BatchBackends, UnknownOptionListsTheKnownOnes) {
  const Registry registry = makeRegistry();
  for (const char* name : kBackends) {
    try {
      registry.makeBackend(std::string(name) + ":max_iteration=3");
      FAIL() << name << ": no error";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("max_iteration'"), std::string::npos) << what;
      EXPECT_NE(what.find("max_iterations"), std::string::npos) << what;
    }
  }
  EXPECT_THROW(registry.makeBackend("cholesky:ordering=colamdx"), Error);
  EXPECT_THROW(registry.makeBackend("ceres:linear_solver=magic"), Error);
}

TEST(BatchBackends, BadStepIsAnError) {
  const Registry registry = makeRegistry();
  for (const char* name : kBackends) {
    auto backend = registry.makeBackend(name);
    Step s;
    s.new_factors.push_back(
        std::make_shared<BetweenFactor>(X(0), X(1), Pose2(), Eigen::Matrix3d::Identity()));
    EXPECT_THROW(backend->update(s), Error) << name;
    EXPECT_TRUE(backend->update(firstStep()).status.ok()) << name;
  }
}

}  // namespace
}  // namespace hamal
