// The doubt rule "the noise the answer shows" (backends/robust/noise_scale.h):
// the a-posteriori variance factor counts the redundancy of what an answer
// keeps.
#include "backends/robust/noise_scale.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "factors/between_factor.h"

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

}  // namespace
}  // namespace hamal::robust
