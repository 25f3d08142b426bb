// Metrics: chi2 sums whitened squared residuals; ATE aligns rigidly.
#include "core/metrics.h"

#include <ceres/loss_function.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "factors/prior_factor.h"

namespace hamal {
namespace {

TEST(Metrics, Chi2IsSumOfWeightedSquares) {
  std::vector<FactorPtr> f = {
      std::make_shared<PriorFactor>(X(0), Pose2(0, 0, 0), Eigen::Vector3d(1, 2, 3).asDiagonal()),
      std::make_shared<PriorFactor>(X(1), Pose2(1, 0, 0), Eigen::Matrix3d::Identity())};
  Values v;
  v.insert(X(0), Pose2(1, 1, 1));
  v.insert(X(1), Pose2(1, 0, 0.5));
  EXPECT_NEAR(chi2(f, v), 1 + 2 + 3 + 0.25, 1e-12);
  v.erase(X(1));
  EXPECT_THROW(chi2(f, v), Error);
}

TEST(Metrics, RobustCostPassesEachChi2ThroughItsLoss) {
  auto robust =
      std::make_shared<PriorFactor>(X(0), Pose2(0, 0, 0), Eigen::Vector3d(1, 2, 3).asDiagonal());
  robust->setLoss(std::make_shared<ceres::CauchyLoss>(0.5));  // rho(s) = a^2 log(1 + s / a^2)
  std::vector<FactorPtr> f = {
      robust, std::make_shared<PriorFactor>(X(1), Pose2(1, 0, 0), Eigen::Matrix3d::Identity())};
  Values v;
  v.insert(X(0), Pose2(1, 1, 1));
  v.insert(X(1), Pose2(1, 0, 0.5));
  EXPECT_NEAR(robustChi2(*f[0], v), 0.25 * std::log(1 + 6 / 0.25), 1e-12);
  EXPECT_NEAR(robustCost(f, v), 0.25 * std::log(1 + 6 / 0.25) + 0.25, 1e-12);
  EXPECT_NEAR(chi2(f, v), 6.25, 1e-12);  // the grade stays without the loss
  v.erase(X(1));
  EXPECT_THROW(robustCost(f, v), Error);
}

TEST(Metrics, AteIsZeroAfterRigidMotion) {
  Values truth, est;
  const Pose2 motion(3, -2, 0.7);
  for (int i = 0; i < 20; ++i) {
    const Pose2 p(i * 0.5, std::sin(i * 0.3), 0.1 * i);
    truth.insert(X(i), p);
    est.insert(X(i), motion.compose(p));
  }
  EXPECT_NEAR(absoluteTrajectoryError(est, truth).translation_rmse, 0, 1e-9);
  EXPECT_NEAR(absoluteTrajectoryError(est, truth).rotation_rmse, 0, 1e-9);
  EXPECT_GT(absoluteTrajectoryError(est, truth, false).translation_rmse, 1.0);
  EXPECT_EQ(absoluteTrajectoryError(est, truth).poses, 20u);
}

}  // namespace
}  // namespace hamal
