// The spoiling tool's claims (apps/robust/false_loop_closures.h): the same
// seed gives the same false edges, each policy draws the pairs it says, no
// pair is used twice, the measurement noise has the stated sigmas, and a
// request that cannot be met is an error, quickly, never a hang.
#include "apps/robust/false_loop_closures.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <set>

#include "apps/generator/manhattan_world.h"
#include "core/error.h"
#include "factors/between_factor.h"

namespace hamal::apps {
namespace {

// A chain of `poses` poses with one loop closure (0 -> poses-1) to take the
// information from.
Graph chain(std::size_t poses) {
  Graph g;
  g.source = "chain";
  const Eigen::Matrix3d info = Eigen::Vector3d(100, 100, 400).asDiagonal();
  for (std::size_t i = 0; i + 1 < poses; ++i)
    g.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0), info));
  const Eigen::Matrix3d lc = Eigen::Vector3d(44, 45, 46).asDiagonal();
  g.add(std::make_shared<BetweenFactor>(X(0), X(poses - 1), Pose2(0, 0, 0), lc));
  return g;
}

const BetweenFactor& between(const FactorPtr& f) { return dynamic_cast<const BetweenFactor&>(*f); }

TEST(FalseLoopClosures, SameSeedSameEdgesOtherSeedOtherEdges) {
  const Graph g = generateManhattanWorld({}).graph;
  for (const char* policy : {"random", "local", "random-group", "local-group"}) {
    SpoilOptions o;
    o.outliers = 57;
    o.policy = parseSpoilPolicy(policy);
    o.seed = 7;
    const SpoiledGraph a = spoilGraph(g, o), b = spoilGraph(g, o);
    ASSERT_EQ(a.false_edges.size(), 57u) << policy;
    for (std::size_t k = 0; k < a.false_edges.size(); ++k) {
      EXPECT_EQ(a.false_edges[k].from, b.false_edges[k].from);
      EXPECT_EQ(a.false_edges[k].to, b.false_edges[k].to);
      const auto& za = between(a.graph.factors[a.false_edges[k].factor]).measurement();
      const auto& zb = between(b.graph.factors[b.false_edges[k].factor]).measurement();
      EXPECT_EQ(za.x, zb.x);
      EXPECT_EQ(za.theta, zb.theta);
    }
    o.seed = 8;
    const SpoiledGraph c = spoilGraph(g, o);
    int same = 0;
    for (std::size_t k = 0; k < a.false_edges.size(); ++k)
      same += a.false_edges[k].from == c.false_edges[k].from &&
              a.false_edges[k].to == c.false_edges[k].to;
    EXPECT_LT(same, 10) << policy;
  }
}

TEST(FalseLoopClosures, CleanGraphFirstThenFalseEdgesOnFreeNonOdometryPairs) {
  const Graph g = generateManhattanWorld({}).graph;
  std::set<std::pair<std::uint64_t, std::uint64_t>> joined;
  for (const auto& f : g.factors) {
    auto a = f->keys()[0].index(), b = f->keys()[1].index();
    joined.insert({std::min(a, b), std::max(a, b)});
  }
  const Eigen::Matrix3d* info = nullptr;
  for (const auto& f : g.factors) {
    const auto& b = between(f);
    if (b.keys()[1].index() - b.keys()[0].index() != 1 &&
        b.keys()[0].index() - b.keys()[1].index() != 1) {
      info = &b.information();
      break;
    }
  }
  ASSERT_NE(info, nullptr);
  for (const char* policy : {"random", "local", "random-group", "local-group"}) {
    SpoilOptions o;
    o.outliers = 95;
    o.policy = parseSpoilPolicy(policy);
    const SpoiledGraph s = spoilGraph(g, o);
    ASSERT_EQ(s.graph.factors.size(), g.factors.size() + 95);
    for (std::size_t i = 0; i < g.factors.size(); ++i)
      EXPECT_EQ(s.graph.factors[i].get(), g.factors[i].get());
    std::set<std::pair<std::uint64_t, std::uint64_t>> used = joined;
    for (std::size_t k = 0; k < s.false_edges.size(); ++k) {
      const FalseEdge& e = s.false_edges[k];
      EXPECT_EQ(e.factor, g.factors.size() + k);
      EXPECT_GE(e.to, e.from + 2) << policy;
      if (o.policy == SpoilPolicy::kLocal || o.policy == SpoilPolicy::kLocalGroup)
        EXPECT_LE(e.to - e.from, o.local_window) << policy;
      EXPECT_TRUE(used.insert({e.from, e.to}).second) << policy << ": pair used twice";
      const auto& f = between(s.graph.factors[e.factor]);
      EXPECT_EQ(f.keys()[0], X(e.from));
      EXPECT_EQ(f.keys()[1], X(e.to));
      EXPECT_TRUE(f.information() == *info);
    }
    // Groups: group_size consecutive edges (i+k, j+k), one measurement.
    if (o.policy == SpoilPolicy::kRandomGroup || o.policy == SpoilPolicy::kLocalGroup) {
      for (std::size_t k = 1; k < s.false_edges.size(); ++k) {
        const FalseEdge &p = s.false_edges[k - 1], &e = s.false_edges[k];
        EXPECT_EQ(e.group, k / o.group_size) << policy;
        if (e.group != p.group) continue;
        EXPECT_EQ(e.from, p.from + 1);
        EXPECT_EQ(e.to, p.to + 1);
        EXPECT_EQ(between(s.graph.factors[e.factor]).measurement().x,
                  between(s.graph.factors[p.factor]).measurement().x);
      }
      EXPECT_EQ(s.false_edges.back().group, 9u);  // 9 groups of 10, then 5
    }
  }
}

// Victoria Park's shape: landmarks take ids between the poses (0, 2, 4, ...
// are poses, odd ids landmarks), so odometry joins ids 2 apart; the first
// loop closure is the one that joins poses not next to each other.
TEST(FalseLoopClosures, TheInformationIsALoopClosuresWhenLandmarksInterleave) {
  Graph g;
  g.source = "interleaved";
  const Eigen::Matrix3d odometry = Eigen::Vector3d(100, 100, 400).asDiagonal();
  const Eigen::Matrix3d lc = Eigen::Vector3d(44, 45, 46).asDiagonal();
  for (std::size_t i = 0; i + 1 < 10; ++i)
    g.add(std::make_shared<BetweenFactor>(X(2 * i), X(2 * i + 2), Pose2(1, 0, 0), odometry));
  g.add(std::make_shared<BetweenFactor>(X(0), X(18), Pose2(0, 0, 0), lc));
  SpoilOptions o;
  o.outliers = 3;
  const SpoiledGraph s = spoilGraph(g, o);
  ASSERT_EQ(s.false_edges.size(), 3u);
  for (const auto& e : s.false_edges)
    EXPECT_EQ(between(s.graph.factors[e.factor]).information(), lc);
}

TEST(FalseLoopClosures, NoiseHasTheStatedSigmas) {
  SpoilOptions o;
  o.outliers = 4000;
  const SpoiledGraph s = spoilGraph(chain(2000), o);
  double sx = 0, sy = 0, st = 0, mx = 0;
  for (const auto& e : s.false_edges) {
    const Pose2& z = between(s.graph.factors[e.factor]).measurement();
    sx += z.x * z.x;
    sy += z.y * z.y;
    st += z.theta * z.theta;
    mx += z.x;
  }
  const double n = s.false_edges.size();
  // Sample sigma of 4000 normals: standard error ~1.1%; 3 of them is 3.4%.
  EXPECT_NEAR(std::sqrt(sx / n), o.sigma_xy, 0.034 * o.sigma_xy);
  EXPECT_NEAR(std::sqrt(sy / n), o.sigma_xy, 0.034 * o.sigma_xy);
  EXPECT_NEAR(std::sqrt(st / n), o.sigma_theta, 0.034 * o.sigma_theta);
  EXPECT_NEAR(mx / n, 0, 3 * o.sigma_xy / std::sqrt(n));
}

TEST(FalseLoopClosures, EveryFreePairCanBeTakenAndOneMoreIsAnError) {
  // 8 poses: pairs with j - i >= 2 are 6+5+4+3+2+1 = 21, one taken by 0-7.
  const Graph g = chain(8);
  SpoilOptions o;
  EXPECT_EQ(freePosePairs(g, o), 20u);
  o.outliers = 20;
  const SpoiledGraph s = spoilGraph(g, o);
  EXPECT_EQ(s.false_edges.size(), 20u);
  o.outliers = 21;
  try {
    spoilGraph(g, o);
    FAIL() << "21 false edges on 20 free pairs";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("only 20 free pose pairs"), std::string::npos) << e.what();
  }
  o.policy = SpoilPolicy::kLocal;
  o.local_window = 3;  // gaps 2 and 3: 6 + 5 pairs
  EXPECT_EQ(freePosePairs(g, o), 11u);
  o.outliers = 11;
  EXPECT_EQ(spoilGraph(g, o).false_edges.size(), 11u);
  o.outliers = 12;
  EXPECT_THROW(spoilGraph(g, o), Error);
}

TEST(FalseLoopClosures, GroupsThatCannotFitAreAnErrorNotAHang) {
  // 20 poses, groups of 10: few starts fit, and after a few groups none.
  SpoilOptions o;
  o.policy = SpoilPolicy::kRandomGroup;
  o.outliers = 100;  // fewer than the 170 free pairs, more than groups can hold
  const auto start = std::chrono::steady_clock::now();
  try {
    spoilGraph(chain(20), o);
    FAIL() << "100 grouped edges fit on 20 poses";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no free pose pairs left"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

TEST(FalseLoopClosures, BadRequestsAreErrors) {
  SpoilOptions o;
  o.outliers = 1;
  Graph no_loops;
  no_loops.source = "odometry only";
  for (int i = 0; i < 5; ++i)
    no_loops.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0),
                                                 Eigen::Matrix3d::Identity()));
  EXPECT_THROW(spoilGraph(no_loops, o), Error);
  EXPECT_THROW(spoilGraph(chain(2), o), Error);
  o.policy = SpoilPolicy::kLocal;
  o.local_window = 1;
  EXPECT_THROW(spoilGraph(chain(10), o), Error);
  EXPECT_THROW(parseSpoilPolicy("grouped"), Error);
  o = SpoilOptions();  // zero outliers: the clean graph as it was
  EXPECT_EQ(spoilGraph(chain(10), o).graph.factors.size(), 10u);
}

}  // namespace
}  // namespace hamal::apps
