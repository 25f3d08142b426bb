// PriorFactor (a pose measured in the global frame): Jacobians over random
// states, the residual by hand with its wrapped angle, predict(), and the
// EDGE_SE2_PRIOR round trip.
#include "factors/prior_factor.h"

#include <gtest/gtest.h>

#include <cmath>

#include "conformance/factor_round_trip.h"
#include "core/jacobian_check.h"

namespace hamal {
namespace {

Eigen::Matrix3d information() {
  Eigen::Matrix3d info;
  info << 40.0, 3.0, 1.0,  //
      3.0, 8.0, -0.5,      //
      1.0, -0.5, 20.0;
  return info;
}

TEST(PriorFactor, JacobiansMatchNumericOverRandomStates) {
  const PriorFactor f(X(3), Pose2(1.0, 2.0, 3.0), information());
  const JacobianCheckResult r = checkJacobians(f);
  EXPECT_TRUE(r.ok) << r.report;
  EXPECT_EQ(r.trials, 200);
}

TEST(PriorFactor, ResidualByHandWithTheAngleWrapped) {
  const PriorFactor f(X(3), Pose2(1.0, 2.0, 3.0), information());
  Values v;
  v.insert(X(3), Pose2(1.5, 1.0, -3.0));
  const Eigen::Vector3d e(0.5, -1.0, 2 * M_PI - 6.0);
  EXPECT_NEAR(f.chi2(v), e.dot(information() * e), 1e-10);
}

TEST(PriorFactor, PredictsItsPose) {
  const PriorFactor f(X(3), Pose2(1.0, 2.0, 3.0), information());
  Values::Entry guess;
  ASSERT_TRUE(f.predict(X(3), Values(), &guess));
  EXPECT_EQ(guess.data[0], 1.0);
  EXPECT_EQ(guess.data[1], 2.0);
  EXPECT_EQ(guess.data[2], 3.0);
}

TEST(PriorFactor, RoundTripsThroughItsFileLine) {
  EXPECT_TRUE(
      testing::roundTrips(PriorFactor(X(7), Pose2(1.0 / 3.0, -2.5, -M_PI / 3), information())));
  const PriorFactor f(X(3), Pose2(1.0, 2.0, 3.0), information());
  EXPECT_FALSE(f.equals(PriorFactor(X(4), Pose2(1.0, 2.0, 3.0), information())));
  EXPECT_FALSE(f.equals(PriorFactor(X(3), Pose2(1.0, 2.0 + 1e-6, 3.0), information())));
}

}  // namespace
}  // namespace hamal
