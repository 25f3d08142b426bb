// The synthetic Manhattan world (apps/generator/manhattan_world.h): same seed
// same graph, another seed another graph; the counts, the grid, the noise
// level and the loop closures are what the header promises.
#include "apps/generator/manhattan_world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "apps/protocol/thesis_protocol.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/metrics.h"
#include "factors/between_factor.h"

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
  options.sigma_xy = 0.2;
  options.sigma_theta = 0.03;
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

TEST(ManhattanWorld, BadOptionsAreErrors) {
  auto with = [](auto change) {
    ManhattanWorldOptions o;
    o.poses = 10;
    change(o);
    return o;
  };
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.poses = 1; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.sigma_xy = 0; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.sigma_theta = -1; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.loop_closure_rate = 1.5; })), Error);
  EXPECT_THROW(generateManhattanWorld(with([](auto& o) { o.loop_closure_radius = -1; })), Error);
  EXPECT_NO_THROW(generateManhattanWorld(with([](auto& o) { o.loop_closure_rate = 0; })));
}

}  // namespace
}  // namespace hamal::apps
