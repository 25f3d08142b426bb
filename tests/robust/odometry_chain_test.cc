// The odometry chain's O(1) covariance from prefix sums
// (backends/robust/odometry_chain.h) against step-by-step first-order
// propagation on random chains, in both directions, and its errors.
#include "backends/robust/odometry_chain.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/position_factor.h"

namespace hamal::robust {
namespace {

Eigen::Matrix3d randomCovariance(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix3d a;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a(r, c) = u(rng);
  Eigen::Matrix3d cov = 1e-3 * (a * a.transpose() + 0.1 * Eigen::Matrix3d::Identity());
  cov.row(2) *= 0.1;
  cov.col(2) *= 0.1;
  return cov;
}

struct RandomChain {
  std::uint64_t first = 7;
  std::vector<UncertainPose> links;  // x_m-1^-1 x_m
  OdometryChain chain;
};

RandomChain randomChain(std::uint64_t seed, int n, bool reverse_some) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> step(-2, 2), turn(-1.5, 1.5);
  RandomChain c;
  for (int m = 0; m < n; ++m) {
    UncertainPose z{Pose2(step(rng), step(rng), turn(rng)), randomCovariance(rng)};
    c.links.push_back(z);
    const Key a = X(c.first + m), b = X(c.first + m + 1);
    if (reverse_some && m % 3 == 1) {
      // The same link written from x_m to x_m-1 (InverseIsFirstOrderExact
      // checks inverse()).
      const UncertainPose zi = inverse(z);
      c.chain.add(BetweenFactor(b, a, zi.pose, zi.covariance.inverse()));
    } else {
      c.chain.add(BetweenFactor(a, b, z.pose, z.covariance.inverse()));
    }
  }
  return c;
}

// x_a^-1 x_b composed link by link, with Sigma' = F Sigma F^T + G Sigma_m G^T.
UncertainPose stepByStep(const RandomChain& c, std::uint64_t a, std::uint64_t b) {
  UncertainPose out;
  for (std::uint64_t m = a; m < b; ++m) {
    const UncertainPose& z = c.links[m - c.first];
    Eigen::Matrix3d f = Eigen::Matrix3d::Identity(), g = Eigen::Matrix3d::Identity();
    const Eigen::Vector2d rt = out.pose.R() * z.pose.t();
    f(0, 2) = -rt.y();
    f(1, 2) = rt.x();
    g.topLeftCorner<2, 2>() = out.pose.R();
    out.covariance = f * out.covariance * f.transpose() + g * z.covariance * g.transpose();
    out.pose = out.pose.compose(z.pose);
  }
  return out;
}

double relativeError(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return (a - b).norm() / b.norm();
}

TEST(OdometryChain, PrefixSumCovarianceEqualsStepByStepPropagation) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const RandomChain c = randomChain(seed, 200, seed == 2);
    std::mt19937_64 rng(seed + 100);
    std::uniform_int_distribution<std::uint64_t> id(c.first, c.first + 200);
    for (int q = 0; q < 50; ++q) {
      std::uint64_t a = id(rng), b = id(rng);
      if (a > b) std::swap(a, b);
      if (a == b) continue;
      const UncertainPose direct = stepByStep(c, a, b);
      const UncertainPose fast = c.chain.between(a, b);
      EXPECT_NEAR(fast.pose.x, direct.pose.x, 1e-9);
      EXPECT_NEAR(fast.pose.y, direct.pose.y, 1e-9);
      EXPECT_NEAR(wrapAngle(fast.pose.theta - direct.pose.theta), 0, 1e-9);
      EXPECT_LT(relativeError(fast.covariance, direct.covariance), 1e-8) << a << " " << b;
      // Backwards: the inverse, with its covariance in x_b's frame.
      const UncertainPose back = c.chain.between(b, a);
      const UncertainPose inv = inverse(direct);
      EXPECT_NEAR(back.pose.x, inv.pose.x, 1e-9);
      EXPECT_NEAR(back.pose.y, inv.pose.y, 1e-9);
      EXPECT_LT(relativeError(back.covariance, inv.covariance), 1e-8);
    }
  }
}

TEST(OdometryChain, InverseIsFirstOrderExact) {
  // inverse()'s Jacobian against central differences of z -> z^-1.
  std::mt19937_64 rng(9);
  const UncertainPose z{Pose2(1.3, -0.7, 2.1), randomCovariance(rng)};
  Eigen::Matrix3d numeric;
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[k] = h;
    const Pose2 plus = Pose2(z.pose.x + d.x(), z.pose.y + d.y(), z.pose.theta + d.z()).inverse();
    const Pose2 minus = Pose2(z.pose.x - d.x(), z.pose.y - d.y(), z.pose.theta - d.z()).inverse();
    numeric.col(k) =
        Eigen::Vector3d(plus.x - minus.x, plus.y - minus.y, wrapAngle(plus.theta - minus.theta)) /
        (2 * h);
  }
  const UncertainPose zi = inverse(z);
  EXPECT_LT(relativeError(zi.covariance, numeric * z.covariance * numeric.transpose()), 1e-7);
  EXPECT_NEAR(zi.pose.x, z.pose.inverse().x, 1e-15);
}

TEST(OdometryChain, LinksAddedOutOfOrderGiveTheSameChain) {
  const RandomChain c = randomChain(4, 30, false);
  OdometryChain shuffled;
  for (int m = 29; m >= 0; --m)
    shuffled.add(BetweenFactor(X(c.first + m), X(c.first + m + 1), c.links[m].pose,
                               c.links[m].covariance.inverse()));
  const UncertainPose a = c.chain.between(c.first + 3, c.first + 25);
  const UncertainPose b = shuffled.between(c.first + 3, c.first + 25);
  EXPECT_NEAR(a.pose.x, b.pose.x, 1e-12);
  EXPECT_LT(relativeError(a.covariance, b.covariance), 1e-10);
  EXPECT_TRUE(a.covariance.isApprox(stepByStep(c, c.first + 3, c.first + 25).covariance, 1e-8));
}

TEST(OdometryChain, CrossCovarianceIsTheSharedLinks) {
  const RandomChain c = randomChain(5, 40, false);
  const std::uint64_t f = c.first;
  // (f+5, f+20] and (f+10, f+30] share (f+10, f+20]; the second chain runs backwards.
  const Eigen::Matrix3d shared = c.chain.noiseCovariance(f + 10, f + 20);
  EXPECT_TRUE(c.chain.noiseCrossCovariance(f + 5, f + 20, f + 10, f + 30).isApprox(shared));
  EXPECT_TRUE(c.chain.noiseCrossCovariance(f + 5, f + 20, f + 30, f + 10).isApprox(-shared));
  EXPECT_TRUE(c.chain.noiseCrossCovariance(f + 1, f + 5, f + 10, f + 30).isZero());
}

TEST(OdometryChain, AMissingLinkIsAnErrorNamingThePoses) {
  OdometryChain chain;
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  chain.add(BetweenFactor(X(0), X(1), Pose2(1, 0, 0), info));
  chain.add(BetweenFactor(X(1), X(2), Pose2(1, 0, 0), info));
  chain.add(BetweenFactor(X(3), X(4), Pose2(1, 0, 0), info));
  EXPECT_NO_THROW(chain.between(0, 2));
  try {
    chain.between(1, 4);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x1 and x4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("x2 -> x3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(chain.between(0, 9), Error);
  chain.add(BetweenFactor(X(2), X(3), Pose2(1, 0, 0), info));  // the gap closes
  EXPECT_NEAR(chain.between(0, 4).pose.x, 4, 1e-12);
  // Not odometry: not one id apart, or no relative pose.
  EXPECT_FALSE(OdometryChain::isOdometry(BetweenFactor(X(0), X(2), Pose2(), info)));
  EXPECT_THROW(chain.add(BetweenFactor(X(0), X(2), Pose2(), info)), Error);
  EXPECT_FALSE(
      OdometryChain::isOdometry(PositionFactor(X(1), Point2(0, 0), Eigen::Matrix2d::Identity())));
}

TEST(OdometryChain, TwoMeasurementsOfOneLinkAreFused) {
  OdometryChain chain;
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  chain.add(BetweenFactor(X(0), X(1), Pose2(1, 0, 0), info));
  chain.add(BetweenFactor(X(0), X(1), Pose2(2, 0, 0), info));
  const UncertainPose z = chain.between(0, 1);
  EXPECT_NEAR(z.pose.x, 1.5, 1e-12);
  EXPECT_TRUE(z.covariance.isApprox(0.5 * Eigen::Matrix3d::Identity()));
}

}  // namespace
}  // namespace hamal::robust
