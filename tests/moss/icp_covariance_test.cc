// IcpCovariance (Censi's closed form): the spread of the point-to-line ICP
// estimate over many live scans with independent range noise (Monte Carlo)
// matches the closed form within its sampling error; a scan matcher told to
// use it turns it into the L2G information.
#include "apps/moss/icp_covariance.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <random>

#include "core/error.h"

namespace hamal::moss {
namespace {

TEST(IcpCovariance, MatchesAMonteCarloEstimate) {
  const World w = loadWorld("CORRIDOR");
  const Laser laser;  // sigma_d = 2 cm
  const Pose2 node(9.0, 0.0, 0.0), live(9.25, 0.15, 0.08);
  const IndexedScan ref(laser.scan(node, w.walls, {}, nullptr));  // the map's scan, fixed
  const Pose2 truth = node.between(live);
  const ScanMatcher matcher;
  std::mt19937_64 rng(11);
  const int samples = 600;
  std::vector<Eigen::Vector3d> x;
  Eigen::Matrix3d closed = Eigen::Matrix3d::Zero();
  // The Gauss-Newton Hessian with the same sigma_d, for comparison.
  ScanMatcherConfig hessian_config;
  hessian_config.sigma = laser.config().sigma_range;
  hessian_config.min_eigenvalue = 0.0;
  const ScanMatcher hessian_matcher(hessian_config);
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
  for (int k = 0; k < samples; ++k) {
    const Scan scan = laser.scan(live, w.walls, {}, &rng);
    const ScanMatch m = matcher.match(ref, scan, truth);
    ASSERT_TRUE(m.ok);
    x.emplace_back(m.relative.x, m.relative.y, m.relative.theta);
    const IcpCovariance c = icpCovariance(ref, scan, m.relative, matcher.config().gate_fine,
                                          laser.config().sigma_range);
    ASSERT_TRUE(c.ok);
    closed += c.covariance / samples;
    hessian += hessian_matcher.match(ref, scan, truth).information.inverse() / samples;
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& v : x) mean += v / samples;
  Eigen::Matrix3d sample = Eigen::Matrix3d::Zero();
  for (const auto& v : x) sample += (v - mean) * (v - mean).transpose() / (samples - 1);
  // A variance estimated from n samples has a relative standard error of
  // sqrt(2 / (n - 1)), 5.8% here: 3 of them, and a little for the model's
  // linearisation, bound the ratio.
  for (int d = 0; d < 3; ++d) {
    const double ratio = sample(d, d) / closed(d, d);
    EXPECT_GT(ratio, 0.8) << "axis " << d << "\nsample\n" << sample << "\nclosed\n" << closed;
    EXPECT_LT(ratio, 1.25) << "axis " << d << "\nsample\n" << sample << "\nclosed\n" << closed;
  }
  // J^T J / sigma_d^2 ignores how obliquely each beam meets its wall: here it
  // overstates theta's variance by more than half.
  EXPECT_LT(sample(2, 2) / hessian(2, 2), 0.75) << "hessian\n" << hessian;
  // Correlations agree too (their sampling error is about 1 / sqrt(n)).
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      const double rs = sample(a, b) / std::sqrt(sample(a, a) * sample(b, b));
      const double rc = closed(a, b) / std::sqrt(closed(a, a) * closed(b, b));
      EXPECT_NEAR(rs, rc, 0.15) << a << "," << b;
    }
}

TEST(IcpCovariance, TheMatcherUsesItsInverseAsInformation) {
  const World w = loadWorld("CORRIDOR");
  const Laser laser;
  const Pose2 node(9.0, 0.0, 0.0), live(9.25, 0.15, 0.08);
  std::mt19937_64 rng(3);
  const IndexedScan ref(laser.scan(node, w.walls, {}, &rng));
  const Scan scan = laser.scan(live, w.walls, {}, &rng);
  ScanMatcherConfig config;
  config.information = ScanMatcherConfig::Information::kCensi;
  config.min_eigenvalue = 0.0;
  const ScanMatch m = ScanMatcher(config).match(ref, scan, node.between(live));
  ASSERT_TRUE(m.ok);
  const IcpCovariance c =
      icpCovariance(ref, scan, m.relative, config.gate_fine, config.sigma_range);
  ASSERT_TRUE(c.ok);
  EXPECT_LT((m.information * c.covariance - Eigen::Matrix3d::Identity()).norm(), 1e-6);
  EXPECT_EQ(parseInformation("censi"), ScanMatcherConfig::Information::kCensi);
  EXPECT_EQ(parseInformation("hessian"), ScanMatcherConfig::Information::kHessian);
  EXPECT_THROW(parseInformation("fisher"), Error);
}

// --censi_sigma: the matcher's sigma_d scales the covariance by sigma_d^2, so
// the L2G information at 5 cm is (2/5)^2 of the one at 2 cm, same match.
TEST(IcpCovariance, SigmaDScalesTheInformation) {
  const World w = loadWorld("CORRIDOR");
  const Laser laser;
  const Pose2 node(9.0, 0.0, 0.0), live(9.25, 0.15, 0.08);
  std::mt19937_64 rng(5);
  const IndexedScan ref(laser.scan(node, w.walls, {}, &rng));
  const Scan scan = laser.scan(live, w.walls, {}, &rng);
  ScanMatcherConfig config;
  config.information = ScanMatcherConfig::Information::kCensi;
  config.min_eigenvalue = 0.0;
  const ScanMatch at2 = ScanMatcher(config).match(ref, scan, node.between(live));
  config.sigma_range = 0.05;
  const ScanMatch at5 = ScanMatcher(config).match(ref, scan, node.between(live));
  ASSERT_TRUE(at2.ok && at5.ok);
  EXPECT_EQ(at2.relative.x, at5.relative.x);
  EXPECT_LT((at5.information - 0.16 * at2.information).norm(), 1e-9 * at2.information.norm());
}

TEST(IcpCovariance, TooFewPairsIsNotOk) {
  const IndexedScan ref(Scan{Point2(1, 0), Point2(1, 0.01)});
  EXPECT_FALSE(icpCovariance(ref, Scan{Point2(1, 0)}, Pose2(), 0.2, 0.02).ok);
}

}  // namespace
}  // namespace hamal::moss
