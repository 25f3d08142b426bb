// The synthetic Manhattan world (apps/generator/manhattan_world.h): same seed
// same graph, another seed another graph; the counts, the grid, the noise
// level and the loop closures are what the header promises.
#include "apps/generator/manhattan_world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "factors/between_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal::apps {
namespace {

std::string asG2o(const ManhattanWorld& world) {
  std::ostringstream os;
  writeG2o(os, world.graph.initial, world.graph.factors);
  return os.str();
}

ManhattanWorld make(std::size_t poses, std::uint64_t seed) {
  ManhattanWorldOptions options;
  options.poses = poses;
  options.seed = seed;
  return generateManhattanWorld(options);
}

TEST(ManhattanWorld, SameSeedGivesTheSameGraph) {
  const ManhattanWorld a = make(500, 42), b = make(500, 42);
  EXPECT_EQ(asG2o(a), asG2o(b));
  for (Key k : a.truth.keys()) {
    EXPECT_EQ(a.truth.pose(k).x, b.truth.pose(k).x);
    EXPECT_EQ(a.truth.pose(k).theta, b.truth.pose(k).theta);
  }
}

TEST(ManhattanWorld, AnotherSeedGivesAnotherGraph) {
  const ManhattanWorld a = make(500, 1), b = make(500, 2);
  EXPECT_NE(asG2o(a), asG2o(b));
  // Not only the noise: the path differs too.
  bool path_differs = false;
  for (Key k : a.truth.keys())
    path_differs |=
        a.truth.pose(k).x != b.truth.pose(k).x || a.truth.pose(k).y != b.truth.pose(k).y;
  EXPECT_TRUE(path_differs);
}

TEST(ManhattanWorld, CountsAndLoopClosures) {
  const ManhattanWorld world = make(1000, 3);
  EXPECT_EQ(world.truth.size(), 1000u);
  EXPECT_EQ(world.graph.initial.size(), 1000u);
  EXPECT_EQ(world.odometry_edges, 999u);
  EXPECT_GT(world.loop_closures, 50u);  // about 0.3 per pose with the defaults
  EXPECT_EQ(world.graph.factors.size(), world.odometry_edges + world.loop_closures);
  EXPECT_EQ(world.world_size, 32u);  // ceil(sqrt(1000))

  std::size_t closures = 0;
  for (const auto& f : world.graph.factors) {
    const auto* between = dynamic_cast<const BetweenFactor*>(f.get());
    ASSERT_NE(between, nullptr);
    EXPECT_EQ(f->tag(), "EDGE_SE2");
    const Key a = f->keys()[0], b = f->keys()[1];
    ASSERT_LT(a.index(), b.index());
    // Isotropic in x, y (so thesis and measurement-frame residuals agree).
    EXPECT_EQ(between->information()(0, 0), between->information()(1, 1));
    EXPECT_EQ(between->information()(0, 1), 0.0);
    if (b.index() == a.index() + 1) continue;
    ++closures;
    EXPECT_GE(b.index() - a.index(), 10u);  // min_loop_gap
    const Pose2 ta = world.truth.pose(a), tb = world.truth.pose(b);
    EXPECT_LE(std::hypot(ta.x - tb.x, ta.y - tb.y), 1.5);  // the radius
  }
  EXPECT_EQ(closures, world.loop_closures);
}

TEST(ManhattanWorld, TruthIsAUnitStepWalkOnTheGridInsideTheWorld) {
  const ManhattanWorld world = make(2000, 5);
  // [-floor(side / 2), side - floor(side / 2)], pose 0 at the origin.
  const double low = -double(world.world_size / 2), high = low + double(world.world_size);
  for (std::size_t i = 0; i < 2000; ++i) {
    const Pose2 p = world.truth.pose(X(i));
    EXPECT_EQ(p.x, std::round(p.x));
    EXPECT_TRUE(p.x >= low && p.x <= high && p.y >= low && p.y <= high) << p.x << " " << p.y;
    const double quarter = p.theta / (M_PI / 2);
    EXPECT_NEAR(quarter, std::round(quarter), 1e-12);
    if (i == 0) continue;
    const Pose2 q = world.truth.pose(X(i - 1));
    EXPECT_DOUBLE_EQ(std::hypot(p.x - q.x, p.y - q.y), 1.0);
    // The heading is the direction of the step: never a U-turn.
    EXPECT_NEAR(std::cos(p.theta) * (p.x - q.x) + std::sin(p.theta) * (p.y - q.y), 1.0, 1e-12);
  }
}

TEST(ManhattanWorld, NoiseMatchesTheSigmas) {
  // chi2 at the truth is a sum of 3 M squared standard normals: mean 3 M,
  // standard deviation sqrt(6 M). 5 sigma either way.
  ManhattanWorldOptions options;
  options.poses = 3000;
  options.noise.sigma_xy = 0.2;
  options.noise.sigma_theta = 0.03;
  const ManhattanWorld world = generateManhattanWorld(options);
  const double m = double(world.graph.factors.size());
  EXPECT_NEAR(chi2(world.graph.factors, world.truth), 3 * m, 5 * std::sqrt(6 * m));
  // The initial values are the noisy odometry composed: they drift.
  const TrajectoryError drift = absoluteTrajectoryError(world.graph.initial, world.truth);
  EXPECT_GT(drift.translation_rmse, 0.5);
}

TEST(ManhattanWorld, TheThesisProtocolCanStepIt) {
  const ManhattanWorld world = make(300, 9);
  const ThesisProtocol protocol(world.graph);
  EXPECT_EQ(protocol.size(), 300u);
  // Odometry composed by the protocol is the generator's initial guess.
  const Values initial = protocol.initialValues();
  const Pose2 a = initial.pose(X(299)), b = world.graph.initial.pose(X(299));
  EXPECT_NEAR(a.x, b.x, 1e-9);
  EXPECT_NEAR(a.y, b.y, 1e-9);
}

TEST(ManhattanWorld, LargeWorldsAreLinear) {
  // 100k poses: a quadratic loop-closure search would take minutes.
  ManhattanWorldOptions options;
  options.poses = 100000;
  const ManhattanWorld world = generateManhattanWorld(options);
  EXPECT_EQ(world.truth.size(), 100000u);
  EXPECT_GT(world.loop_closures, 10000u);
}

// The judging worlds (the shapes of the header): all options at once.
ManhattanWorldOptions judging(std::uint64_t seed) {
  ManhattanWorldOptions o;
  o.poses = 1200;
  o.seed = seed;
  o.loop_closures.pose_probability = 0.1;
  o.loop_closures.first_pose = 400;
  o.noise.odometry_sigma_xy = 0.1;
  o.noise.odometry_sigma_theta = 0.02;
  o.odometry_gaps = 3;
  o.components = 2;
  return o;
}

std::string asG2oWithFixes(const ManhattanWorld& world) {
  std::ostringstream os;
  writeG2o(os, world.graph.initial, world.graph.factors, world.graph.fixed);
  return os.str();
}

// Union-find over the poses joined by a factor.
std::size_t componentCount(const ManhattanWorld& world) {
  std::vector<std::size_t> parent(world.truth.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  std::function<std::size_t(std::size_t)> root = [&](std::size_t i) {
    return parent[i] == i ? i : parent[i] = root(parent[i]);
  };
  for (const auto& f : world.graph.factors)
    parent[root(f->keys()[0].index())] = root(f->keys()[1].index());
  std::size_t roots = 0;
  for (std::size_t i = 0; i < parent.size(); ++i) roots += root(i) == i;
  return roots;
}

TEST(ManhattanWorld, JudgingWorldsAreTheSameForASeed) {
  const ManhattanWorld a = generateManhattanWorld(judging(4)),
                       b = generateManhattanWorld(judging(4));
  EXPECT_EQ(asG2oWithFixes(a), asG2oWithFixes(b));
  EXPECT_NE(asG2oWithFixes(a), asG2oWithFixes(generateManhattanWorld(judging(5))));
  // The options off give the default world, draw for draw.
  ManhattanWorldOptions off;
  off.poses = 500;
  off.seed = 42;
  off.noise.odometry_sigma_xy = off.noise.sigma_xy;
  EXPECT_EQ(asG2o(generateManhattanWorld(off)), asG2o(make(500, 42)));
}

TEST(ManhattanWorld, SparseLoopClosuresAfterALongDrift) {
  const ManhattanWorldOptions o = judging(6);
  const ManhattanWorld world = generateManhattanWorld(o);
  std::map<std::uint64_t, int> closures_at;
  for (const auto& f : world.graph.factors) {
    const std::uint64_t a = f->keys()[0].index(), b = f->keys()[1].index();
    if (b <= a + 2) continue;  // odometry and the gaps' closures
    EXPECT_GE(b, o.loop_closures.first_pose);
    ++closures_at[b];
  }
  ASSERT_GT(closures_at.size(), 5u);
  for (const auto& [pose, count] : closures_at) EXPECT_EQ(count, 1) << "pose " << pose;
  // About one closing pose in ten among those in reach: far fewer than the default's.
  EXPECT_LT(closures_at.size(), (o.poses - o.loop_closures.first_pose) / 5);
}

TEST(ManhattanWorld, OdometryNoiseMatchesItsOwnSigmas) {
  // chi2 at the truth of M odometry edges: mean 3 M, sd sqrt(6 M); 5 sd either way.
  ManhattanWorldOptions o = judging(7);
  o.noise.odometry_sigma_xy = 0.3;
  o.noise.odometry_sigma_theta = 0.05;
  const ManhattanWorld world = generateManhattanWorld(o);
  std::vector<FactorPtr> odometry, closures;
  for (const auto& f : world.graph.factors) {
    const auto* b = dynamic_cast<const BetweenFactor*>(f.get());
    ASSERT_NE(b, nullptr);
    const bool is_odometry = f->keys()[1].index() == f->keys()[0].index() + 1;
    (is_odometry ? odometry : closures).push_back(f);
    const double sxy = is_odometry ? 0.3 : o.noise.sigma_xy,
                 sth = is_odometry ? 0.05 : o.noise.sigma_theta;
    EXPECT_DOUBLE_EQ(b->information()(0, 0), 1 / (sxy * sxy));
    EXPECT_DOUBLE_EQ(b->information()(2, 2), 1 / (sth * sth));
  }
  const double m = double(odometry.size()), k = double(closures.size());
  EXPECT_NEAR(chi2(odometry, world.truth), 3 * m, 5 * std::sqrt(6 * m));
  EXPECT_NEAR(chi2(closures, world.truth), 3 * k, 5 * std::sqrt(6 * k) + 5);
}

TEST(ManhattanWorld, OdometryGapsAreBridgedByALoopClosure) {
  const ManhattanWorld world = generateManhattanWorld(judging(8));
  ASSERT_EQ(world.gaps.size(), 3u);
  for (std::size_t g : world.gaps) {
    bool odometry = false, bridge = false;
    for (const auto& f : world.graph.factors) {
      const std::uint64_t a = f->keys()[0].index(), b = f->keys()[1].index();
      odometry |= a + 1 == g && b == g;
      bridge |= a + 2 == g && b == g;
    }
    EXPECT_FALSE(odometry) << "gap at " << g;
    EXPECT_TRUE(bridge) << "gap at " << g;
    // The initial values are composed across the gap through its closure.
    const Pose2 p = world.graph.initial.pose(X(g)), q = world.graph.initial.pose(X(g - 2));
    EXPECT_LT(std::hypot(p.x - q.x, p.y - q.y), 3.0);
  }
  EXPECT_EQ(world.odometry_edges + world.gaps.size() + world.component_starts.size() - 1,
            world.truth.size() - 1);
  EXPECT_EQ(world.graph.factors.size(), world.odometry_edges + world.loop_closures);
}

TEST(ManhattanWorld, SeveralComponentsEachFixedAtItsStart) {
  ManhattanWorldOptions o = judging(9);
  o.components = 3;
  o.odometry_gaps = 0;
  const ManhattanWorld world = generateManhattanWorld(o);
  ASSERT_EQ(world.component_starts, (std::vector<std::size_t>{0, 400, 800}));
  EXPECT_EQ(componentCount(world), 3u);
  EXPECT_EQ(world.graph.fixed.size(), 3u);
  for (std::size_t s : world.component_starts) {
    EXPECT_TRUE(world.graph.fixed.count(X(s)));
    EXPECT_EQ(world.graph.initial.pose(X(s)).x, world.truth.pose(X(s)).x);
    EXPECT_EQ(world.graph.initial.pose(X(s)).y, world.truth.pose(X(s)).y);
  }
  for (const auto& f : world.graph.factors) {
    const std::uint64_t a = f->keys()[0].index(), b = f->keys()[1].index();
    EXPECT_EQ(a / 400, b / 400) << a << "-" << b;
  }
  // The thesis protocol steps it (the fixed poses enter as fixed).
  const ThesisProtocol protocol(world.graph);
  EXPECT_EQ(protocol.size(), 1200u);
  // One component, a gap: still one connected graph.
  o.components = 1;
  o.odometry_gaps = 2;
  EXPECT_EQ(componentCount(generateManhattanWorld(o)), 1u);
}

TEST(ManhattanWorld, BadOptionsAreErrors) {
  auto with = [](auto change) {
    ManhattanWorldOptions o;
    o.poses = 10;
    change(o);
    return o;
  };
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.poses = 1; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.noise.sigma_xy = 0; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.noise.sigma_theta = -1; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.loop_closures.rate = 1.5; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.loop_closures.radius = -1; })), Error);
  EXPECT_NO_THROW(generateManhattanWorld(with([](auto& o) { o.loop_closures.rate = 0; })));
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.loop_closures.pose_probability = 2; })),
               Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.noise.odometry_sigma_xy = -1; })),
               Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.components = 0; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.components = 3; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.odometry_gaps = 5; })), Error);
  EXPECT_NO_THROW(generateManhattanWorld(with([](auto& o) { o.odometry_gaps = 2; })));
}

}  // namespace
}  // namespace hamal::apps
