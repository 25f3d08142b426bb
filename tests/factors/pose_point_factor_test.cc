// PosePointFactor (landmark seen in the robot's frame): Jacobians, residual
// by hand, predict() of the landmark, the EDGE_SE2_XY round trip.
#include "factors/pose_point_factor.h"

#include <gtest/gtest.h>

#include "conformance/factor_round_trip.h"
#include "core/jacobian_check.h"

namespace hamal {
namespace {

Eigen::Matrix2d information() {
  Eigen::Matrix2d info;
  info << 6.0, -1.5, -1.5, 2.0;
  return info;
}

TEST(PosePointFactor, JacobiansMatchNumericOverRandomStates) {
  const PosePointFactor f(X(2), L(5), Point2(4.0, -1.0), information());
  const JacobianCheckResult r = checkJacobians(f);
  EXPECT_TRUE(r.ok) << r.report;
  EXPECT_EQ(r.trials, 200);
}

TEST(PosePointFactor, ResidualByHand) {
  // Robot at (1, 2) facing +y: a landmark at (1, 5) is 3 m straight ahead.
  Values v;
  v.insert(X(2), Pose2(1.0, 2.0, M_PI / 2));
  v.insert(L(5), Point2(1.0, 5.0));
  double r[2];
  ASSERT_TRUE(PosePointFactor(X(2), L(5), Point2(3.0, 0.0), information()).evaluate(v, r));
  EXPECT_NEAR(r[0], 0.0, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);
  const PosePointFactor f(X(2), L(5), Point2(2.0, 1.0), information());
  const Eigen::Vector2d e(1.0, -1.0);
  EXPECT_NEAR(f.chi2(v), e.dot(information() * e), 1e-12);
}

TEST(PosePointFactor, PredictsTheLandmarkFromThePose) {
  const PosePointFactor f(X(2), L(5), Point2(4.0, -1.0), information());
  Values known;
  known.insert(X(2), Pose2(-3.0, 7.0, 2.2));
  Values::Entry guess;
  ASSERT_TRUE(f.predict(L(5), known, &guess));
  EXPECT_EQ(guess.type, VariableType::kPoint2);
  known.insert(L(5), Point2(guess.data[0], guess.data[1]));
  EXPECT_LT(f.chi2(known), 1e-20);
  // The pose's heading cannot be told from one point.
  Values only_landmark;
  only_landmark.insert(L(5), Point2(1, 1));
  EXPECT_FALSE(f.predict(X(2), only_landmark, &guess));
  EXPECT_FALSE(f.predict(L(5), Values(), &guess));
}

TEST(PosePointFactor, RoundTripsThroughItsFileLine) {
  EXPECT_TRUE(
      testing::roundTrips(PosePointFactor(X(2), L(5), Point2(1.0 / 3.0, -1e-7), information())));
  const PosePointFactor f(X(2), L(5), Point2(4.0, -1.0), information());
  EXPECT_FALSE(f.equals(PosePointFactor(X(2), L(6), Point2(4.0, -1.0), information())));
  EXPECT_FALSE(f.equals(PosePointFactor(X(2), L(5), Point2(4.0, -1.0 + 1e-6), information())));
}

}  // namespace
}  // namespace hamal
