// LandmarkPriorFactor (a landmark's position measured in the global frame):
// Jacobians over random states, the residual by hand, predict(), the
// EDGE_XY_PRIOR round trip.
#include "factors/landmark_prior_factor.h"

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

TEST(LandmarkPriorFactor, JacobiansMatchNumericOverRandomStates) {
  const LandmarkPriorFactor f(L(9), Point2(0.5, -0.25), information());
  const JacobianCheckResult r = checkJacobians(f);
  EXPECT_TRUE(r.ok) << r.report;
  EXPECT_EQ(r.trials, 200);
}

TEST(LandmarkPriorFactor, ResidualByHandAndPredict) {
  const LandmarkPriorFactor f(L(9), Point2(0.5, -0.25), information());
  Values v;
  v.insert(L(9), Point2(1.5, 0.75));
  const Eigen::Vector2d e(1.0, 1.0);
  EXPECT_NEAR(f.chi2(v), e.dot(information() * e), 1e-12);
  Values::Entry guess;
  ASSERT_TRUE(f.predict(L(9), Values(), &guess));
  EXPECT_EQ(guess.type, VariableType::kPoint2);
  EXPECT_EQ(guess.data[0], 0.5);
  EXPECT_EQ(guess.data[1], -0.25);
}

TEST(LandmarkPriorFactor, RoundTripsThroughItsFileLine) {
  EXPECT_TRUE(
      testing::roundTrips(LandmarkPriorFactor(L(9), Point2(1.0 / 3.0, -1e-9), information())));
  const LandmarkPriorFactor f(L(9), Point2(0.5, -0.25), information());
  EXPECT_FALSE(f.equals(LandmarkPriorFactor(L(8), Point2(0.5, -0.25), information())));
  EXPECT_FALSE(f.equals(LandmarkPriorFactor(L(9), Point2(0.5, -0.25), 2.0 * information())));
}

}  // namespace
}  // namespace hamal
