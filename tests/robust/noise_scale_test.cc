// The doubt rule "the noise the answer shows" (backends/robust/noise_scale.h):
// the a-posteriori variance factor counts the redundancy of what an answer
// keeps; where the stated informations overstate the noise 50 times (as
// M3500's do), a false group that bends the map within c2 passes the plain
// cheaper-alternative check and is caught at c2 scaled by the factor, at the
// end of a run; where the informations are the noise's, the right answer
// stays ok.
#include "backends/robust/noise_scale.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "apps/bench/bench_runner.h"
#include "apps/robust/false_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/loop_closure.h"
#include "backends/robust/truncated_objective_check.h"
#include "core/error.h"
#include "factors/between_factor.h"
#include "tests/robust/spoiled_world.h"

namespace hamal::robust {
namespace {

TEST(NoiseScale, TheRedundancyIsTheRowsLessTheFreeParameters) {
  // x0 - x1 - x2 and a closure x0 - x2, x0 fixed: 9 rows, 6 parameters.
  Values v;
  for (std::uint64_t i = 0; i < 3; ++i) v.insert(X(i), Pose2(i, 0, 0));
  const Eigen::Matrix3d info = Eigen::Vector3d(4, 4, 4).asDiagonal();
  const std::vector<FactorPtr> odometry = {
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), info),
      std::make_shared<BetweenFactor>(X(1), X(2), Pose2(1.5, 0, 0), info)};
  const std::vector<FactorPtr> closures = {
      std::make_shared<BetweenFactor>(X(0), X(2), Pose2(2.5, 0, 0), info)};
  const NoiseScale fixed = aPosterioriVarianceFactor(odometry, closures, {11.34}, {X(0)}, v);
  EXPECT_DOUBLE_EQ(fixed.redundancy, 3);
  EXPECT_DOUBLE_EQ(fixed.chi2, 2 * 4 * 0.25);  // x2 is 0.5 short of both
  // No fixed variable: the plane's 3 rigid motions are no parameters either.
  EXPECT_DOUBLE_EQ(aPosterioriVarianceFactor(odometry, closures, {11.34}, {}, v).redundancy, 3);
  // A closure beyond its c2 is not kept: 6 rows, 6 parameters.
  const NoiseScale dropped = aPosterioriVarianceFactor(odometry, closures, {1e-3}, {X(0)}, v);
  EXPECT_DOUBLE_EQ(dropped.redundancy, 0);
  EXPECT_FALSE(noiseOverstated(dropped));
  EXPECT_THROW(aPosterioriVarianceFactor(odometry, closures, {}, {X(0)}, v), Error);
}

struct World : testing::SpoiledWorld {
  Values bent;              // least squares with what fits of the group
  std::size_t bent_by = 0;  // false closures the bent map keeps
};

// 300 poses and one local group of 10 false closures; every information
// `scale` times the generator's noise's (0.02: covariances overstated 50
// times, as M3500's).
World makeWorld(double scale) {
  testing::SpoiledWorldOptions o;
  o.information_scale = scale;
  o.outliers = 10;
  o.policy = apps::SpoilPolicy::kLocalGroup;
  o.spoil_seed = 4;
  World out{testing::makeSpoiledWorld(o)};
  const auto optimum = [&](const Graph& g) {
    const apps::BatchOptimum opt =
        apps::solveBatchOptimum(g, ThesisProtocol(g), 0, out.registry, "cholesky");
    EXPECT_TRUE(opt.status.ok()) << opt.status.message;
    return opt.estimate;
  };
  // As PCM keeps the part of a group consistent with the rest: least
  // squares with the group, the false closure furthest beyond c2 left out
  // until every one kept fits.
  const double c2 = GncOptions().threshold(3);
  Graph bent = out.spoiled.graph;
  for (;;) {
    out.bent = optimum(bent);
    std::size_t worst = 0;
    double most = c2;
    for (std::size_t i = out.clean.factors.size(); i < bent.factors.size(); ++i)
      if (const double s = bent.factors[i]->chi2(out.bent); s > most) {
        most = s;
        worst = i;
      }
    if (worst == 0) break;
    bent.factors.erase(bent.factors.begin() + static_cast<std::ptrdiff_t>(worst));
  }
  out.bent_by = bent.factors.size() - out.clean.factors.size();
  return out;
}

TruncatedObjectiveCheck makeCheck(const World& w) {
  TruncatedObjectiveCheck check([&w] { return w.registry.makeBackend("cholesky"); }, isLoopClosure,
                                GncOptions());
  check.add(ThesisProtocol(w.spoiled.graph).batch());
  return check;
}

TEST(NoiseScale, AFalseGroupBentWithinC2WhereTheNoiseIsOverstatedIsInDoubt) {
  const World w = makeWorld(0.02);
  // Part of the group bends the map, within c2: the plain rule finds no
  // cheaper map.
  ASSERT_GE(w.bent_by, 2u);
  double bend = 0;
  for (const auto& [key, entry] : w.clean_optimum) {
    const Pose2 a = w.clean_optimum.pose(key), b = w.bent.pose(key);
    bend = std::max(bend, std::hypot(a.x - b.x, a.y - b.y));
  }
  EXPECT_GT(bend, 1.0);
  TruncatedObjectiveCheck check = makeCheck(w);
  ASSERT_TRUE(check.judge(w.bent).ok());
  const Status s = check.judge(w.bent, true);
  EXPECT_EQ(s.code, Status::kUncertain) << s.message;
  EXPECT_NE(s.message.find("noise scale"), std::string::npos) << s.message;
}

TEST(NoiseScale, WhereTheInformationsAreTheNoisesTheRightAnswerStaysOk) {
  const World w = makeWorld(1);
  std::vector<FactorPtr> inliers, closures;
  for (const FactorPtr& f : w.clean.factors) (isLoopClosure(*f) ? closures : inliers).push_back(f);
  const NoiseScale scale = aPosterioriVarianceFactor(
      inliers, closures, std::vector<double>(closures.size(), GncOptions().threshold(3)), {X(0)},
      w.clean_optimum);
  EXPECT_NEAR(scale.factor(), 1, 0.3);
  EXPECT_FALSE(noiseOverstated(scale));
  TruncatedObjectiveCheck check = makeCheck(w);
  const Status s = check.judge(w.clean_optimum, true);
  EXPECT_TRUE(s.ok()) << s.message;
}

}  // namespace
}  // namespace hamal::robust
