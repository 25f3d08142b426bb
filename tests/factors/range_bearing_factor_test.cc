// RangeBearingFactor (thesis eq. 2.34-2.37, bearing from the robot to the
// landmark): Jacobians away from the singular state, the bearing's
// direction, wrapping, predict() of the landmark, the EDGE_SE2_RANGE_BEARING
// round trip.
#include "factors/range_bearing_factor.h"

#include <gtest/gtest.h>

#include "conformance/factor_round_trip.h"
#include "core/jacobian_check.h"

namespace hamal {
namespace {

Eigen::Matrix2d information() {
  Eigen::Matrix2d info;
  info << 4.0, 0.5, 0.5, 30.0;
  return info;
}

TEST(RangeBearingFactor, JacobiansMatchNumericOverRandomStates) {
  const RangeBearingFactor f(X(1), L(1), 5.0, -2.0, information());
  JacobianCheckOptions options;
  // Range and bearing are singular with the landmark on the robot.
  options.accept = [](const Values& v) { return (v.point(L(1)) - v.pose(X(1)).t()).norm() > 1e-3; };
  const JacobianCheckResult r = checkJacobians(f, options);
  EXPECT_TRUE(r.ok) << r.report;
  EXPECT_EQ(r.trials, 200);
}

TEST(RangeBearingFactor, EvaluateFailsWithTheLandmarkOnTheRobot) {
  Values v;
  v.insert(X(1), Pose2(2.0, 3.0, 1.0));
  v.insert(L(1), Point2(2.0, 3.0));
  double r[2];
  EXPECT_FALSE(RangeBearingFactor(X(1), L(1), 1.0, 0.0, information()).evaluate(v, r));
}

TEST(RangeBearingFactor, BearingIsFromTheRobotToTheLandmark) {
  // Robot at the origin facing +x, landmark 2 m to its left: bearing +pi/2
  // (the thesis' eq. 2.35 as printed would give -pi/2).
  Values v;
  v.insert(X(1), Pose2(0.0, 0.0, 0.0));
  v.insert(L(1), Point2(0.0, 2.0));
  double r[2];
  ASSERT_TRUE(
      RangeBearingFactor(X(1), L(1), 2.0, M_PI / 2, Eigen::Matrix2d::Identity()).evaluate(v, r));
  EXPECT_NEAR(r[0], 0.0, 1e-12);
  EXPECT_NEAR(r[1], 0.0, 1e-12);

  // Robot at (1, 2) facing +y, landmark (1, 5): 3 m straight ahead.
  v.set(X(1), Pose2(1.0, 2.0, M_PI / 2));
  v.set(L(1), Point2(1.0, 5.0));
  ASSERT_TRUE(RangeBearingFactor(X(1), L(1), 2.5, 0.1, information()).evaluate(v, r));
  const Eigen::Vector2d e(0.5, -0.1);
  EXPECT_NEAR(RangeBearingFactor(X(1), L(1), 2.5, 0.1, information()).chi2(v),
              e.dot(information() * e), 1e-12);
}

TEST(RangeBearingFactor, BearingResidualIsWrapped) {
  // Landmark behind the robot: bearing pi; measured -pi + 0.05 is 0.05 off.
  Values v;
  v.insert(X(1), Pose2(0.0, 0.0, 0.0));
  v.insert(L(1), Point2(-3.0, -1e-9));
  double r[2];
  ASSERT_TRUE(RangeBearingFactor(X(1), L(1), 3.0, -M_PI + 0.05, Eigen::Matrix2d::Identity())
                  .evaluate(v, r));
  EXPECT_NEAR(r[1], -0.05, 1e-8);
}

TEST(RangeBearingFactor, PredictsTheLandmarkFromThePose) {
  const RangeBearingFactor f(X(1), L(1), 7.5, 2.8, information());
  Values known;
  known.insert(X(1), Pose2(4.0, -2.0, 1.7));
  Values::Entry guess;
  ASSERT_TRUE(f.predict(L(1), known, &guess));
  known.insert(L(1), Point2(guess.data[0], guess.data[1]));
  EXPECT_LT(f.chi2(known), 1e-20);
  EXPECT_NEAR((known.point(L(1)) - known.pose(X(1)).t()).norm(), 7.5, 1e-12);
  EXPECT_FALSE(f.predict(X(1), known, &guess));
}

TEST(RangeBearingFactor, RoundTripsThroughItsFileLine) {
  EXPECT_TRUE(
      testing::roundTrips(RangeBearingFactor(X(1), L(2), 1.0 / 3.0, -M_PI / 7, information())));
  const RangeBearingFactor f(X(1), L(1), 5.0, -2.0, information());
  EXPECT_FALSE(f.equals(RangeBearingFactor(X(1), L(1), 5.0, -2.0 + 1e-6, information())));
  EXPECT_TRUE(f.equals(RangeBearingFactor(X(1), L(1), 5.0 + 1e-12, -2.0, information())));
}

}  // namespace
}  // namespace hamal
