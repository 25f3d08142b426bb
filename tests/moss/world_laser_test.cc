// MOSS worlds and laser (thesis sec. 5.5, fig. 5.5): the built-in worlds,
// bad world files (file, line, reason), ray casting against known geometry,
// range noise matching sigma_d, and the speed of scanning a whole trial.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>

#include "apps/moss/laser.h"
#include "apps/moss/world.h"
#include "core/error.h"

namespace hamal::moss {
namespace {

std::string errorOf(const std::string& text) {
  try {
    parseWorld(text, "w.txt");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(World, BuiltinsHaveTheThesisDimensions) {
  const World c = loadWorld("CORRIDOR");
  EXPECT_NEAR((c.max() - c.min()).x(), 12.0, 1e-12);
  EXPECT_NEAR((c.max() - c.min()).y(), 6.0, 1e-12);
  const World s = loadWorld("SQUARE");
  EXPECT_NEAR((s.max() - s.min()).x(), 12.0, 1e-12);
  EXPECT_NEAR((s.max() - s.min()).y(), 12.0, 1e-12);
  EXPECT_GT(s.walls.size(), 4u);  // interior L walls
}

TEST(World, BadFilesNameFileLineAndReason) {
  const std::string ok = "WORLD T\nSTART 1 1 0\nROUTE 3 1\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {ok + "WALL 0 0 5 0\nWALL 0 0 0 x\n", "w.txt:5: "},
      {ok + "WALL 0 0 5 0\nWALL 2 2 2 2\n", "w.txt:5: zero-length wall"},
      {ok + "WALL 0 0 5 0\nWALL 0 0 5\n", "w.txt:5: "},
      {ok + "WALL 0 0 5 0 7\n", "w.txt:4: "},
      {ok + "DOOR 0 0 5 0\n", "w.txt:4: unknown record 'DOOR'"},
      {"WORLD T\nSTART 1 1 0\nROUTE 3 0.1\nWALL 0 0 5 0\n",
       "w.txt:3: ROUTE waypoint (3, 0.1) is inside a wall"},
      {"WORLD T\nSTART 1 0 0\nROUTE 3 1\nWALL 0 0 5 0\n", "w.txt:2: START"},
      {"WORLD T\nSTART 1 1 0\nWALL 0 0 5 0\n", "no ROUTE line"},
      {"WORLD T\nROUTE 3 1\nWALL 0 0 5 0\n", "no START line"},
      {ok, "no WALL line"},
      // The mapping run drives START, then each waypoint in turn, in straight legs.
      {"WORLD T\nROUTE 3 1\nROUTE 3 -1\nSTART 1 1 0\nWALL 0 0 5 0\n",
       "w.txt:3: the route from (3, 1) to ROUTE waypoint (3, -1) goes through the wall (0, 0)-(5, "
       "0)"},
      {"WORLD T\nSTART 1 -1 0\nROUTE 3 1\nWALL 0 0 5 0\n",
       "w.txt:3: the route from (1, -1) to ROUTE waypoint (3, 1) goes through the wall"},
  };
  for (const auto& [text, reason] : cases) {
    SCOPED_TRACE(text);
    const std::string e = errorOf(text);
    EXPECT_NE(e.find(reason), std::string::npos) << e;
    EXPECT_EQ(e.rfind("w.txt:", 0), 0u) << e;
  }
  const std::string box = "WALL 0 0 5 0  # the floor\nWALL 5 0 5 3\nWALL 5 3 0 3\nWALL 0 3 0 0\n";
  EXPECT_EQ(errorOf(ok + "# a comment\n\n" + box), "");
}

TEST(World, ARoutePointOutsideTheWorldOrALegTooNarrowIsRefused) {
  // The mapping run would stop short of its route without a word.
  const std::string box = "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      // Outside the closed box: the leg crosses a wall.
      {"START 1 1 0\nROUTE 20 1\n" + box,
       "w.txt:3: the route from (1, 1) to ROUTE waypoint (20, 1) goes through the wall (10, "
       "0)-(10, 10)"},
      // The whole route outside: no leg crosses a wall.
      {"START -5 -5 0\nROUTE -5 5\n" + box,
       "w.txt:2: START (-5, -5) is outside the world (its walls span (0, 0)-(10, 10))"},
      {"START 1 1 0\nROUTE 9 9\nROUTE 9 12\nROUTE 12 12\n" + box, "w.txt:4: "},
      {"START 1 1 0\nROUTE 3 1\nWALL 0 0 5 0\n",
       "w.txt:2: START (1, 1) is outside the world (its walls span (0, 0)-(5, 0))"},
      // Beside a wall's end, closer than the robot's radius: a gap it cannot pass.
      {"START 1 5 0\nROUTE 9 5\n" + box + "WALL 5 0 5 4.85\nWALL 5 5.15 5 10\n",
       "w.txt:3: the route from (1, 5) to ROUTE waypoint (9, 5) passes 0.15 m from the end of the "
       "wall (5, 0)-(5, 4.85), closer than the robot's radius (0.2 m)"},
  };
  for (const auto& [text, reason] : cases) {
    SCOPED_TRACE(text);
    const std::string e = errorOf("WORLD T\n" + text);
    EXPECT_NE(e.find(reason), std::string::npos) << e;
  }
  EXPECT_EQ(errorOf("WORLD T\nSTART 1 5 0\nROUTE 9 5\n" + box + "WALL 5 0 5 4.7\n"), "");
}

// One format for both experiments: FLAG's records in a world file are read
// and left to FLAG; the world is the same as without them.
TEST(World, AFileWithFlagsRecordsLoads) {
  const std::string moss = builtinWorldText("CORRIDOR");
  const World plain = parseWorld(moss, "c.world");
  const World both =
      parseWorld(moss + "CORNER 0 10 1\nOBJECT 5 0.9 1 0\nPERSON 1 0 9 0 0 1\nPATH 1 0\nPATH 9 0\n",
                 "c.world");
  EXPECT_EQ(both.name, "corridor");
  ASSERT_EQ(both.walls.size(), plain.walls.size());
  for (std::size_t i = 0; i < plain.walls.size(); ++i) {
    EXPECT_EQ(both.walls[i].a, plain.walls[i].a);
    EXPECT_EQ(both.walls[i].b, plain.walls[i].b);
  }
  EXPECT_EQ(both.route, plain.route);
  EXPECT_EQ(both.start.t(), plain.start.t());
}

TEST(World, AMissingFileIsAnError) { EXPECT_THROW(loadWorld("/nonexistent/world.txt"), Error); }

TEST(Laser, RangesAreExactAgainstKnownWalls) {
  // A 4 x 4 box around the origin: beam 0 (along x) hits x = 2 at 2 m.
  const std::vector<Segment> box = boxSegments(Point2(0, 0), 4.0);
  const Laser laser;
  const std::vector<double> r = laser.ranges(Pose2(0, 0, 0), box, {});
  ASSERT_EQ(r.size(), 180u);
  EXPECT_NEAR(r[0], 2.0, 1e-12);
  EXPECT_NEAR(r[45], 2.0, 1e-12);                             // 90 degrees
  EXPECT_NEAR(r[22], 2.0 / std::cos(44 * M_PI / 180), 1e-9);  // 44 degrees
  // Turned by 90 degrees, beam 0 looks along y.
  const std::vector<double> turned = laser.ranges(Pose2(0, 1, M_PI / 2), box, {});
  EXPECT_NEAR(turned[0], 1.0, 1e-12);
  // An obstacle in front shortens the beam; nothing within 4 m: max range.
  const std::vector<Segment> post = boxSegments(Point2(1, 0), 0.2);
  EXPECT_NEAR(laser.ranges(Pose2(0, 0, 0), box, post)[0], 0.9, 1e-12);
  const std::vector<Segment> far = boxSegments(Point2(0, 0), 20.0);
  const Scan none = laser.scan(Pose2(0, 0, 0), far, {}, nullptr);
  EXPECT_TRUE(none.empty());
}

TEST(Laser, RangeNoiseHasSigmaD) {
  const std::vector<Segment> box = boxSegments(Point2(0, 0), 4.0);
  const Laser laser;
  const std::vector<double> exact = laser.ranges(Pose2(0.3, -0.2, 0.1), box, {});
  std::mt19937_64 rng(5);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int k = 0; k < 200; ++k) {
    const Scan s = laser.scan(Pose2(0.3, -0.2, 0.1), box, {}, &rng);
    ASSERT_EQ(s.size(), exact.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
      const double e = s[i].norm() - exact[i];
      sum += e;
      sum2 += e * e;
      ++n;
    }
  }
  const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
  // 36000 samples: the sample sigma is within 1% of 2 cm with overwhelming
  // probability; 3% leaves room.
  EXPECT_NEAR(sigma, 0.02, 0.02 * 0.03);
  EXPECT_NEAR(mean, 0.0, 5 * 0.02 / std::sqrt(n));
}

TEST(Laser, ATrialOf204PosesScansInMilliseconds) {
  const World w = loadWorld("SQUARE");
  const Laser laser;
  std::mt19937_64 rng(1);
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t points = 0;
  for (int i = 0; i < 204; ++i)
    points += laser
                  .scan(Pose2(1.5 + 0.04 * i, 1.5, 0.01 * i), w.walls,
                        boxSegments(Point2(5, 2), 0.3), &rng)
                  .size();
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GT(points, 204u * 50);
  // A generous bound for a loaded machine and sanitizer builds.
  EXPECT_LT(ms, 2000.0);
  RecordProperty("scan_ms_204_poses", std::to_string(ms));
}

}  // namespace
}  // namespace hamal::moss
