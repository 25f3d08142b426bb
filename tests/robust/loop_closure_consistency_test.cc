// The pairwise consistency of two loop closures
// (backends/robust/loop_closure_consistency.h): the cycle's first-order
// covariance against a Monte-Carlo estimate (with and without odometry the
// two chains share), and on a simulated world with its
// true noise: true closures agree, random false ones do not.
#include "backends/robust/loop_closure_consistency.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <random>

#include "apps/generator/manhattan_world.h"
#include "apps/robust/false_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/loop_closure.h"
#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/position_factor.h"

namespace hamal::robust {
namespace {

Eigen::Matrix3d randomCovariance(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix3d a;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a(r, c) = u(rng);
  Eigen::Matrix3d cov = scale * (a * a.transpose() + 0.2 * Eigen::Matrix3d::Identity());
  cov.row(2) *= 0.1;
  cov.col(2) *= 0.1;
  return cov;
}

Pose2 perturb(const Pose2& z, const Eigen::Matrix3d& cov, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  const Eigen::Vector3d d =
      Eigen::LLT<Eigen::Matrix3d>(cov).matrixL() * Eigen::Vector3d(n(rng), n(rng), n(rng));
  return Pose2(z.x + d.x(), z.y + d.y(), wrapAngle(z.theta + d.z()));
}

LoopClosure closure(std::uint64_t from, std::uint64_t to, const Pose2& z,
                    const Eigen::Matrix3d& cov) {
  return loopClosureOf(BetweenFactor(X(from), X(to), z, cov.inverse()));
}

// A random 40-pose chain and two true closures; the cycle's error over
// noisy draws of everything, against the covariance at the true values.
void checkMonteCarlo(std::uint64_t i, std::uint64_t j, std::uint64_t k, std::uint64_t l) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> step(-1, 1), turn(-0.5, 0.5);
  const int n = 40;
  std::vector<Pose2> links, truth{Pose2()};
  std::vector<Eigen::Matrix3d> covs;
  OdometryChain exact;
  for (int m = 0; m < n; ++m) {
    links.emplace_back(step(rng), step(rng), turn(rng));
    covs.push_back(randomCovariance(rng, 2e-4));
    truth.push_back(truth.back().compose(links.back()));
    exact.add(BetweenFactor(X(m), X(m + 1), links[m], covs[m].inverse()));
  }
  const Eigen::Matrix3d cov_a = randomCovariance(rng, 1e-3), cov_b = randomCovariance(rng, 1e-3);
  const Pose2 za = truth[i].between(truth[j]), zb = truth[k].between(truth[l]);
  const CycleError at_truth = cycleError(exact, closure(i, j, za, cov_a), closure(k, l, zb, cov_b));
  EXPECT_LT(at_truth.error.norm(), 1e-12);

  const int draws = 4000;
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  int inside = 0;
  double mean_d2 = 0;
  const double threshold = chiSquareQuantile(3, 0.99);
  for (int s = 0; s < draws; ++s) {
    OdometryChain noisy;
    for (int m = 0; m < n; ++m)
      noisy.add(BetweenFactor(X(m), X(m + 1), perturb(links[m], covs[m], rng), covs[m].inverse()));
    const CycleError e = cycleError(noisy, closure(i, j, perturb(za, cov_a, rng), cov_a),
                                    closure(k, l, perturb(zb, cov_b, rng), cov_b));
    second += e.error * e.error.transpose();
    mean_d2 += e.mahalanobis2 / draws;
    inside += e.mahalanobis2 < threshold;
  }
  second /= draws;
  EXPECT_LT((second - at_truth.covariance).norm() / at_truth.covariance.norm(), 0.08)
      << "Monte-Carlo\n"
      << second << "\nfirst order\n"
      << at_truth.covariance;
  EXPECT_NEAR(mean_d2, 3.0, 0.25);
  EXPECT_NEAR(static_cast<double>(inside) / draws, 0.99, 0.006);
}

TEST(LoopClosureConsistency, CycleCovarianceMatchesMonteCarloWithSeparateChains) {
  checkMonteCarlo(2, 30, 10, 25);
}

TEST(LoopClosureConsistency, CycleCovarianceMatchesMonteCarloWhenTheChainsShareOdometry) {
  // x2 -> x20 and x5 -> x30 share (x5, x20]; b runs backwards.
  checkMonteCarlo(2, 30, 20, 5);
}

TEST(LoopClosureConsistency, AFactorWithoutARelativePoseIsAnErrorNamingIt) {
  try {
    loopClosureOf(PositionFactor(X(4), Point2(1, 2), Eigen::Matrix2d::Identity()));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("relative-pose"), std::string::npos) << e.what();
  }
}

TEST(LoopClosureConsistency, TrueClosuresAgreeAndFalseOnesDoNot) {
  apps::ManhattanWorldOptions w;
  w.poses = 400;
  w.seed = 3;
  const Graph clean = apps::generateManhattanWorld(w).graph;
  apps::SpoilOptions o;
  o.outliers = 30;
  o.seed = 5;
  const apps::SpoiledGraph spoiled = apps::spoilGraph(clean, o);
  OdometryChain chain;
  std::vector<LoopClosure> truth, wrong;
  for (std::size_t f = 0; f < spoiled.graph.factors.size(); ++f) {
    const Factor& factor = *spoiled.graph.factors[f];
    if (OdometryChain::isOdometry(factor)) chain.add(factor);
    if (!isLoopClosure(factor)) continue;
    (f < clean.factors.size() ? truth : wrong).push_back(loopClosureOf(factor));
  }
  ASSERT_GT(truth.size(), 50u);
  const double threshold = chiSquareQuantile(3, 0.99);
  std::size_t true_pairs = 0, true_consistent = 0, mixed_pairs = 0, mixed_consistent = 0;
  for (std::size_t a = 0; a < truth.size(); ++a) {
    for (std::size_t b = a + 1; b < truth.size(); ++b, ++true_pairs)
      true_consistent += cycleError(chain, truth[a], truth[b]).mahalanobis2 < threshold;
    for (const LoopClosure& f : wrong) {
      ++mixed_pairs;
      mixed_consistent += cycleError(chain, truth[a], f).mahalanobis2 < threshold;
    }
  }
  const double t = double(true_consistent) / true_pairs, m = double(mixed_consistent) / mixed_pairs;
  EXPECT_GT(t, 0.97) << true_consistent << " of " << true_pairs;
  EXPECT_LT(m, 0.05) << mixed_consistent << " of " << mixed_pairs;
}

}  // namespace
}  // namespace hamal::robust
