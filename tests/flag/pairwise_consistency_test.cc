// The pairwise consistency check and nearest-neighbour association
// (apps/flag/pairwise_consistency.h, nearest_neighbour_association.h). The
// maximum clique found through igraph is compared with an exhaustive search
// over every subset of small random graphs, an independent answer.
#include "apps/flag/pairwise_consistency.h"

#include <gtest/gtest.h>

#include <random>

#include "apps/flag/nearest_neighbour_association.h"
#include "core/error.h"

namespace hamal::flag {
namespace {

TEST(PairwiseConsistency, AcceptsAClusterAndRejectsAWalkingPerson) {
  // Five measurements of a landmark within 4 cm of each other, and a person
  // moving 15 cm between measurements (thesis fig. 4.7).
  std::vector<Point2> points = {{0, 0}, {0.03, 0}, {0, 0.03}, {0.02, 0.02}, {-0.01, 0.02}};
  for (int k = 0; k < 5; ++k) points.emplace_back(0.3 + 0.15 * k, 0.2);
  const PairwiseConsistency check(0.10, 2, false);
  const std::vector<bool> ok = check.check(points);
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(ok[k]) << k;
  for (int k = 5; k < 10; ++k) EXPECT_FALSE(ok[k]) << k;
  const PairwiseConsistency clique(0.10, 2, true);
  EXPECT_EQ(clique.check(points), ok);
}

TEST(PairwiseConsistency, NeedsEnoughLinks) {
  const std::vector<Point2> pair = {{0, 0}, {0.05, 0}};
  EXPECT_EQ(PairwiseConsistency(0.1, 1, false).check(pair), (std::vector<bool>{true, true}));
  EXPECT_EQ(PairwiseConsistency(0.1, 2, false).check(pair), (std::vector<bool>{false, false}));
  EXPECT_EQ(PairwiseConsistency(0.1, 2, true).check(pair), (std::vector<bool>{false, false}));
  EXPECT_TRUE(PairwiseConsistency(0.1, 1, true).check({}).empty());
}

TEST(PairwiseConsistency, CovariancesWidenTheThreshold) {
  // Three sightings of a corner 20-30 cm apart through poses 10 cm uncertain
  // (each point's covariance 0.01 I): inconsistent at the thesis' fixed
  // 10 cm, consistent within 3 sigmas of their difference (sqrt(0.02) m).
  const std::vector<Point2> points = {{0, 0}, {0.2, 0}, {0.1, 0.25}};
  const std::vector<Eigen::Matrix2d> cov(3, 0.01 * Eigen::Matrix2d::Identity());
  const std::vector<bool> all(3, true), none(3, false);
  EXPECT_EQ(PairwiseConsistency(0.1, 2, false).check(points, {}, cov), none);
  EXPECT_EQ(PairwiseConsistency(0.1, 2, false, 3).check(points, {}, cov), all);
  EXPECT_EQ(PairwiseConsistency(0.1, 2, true, 3).check(points, {}, cov), all);
  EXPECT_EQ(PairwiseConsistency(0.1, 2, false, 3).check(points), none);  // no covariances
  // A person walking 1 m between sightings stays inconsistent.
  const std::vector<Point2> walk = {{0, 0}, {1, 0}, {2, 0}};
  EXPECT_EQ(PairwiseConsistency(0.1, 1, false, 3).check(walk, {}, cov), none);
  // The covariance counts along its axes: 0.3 m apart along a 0.1 m axis
  // (and 0.02 m across) is consistent, across it is not.
  Eigen::Matrix2d thin = Eigen::Matrix2d::Zero();
  thin(0, 0) = 0.01;
  thin(1, 1) = 1e-6;
  const std::vector<Eigen::Matrix2d> thins(2, thin);
  EXPECT_EQ(PairwiseConsistency(0.1, 1, false, 3).edges({{0, 0}, {0.3, 0}}, thins).size(), 1u);
  EXPECT_TRUE(PairwiseConsistency(0.1, 1, false, 3).edges({{0, 0}, {0, 0.3}}, thins).empty());
  EXPECT_THROW(PairwiseConsistency(0.1, 1, false, 3).check(walk, {}, thins), Error);
}

// The largest clique by trying every subset, largest first.
std::size_t bruteForceCliqueSize(const std::vector<std::vector<bool>>& adj) {
  const std::size_t n = adj.size();
  std::size_t best = 0;
  for (unsigned mask = 1; mask < (1u << n); ++mask) {
    std::size_t size = __builtin_popcount(mask);
    if (size <= best) continue;
    bool clique = true;
    for (std::size_t i = 0; i < n && clique; ++i)
      for (std::size_t j = i + 1; j < n && clique; ++j)
        if ((mask >> i & 1) && (mask >> j & 1) && !adj[i][j]) clique = false;
    if (clique) best = size;
  }
  return best;
}

TEST(PairwiseConsistency, MaximumCliqueMatchesExhaustiveSearch) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 0.3);
  const PairwiseConsistency clique(0.10, 1, true);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Point2> points(2 + trial % 11);
    for (Point2& p : points) p = Point2(u(rng), u(rng));
    std::vector<std::vector<bool>> adj(points.size(), std::vector<bool>(points.size(), false));
    for (const auto& [i, j] : clique.edges(points)) adj[i][j] = adj[j][i] = true;
    const std::size_t expected = bruteForceCliqueSize(adj);
    const std::vector<bool> ok = clique.check(points);
    std::vector<std::size_t> members;
    for (std::size_t i = 0; i < ok.size(); ++i)
      if (ok[i]) members.push_back(i);
    if (expected < 2) {
      EXPECT_TRUE(members.empty());
      continue;
    }
    EXPECT_EQ(members.size(), expected) << "trial " << trial;
    for (std::size_t a : members)
      for (std::size_t b : members)
        if (a != b) EXPECT_TRUE(adj[a][b]) << "trial " << trial;
  }
}

TEST(NearestNeighbourAssociation, NearestWithinTheGate) {
  const NearestNeighbourAssociation nn(0.5);
  const std::vector<Point2> landmarks = {{0, 0}, {1, 0}, {0, 3}};
  EXPECT_EQ(nn.associate({0.4, 0}, landmarks), std::optional<std::size_t>(0));
  EXPECT_EQ(nn.associate({0.6, 0}, landmarks), std::optional<std::size_t>(1));
  EXPECT_EQ(nn.associate({0, 2}, landmarks), std::nullopt);
  EXPECT_EQ(nn.associate({0, 0}, {}), std::nullopt);
  const Point2 p = project(Pose2(1, 2, 3.14159265358979323846 / 2), 2.0, 0.0);
  EXPECT_NEAR((p - Point2(1, 4)).norm(), 0, 1e-12);
}

}  // namespace
}  // namespace hamal::flag
