// PositionFactor (thesis eq. 2.39-2.41): Jacobians, the residual by hand,
// predict(), the EDGE_SE2_POSITION round trip.
#include "factors/position_factor.h"

#include <gtest/gtest.h>

#include "conformance/factor_round_trip.h"
#include "core/jacobian_check.h"

namespace hamal {
namespace {

Eigen::Matrix2d information() {
  Eigen::Matrix2d info;
  info << 3.0, 1.0, 1.0, 5.0;
  return info;
}

TEST(PositionFactor, JacobiansMatchNumericOverRandomStates) {
  const PositionFactor f(X(4), Point2(-2.0, 8.0), information());
  const JacobianCheckResult r = checkJacobians(f);
  EXPECT_TRUE(r.ok) << r.report;
  EXPECT_EQ(r.trials, 200);
}

TEST(PositionFactor, ResidualByHandIgnoresTheHeading) {
  Values v;
  v.insert(X(4), Pose2(3.0, 4.0, 1.0));
  const PositionFactor f(X(4), Point2(1.0, 1.0), Eigen::Vector2d(4.0, 9.0).asDiagonal());
  double r[2];
  ASSERT_TRUE(f.evaluate(v, r));
  EXPECT_NEAR(r[0], 4.0, 1e-12);  // sqrt(4) * 2
  EXPECT_NEAR(r[1], 9.0, 1e-12);  // sqrt(9) * 3
  v.set(X(4), Pose2(3.0, 4.0, -2.0));
  EXPECT_NEAR(f.chi2(v), 97.0, 1e-12);
}

TEST(PositionFactor, PredictsAPoseAtThePositionWithThetaZero) {
  const PositionFactor f(X(4), Point2(-2.0, 8.0), information());
  Values::Entry guess;
  ASSERT_TRUE(f.predict(X(4), Values(), &guess));
  EXPECT_EQ(guess.type, VariableType::kPose2);
  EXPECT_EQ(guess.data[0], -2.0);
  EXPECT_EQ(guess.data[1], 8.0);
  EXPECT_EQ(guess.data[2], 0.0);
  EXPECT_FALSE(f.predict(X(5), Values(), &guess));
}

TEST(PositionFactor, RoundTripsThroughItsFileLine) {
  EXPECT_TRUE(
      testing::roundTrips(PositionFactor(X(4), Point2(1.0 / 3.0, -2.0 / 7.0), information())));
  const PositionFactor f(X(4), Point2(-2.0, 8.0), information());
  EXPECT_FALSE(f.equals(PositionFactor(X(4), Point2(-2.0, 8.0 + 1e-6), information())));
  EXPECT_TRUE(f.equals(PositionFactor(X(4), Point2(-2.0, 8.0 + 1e-12), information())));
}

}  // namespace
}  // namespace hamal
