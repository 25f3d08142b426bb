// MOSS trials (thesis sec. 5.5): deterministic per seed, the scenario's
// lengths and pose counts, collision-free paths, obstacles in the scans, and
// odometry noise with the stated sigmas.
#include "apps/moss/trials.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.h"

namespace hamal::moss {
namespace {

class CorridorTrials : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ = new World(loadWorld("CORRIDOR"));
    config_ = new TrialConfig(scenarioConfig("CORRIDOR"));
    map_ = new PriorMap(mappingRun(*world_, *config_, 1));
  }
  static void TearDownTestSuite() {
    delete map_;
    delete config_;
    delete world_;
  }
  static World* world_;
  static TrialConfig* config_;
  static PriorMap* map_;
};
World* CorridorTrials::world_ = nullptr;
TrialConfig* CorridorTrials::config_ = nullptr;
PriorMap* CorridorTrials::map_ = nullptr;

TEST_F(CorridorTrials, MappingRunFollowsTheRouteWithAScanPerNode) {
  ASSERT_EQ(map_->poses.size(), 21u);
  ASSERT_EQ(map_->scans.size(), 21u);
  EXPECT_NEAR(map_->poses.front().x, world_->start.x, 1e-12);
  EXPECT_LT((map_->poses.back().t() - world_->route.back()).norm(), 0.35);
  for (const Scan& s : map_->scans) EXPECT_GT(s.size(), 50u);
}

TEST(MappingRun, AWaypointThePlannerCannotReachIsAnError) {
  // A 0.6 m gap in a wall across the route: wider than the robot, too
  // narrow for the Dynamic Window planner, which stops 5 m before it.
  const World world = parseWorld(
      "START 1 5 0\nROUTE 9 5\nWALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n"
      "WALL 5 0 5 4.7\nWALL 5 5.3 5 10\n",
      "gap.txt");
  try {
    mappingRun(world, scenarioConfig("CORRIDOR"), 1);
    ADD_FAILURE() << "the mapping run stopped short of its route without a word";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("world gap.txt: the mapping run stopped "),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(" m short of ROUTE waypoint 1 of 1 (9, 5)"),
              std::string::npos)
        << e.what();
  }
  // Without the wall, the same route is driven to its end.
  const World open = parseWorld(
      "START 1 5 0\nROUTE 9 5\nWALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n",
      "open.txt");
  const PriorMap map = mappingRun(open, scenarioConfig("CORRIDOR"), 1);
  EXPECT_LT((map.path.back().t() - open.route.back()).norm(), 0.3);
}

TEST_F(CorridorTrials, DeterministicPerSeedAndDifferentAcrossSeedsAndStreams) {
  const Trial a = localizationTrial(*world_, *map_, *config_, 4, 0, 2);
  const Trial b = localizationTrial(*world_, *map_, *config_, 4, 0, 2);
  ASSERT_EQ(a.truth.size(), b.truth.size());
  for (std::size_t i = 0; i < a.truth.size(); ++i) {
    EXPECT_EQ(a.truth[i].x, b.truth[i].x);
    EXPECT_EQ(a.scans[i], b.scans[i]);
  }
  for (std::size_t i = 0; i < a.odometry.size(); ++i) EXPECT_EQ(a.odometry[i].y, b.odometry[i].y);
  const Trial c = localizationTrial(*world_, *map_, *config_, 5, 0, 2);
  const Trial d = localizationTrial(*world_, *map_, *config_, 4, 1, 2);
  EXPECT_NE(a.truth.back().x, c.truth.back().x);
  EXPECT_NE(a.truth.back().x, d.truth.back().x);
}

TEST_F(CorridorTrials, TrialsHaveTheScenarioLengthPosesAndNoCollision) {
  for (int s = 0; s < 6; ++s) {
    const Trial t = localizationTrial(*world_, *map_, *config_, 1, 0, s);
    EXPECT_EQ(t.truth.size(), 21u);
    EXPECT_EQ(t.odometry.size(), 20u);
    EXPECT_EQ(t.scans.size(), 21u);
    EXPECT_GE(t.length, 10.0 - 0.06);
    EXPECT_LE(t.length, 15.0 + 0.06);
    EXPECT_EQ(t.obstacles.size(), 4u * config_->obstacles);
    EXPECT_NEAR(t.truth[0].x, world_->start.x, 1e-12);
    for (const Pose2& p : t.truth) {
      EXPECT_GT(distanceToSegments(p.t(), world_->walls), kRobotRadius * 0.9);
      EXPECT_GT(distanceToSegments(p.t(), t.obstacles), kRobotRadius * 0.9);
    }
  }
}

// The odometry error (measured minus true relative pose), drawn many times
// along a trial's true path and divided by the step's stated sigma
// (sigma * sqrt(d / 10 m)): zero mean and unit sigma in x, y and theta,
// within 5% (3 standard errors of a sample sigma from 10^4 draws is 2%).
// The trial's own odometry comes from the same function.
TEST_F(CorridorTrials, OdometryNoiseHasTheStatedSigmas) {
  const Trial t = localizationTrial(*world_, *map_, *config_, 9, 0, 0);
  std::mt19937_64 rng(11);
  std::vector<double> ex, ey, eth;
  while (ex.size() < 10000) {
    const std::vector<Pose2> odometry = sampleOdometry(t.truth, *config_, rng);
    for (std::size_t i = 0; i + 1 < t.truth.size(); ++i) {
      const Pose2 d = t.truth[i].between(t.truth[i + 1]);
      const double length = d.t().norm();
      const double sxy = 0.30 * std::sqrt(length / 10.0);
      const double sth = 0.1 * M_PI / 180 * std::sqrt(length / 10.0);
      ex.push_back((odometry[i].x - d.x) / sxy);
      ey.push_back((odometry[i].y - d.y) / sxy);
      eth.push_back(wrapAngle(odometry[i].theta - d.theta) / sth);
    }
  }
  const auto sigma = [](const std::vector<double>& v) {
    double s2 = 0;
    for (double x : v) s2 += x * x;
    return std::sqrt(s2 / v.size());
  };
  const auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s / v.size();
  };
  EXPECT_NEAR(sigma(ex), 1.0, 0.05);
  EXPECT_NEAR(sigma(ey), 1.0, 0.05);
  EXPECT_NEAR(sigma(eth), 1.0, 0.05);
  EXPECT_NEAR(mean(ex), 0.0, 5 / std::sqrt(ex.size()));
  EXPECT_NEAR(mean(ey), 0.0, 5 / std::sqrt(ey.size()));
  // 30 cm per 10 m: the stated sigma over a whole trial's length.
  double total = 0;
  for (std::size_t i = 0; i + 1 < t.truth.size(); ++i)
    total += std::pow(0.30 * std::sqrt(t.truth[i].between(t.truth[i + 1]).t().norm() / 10.0), 2);
  EXPECT_NEAR(std::sqrt(total), 0.30 * std::sqrt(t.length / 10.0), 0.01);
}

TEST(Discretise, EquallySpacedAlongTheLength) {
  std::vector<Pose2> path;
  for (int i = 0; i <= 100; ++i) path.emplace_back(0.1 * i, 0.0, 0.0);
  double length = 0;
  const std::vector<Pose2> d = discretise(path, 11, &length);
  EXPECT_NEAR(length, 10.0, 1e-9);
  ASSERT_EQ(d.size(), 11u);
  for (int k = 0; k <= 10; ++k) EXPECT_NEAR(d[k].x, k, 1e-9);
}

}  // namespace
}  // namespace hamal::moss
