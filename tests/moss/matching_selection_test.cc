// MOSS scan matching, localization and node selection (thesis sec. 5.3-5.4):
// ICP recovers a known offset and is weak along a featureless hallway; the
// localizer is deterministic and its match cache changes nothing but time;
// Equidistant follows eq. 5.6; SSM's greedy additions never lower the
// likelihood; MOSS never returns a map worse than its climbs' starts, does not
// depend on the thread count, and resumes from its checkpoints.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <filesystem>
#include <fstream>

#include "apps/moss/equidistant.h"
#include "apps/moss/localizer.h"
#include "apps/moss/moss_selection.h"
#include "apps/moss/sparse_scan_matching.h"
#include "backends/builtins.h"
#include "core/error.h"

namespace hamal::moss {
namespace {

struct Fixture {
  World world = loadWorld("CORRIDOR");
  TrialConfig config = scenarioConfig("CORRIDOR");
  PriorMap map;
  std::vector<Trial> trials;
  Registry registry;
  Fixture() {
    map = mappingRun(world, config, 1);
    for (int s = 0; s < 3; ++s) trials.push_back(localizationTrial(world, map, config, 1, 0, s));
    registerBuiltins(registry);
  }
};

const Fixture& setup() {
  static const Fixture* s = new Fixture();
  return *s;
}

TEST(ScanMatcher, RecoversAKnownOffsetNearTheIntersection) {
  const World w = loadWorld("CORRIDOR");
  const Laser laser;
  const Pose2 node(9.0, 0.0, 0.0), live(9.25, 0.15, 0.08);
  std::mt19937_64 rng(2);
  const IndexedScan ref(laser.scan(node, w.walls, {}, &rng));
  const Scan scan = laser.scan(live, w.walls, {}, &rng);
  const Pose2 truth = node.between(live);
  const ScanMatch m = ScanMatcher().match(ref, scan, Pose2(truth.x - 0.2, truth.y + 0.1, 0.0));
  ASSERT_TRUE(m.ok) << m.pairs << " pairs, rms " << m.rms;
  EXPECT_NEAR(m.relative.x, truth.x, 0.03);
  EXPECT_NEAR(m.relative.y, truth.y, 0.03);
  EXPECT_NEAR(m.relative.theta, truth.theta, 0.01);
  EXPECT_LT(m.rms, 0.04);
  EXPECT_GT(m.information.eigenvalues().real().minCoeff(), 0.0);
}

TEST(IndexedScan, TheGridFindsTheTreesNearestPointWithinTheGate) {
  const World w = loadWorld("SQUARE");
  const Laser laser;
  std::mt19937_64 rng(5);
  const IndexedScan scan(laser.scan(Pose2(2.0, 3.0, 0.4), w.walls, {}, &rng), 0.5);
  std::uniform_real_distribution<double> u(-5.0, 9.0);
  int within = 0;
  for (int k = 0; k < 20000; ++k) {
    const Point2 q(u(rng), u(rng));
    for (double gate : {0.2, 0.5}) {
      double tree_d2 = 0.0, grid_d2 = -1.0;
      const int tree = scan.nearest(q, &tree_d2);
      const int grid = scan.nearestWithin(q, gate, &grid_d2);
      if (tree_d2 > gate * gate) {
        EXPECT_EQ(grid, -1) << q.transpose() << " gate " << gate;
      } else {
        ++within;
        ASSERT_EQ(grid, tree) << q.transpose() << " gate " << gate;
        EXPECT_EQ(grid_d2, tree_d2);
      }
    }
  }
  EXPECT_GT(within, 1000);
  double d2;
  EXPECT_EQ(scan.nearestWithin(Point2(1e6, 0), 0.5, &d2), -1);
  // A gate beyond the grid's reach falls back to the tree.
  const int far = scan.nearestWithin(Point2(2.0, 3.0), 10.0, &d2);
  double tree_d2;
  EXPECT_EQ(far, scan.nearest(Point2(2.0, 3.0), &tree_d2));
}

// The point-to-line pair is the nearest point within the gate, with its
// normal, and the signed distance to its line; none beyond the gate.
TEST(IndexedScan, PointToLineIsTheNearestPointsNormalAndSignedDistance) {
  // A wall at y = 1 seen from the origin: normals along y.
  Scan wall;
  for (int i = -20; i <= 20; ++i) wall.push_back(Point2(0.05 * i, 1.0));
  const IndexedScan scan(wall, 0.5);
  Point2 n;
  double r = 0;
  ASSERT_TRUE(scan.pointToLine(Point2(0.12, 1.3), 0.5, &n, &r));
  EXPECT_NEAR(std::abs(n.y()), 1.0, 1e-9);
  EXPECT_NEAR(r, 0.3 * n.y(), 1e-9);
  double d2;
  const int j = scan.nearestWithin(Point2(0.12, 1.3), 0.5, &d2);
  ASSERT_GE(j, 0);
  EXPECT_EQ(n, scan.normals()[j]);
  EXPECT_FALSE(scan.pointToLine(Point2(0.12, 2.0), 0.5, &n, &r));
}

TEST(ScanMatcher, IsWeakAlongAFeaturelessHallway) {
  // 30 m of parallel walls: nothing fixes x.
  const std::vector<Segment> walls = {{Point2(-15, -1), Point2(15, -1)},
                                      {Point2(-15, 1), Point2(15, 1)}};
  const Laser laser;
  std::mt19937_64 rng(3);
  const IndexedScan ref(laser.scan(Pose2(0, 0, 0), walls, {}, &rng));
  const ScanMatch m =
      ScanMatcher().match(ref, laser.scan(Pose2(0, 0.1, 0), walls, {}, &rng), Pose2(0.3, 0.0, 0.0));
  ASSERT_TRUE(m.ok);
  EXPECT_NEAR(m.relative.y, 0.1, 0.02);
  // x is unobservable: wherever ICP leaves it, the information says so.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m.information);
  EXPECT_GT(std::abs(es.eigenvectors()(0, 0)), 0.99);  // weakest direction: x
  EXPECT_LT(es.eigenvalues()(0), 1e-2 * es.eigenvalues()(2)) << es.eigenvalues().transpose();
}

TEST(Localizer, DeterministicAndTheCacheChangesNothing) {
  const Fixture& s = setup();
  Localizer a(s.map, s.trials, LocalizerConfig(), s.registry);
  const Selection full(s.map.poses.size(), 1);
  const Localization first = a.localize(1, full);
  EXPECT_GT(first.l2g_factors, 5);
  EXPECT_EQ(first.failures, 0);
  const std::uint64_t misses = a.cache().misses();
  const Localization again = a.localize(1, full);
  EXPECT_EQ(a.cache().misses(), misses);  // all from the cache
  ASSERT_EQ(first.estimate.size(), again.estimate.size());
  for (std::size_t i = 0; i < first.estimate.size(); ++i)
    EXPECT_EQ(first.estimate[i].x, again.estimate[i].x);
  Localizer b(s.map, s.trials, LocalizerConfig(), s.registry);
  EXPECT_EQ(b.localize(1, full).sum_squared_error, first.sum_squared_error);
}

TEST(Localizer, NoNodesIsDeadReckoning) {
  const Fixture& s = setup();
  Localizer loc(s.map, s.trials, LocalizerConfig(), s.registry);
  const Localization l = loc.localize(0, Selection(s.map.poses.size(), 0));
  EXPECT_EQ(l.l2g_factors, 0);
  Pose2 p = s.trials[0].truth[0];
  for (std::size_t i = 1; i < l.estimate.size(); ++i) {
    p = p.compose(s.trials[0].odometry[i - 1]);
    EXPECT_NEAR(l.estimate[i].x, p.x, 1e-6);
    EXPECT_NEAR(l.estimate[i].y, p.y, 1e-6);
  }
}

TEST(Localizer, AnUnknownBackendIsAnError) {
  const Fixture& s = setup();
  LocalizerConfig c;
  c.backend = "no-such-backend";
  EXPECT_THROW(Localizer(s.map, s.trials, c, s.registry), Error);
}

TEST(Equidistant, FollowsEquation56) {
  EXPECT_EQ(selectedNodes(equidistant(21, 1)), std::vector<int>({9}));  // i = 10 of 21
  EXPECT_EQ(selectedNodes(equidistant(21, 2)), std::vector<int>({6, 13}));
  EXPECT_EQ(selectedNodes(equidistant(21, 20)).size(), 20u);
  EXPECT_EQ(selectedNodes(equidistant(21, 21)).size(), 21u);
  EXPECT_EQ(selectedNodes(equidistant(204, 11)).size(), 11u);
  EXPECT_THROW(equidistant(21, 0), Error);
  EXPECT_THROW(equidistant(21, 22), Error);
}

TEST(SparseScanMatching, GreedyAdditionsNeverLowerTheLikelihood) {
  const Fixture& s = setup();
  const SparseScanMatching ssm(s.map);
  std::vector<int> order;
  const Selection a = ssm.select(8, &order);
  ASSERT_EQ(order.size(), 8u);
  EXPECT_EQ(selectedNodes(a).size(), 8u);
  Selection partial(s.map.poses.size(), 0);
  double previous = -1e300;
  for (int k : order) {
    partial[k] = 1;
    const double l = ssm.logLikelihood(partial);
    EXPECT_GE(l, previous);
    previous = l;
  }
  // The first pick is the best single node.
  for (std::size_t j = 0; j < s.map.poses.size(); ++j) {
    Selection one(s.map.poses.size(), 0);
    one[j] = 1;
    Selection best(s.map.poses.size(), 0);
    best[order[0]] = 1;
    EXPECT_LE(ssm.logLikelihood(one), ssm.logLikelihood(best));
  }
  EXPECT_THROW(ssm.select(22), Error);
}

TEST(Moss, ImprovesOnItsStartsIsThreadIndependentAndResumes) {
  const Fixture& s = setup();
  Localizer loc(s.map, s.trials, LocalizerConfig(), s.registry);
  MossConfig c;
  c.climbs = 3;
  c.steps = 8;
  c.seed = 4;
  c.threads = 1;
  const MossResult one = mossSelect(loc, 3, c);
  EXPECT_EQ(selectedNodes(one.best).size(), 3u);
  EXPECT_EQ(one.evaluations, 3u * 9u);
  EXPECT_NEAR(loc.rmse(one.best), one.best_error, 1e-12);
  for (double e : one.climb_errors) EXPECT_GE(e, one.best_error);
  c.threads = 2;
  const MossResult two = mossSelect(loc, 3, c);
  EXPECT_EQ(two.best, one.best);
  EXPECT_EQ(two.best_error, one.best_error);

  const std::string dir = ::testing::TempDir() + "/moss_resume_" + std::to_string(getpid());
  std::filesystem::remove_all(dir);
  c.checkpoint_dir = dir;
  c.checkpoint_every = 2;
  const MossResult first = mossSelect(loc, 3, c);
  EXPECT_EQ(first.best, one.best);
  const MossResult resumed = mossSelect(loc, 3, c);  // every climb already finished
  EXPECT_EQ(resumed.evaluations, 0u);
  EXPECT_EQ(resumed.best, one.best);
  std::filesystem::remove_all(dir);

  c.checkpoint_dir.clear();
  c.climbs = 0;
  EXPECT_THROW(mossSelect(loc, 3, c), Error);
  c.climbs = 1;
  c.steps = 0;
  EXPECT_THROW(mossSelect(loc, 3, c), Error);
  c.steps = 1;
  EXPECT_THROW(mossSelect(loc, 22, c), Error);
}

// The climbs run on a thread pool: an error inside one (here a damaged
// checkpoint) is the caller's Error.
TEST(Moss, AnErrorInAClimbReachesTheCaller) {
  const Fixture& s = setup();
  Localizer loc(s.map, s.trials, LocalizerConfig(), s.registry);
  MossConfig c;
  c.climbs = 3;
  c.steps = 4;
  c.seed = 4;
  c.threads = 2;
  c.checkpoint_dir = ::testing::TempDir() + "/moss_damaged_" + std::to_string(getpid());
  std::filesystem::create_directories(c.checkpoint_dir);
  std::ofstream(c.checkpoint_dir + "/moss_C3_t1_s4.climb") << "not a checkpoint\n";
  EXPECT_THROW(mossSelect(loc, 3, c), Error);
  std::filesystem::remove_all(c.checkpoint_dir);
}

// A checkpoint is of one climb of one C: one of another C (copied or
// renamed) is refused, not resumed as a climb of the wrong size.
TEST(Moss, ACheckpointOfAnotherCIsRefused) {
  const Fixture& s = setup();
  Localizer loc(s.map, s.trials, LocalizerConfig(), s.registry);
  MossConfig c;
  c.climbs = 1;
  c.steps = 2;
  c.seed = 4;
  c.threads = 1;
  c.checkpoint_dir = ::testing::TempDir() + "/moss_other_c_" + std::to_string(getpid());
  std::filesystem::remove_all(c.checkpoint_dir);
  mossSelect(loc, 3, c);
  const std::string three = c.checkpoint_dir + "/moss_C3_t0_s4.climb";
  const std::string four = c.checkpoint_dir + "/moss_C4_t0_s4.climb";
  ASSERT_TRUE(std::filesystem::exists(three));
  std::filesystem::copy_file(three, four);
  try {
    mossSelect(loc, 4, c);
    ADD_FAILURE() << "a checkpoint of C = 3 resumed a climb of C = 4";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), four +
                                         ": a checkpoint of a climb with C = 3 nodes, not C = 4 "
                                         "(delete it to restart this climb)");
  }
  std::filesystem::remove(four);
  EXPECT_EQ(selectedNodes(mossSelect(loc, 4, c).best).size(), 4u);
  std::filesystem::remove_all(c.checkpoint_dir);
}

}  // namespace
}  // namespace hamal::moss
