// linearize(): plain factors give the cost function's own Jacobians; with a
// robust loss the corrected system keeps the robust gradient rho' J^T r
// (the property Ceres' Corrector guarantees).
#include "core/linearization.h"

#include <gtest/gtest.h>

#include "factors/prior_factor.h"

namespace hamal {
namespace {

TEST(Linearization, PlainFactor) {
  PriorFactor f(X(0), Pose2(1, 2, 0.5), Eigen::Vector3d(4, 9, 16).asDiagonal());
  const double x[3] = {2, 2, 0.0};
  const double* p[1] = {x};
  Linearization lin;
  ASSERT_TRUE(linearize(f, p, &lin));
  EXPECT_NEAR(lin.residual(0), 2.0, 1e-12);
  EXPECT_NEAR(lin.residual(2), -2.0, 1e-12);
  EXPECT_NEAR(lin.cost, 8.0, 1e-12);
  EXPECT_NEAR(lin.jacobians[0](1, 1), 3.0, 1e-12);
}

TEST(Linearization, RobustLossKeepsGradient) {
  PriorFactor f(X(0), Pose2(0, 0, 0), Eigen::Matrix3d::Identity());
  const double x[3] = {1.5, -0.7, 0.4};
  const double* p[1] = {x};
  Linearization plain, robust;
  ASSERT_TRUE(linearize(f, p, &plain));
  f.setLoss(std::make_shared<ceres::CauchyLoss>(0.5));
  ASSERT_TRUE(linearize(f, p, &robust));
  double rho[3];
  f.lossFunction()->Evaluate(plain.residual.squaredNorm(), rho);
  const Eigen::VectorXd g_plain = plain.jacobians[0].transpose() * plain.residual * rho[1];
  const Eigen::VectorXd g_robust = robust.jacobians[0].transpose() * robust.residual;
  EXPECT_TRUE(g_robust.isApprox(g_plain, 1e-12));
  EXPECT_NEAR(robust.cost, rho[0], 1e-12);
  EXPECT_LT(robust.cost, plain.cost);
}

}  // namespace
}  // namespace hamal
