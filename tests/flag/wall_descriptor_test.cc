// The corner's walls as an association descriptor (FlagOptions::
// association.wall_sigma): the detector gives each corner the directions its
// walls leave it in, the map's corners carry theirs (an L two, a T's running
// wall both ways), a detection's walls turned by the heading match a
// landmark's within a tolerance (across the angle's wrap). That with them
// FLAG takes the right one of two landmarks within its gate:
// pose_gate_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "apps/flag/flag_localizer.h"
#include "apps/flag/map_corners.h"
#include "apps/flag/range_scan.h"
#include "apps/flag/vertical_edge_detector.h"

namespace hamal::flag {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

// The smallest angle between two directions.
double apart(double a, double b) { return std::abs(wrapAngle(a - b)); }

TEST(WallDescriptor, DetectorGivesTheDirectionsTheWallsLeaveTheCorner) {
  std::istringstream in(
      "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 0 6\nWALL 0 6 0 0\n"
      "CORNER 0 8 0\nPATH 1 1\nPATH 1.5 1\n");
  const FloorPlan room = readFloorPlan(in, "room", 0.0, 1);
  RangeScannerOptions s;
  s.max_range = 20;
  const Pose2 pose(2, 3, 0.3);
  VerticalEdgeDetectorOptions d;
  d.silhouettes.enabled = false;
  int checked = 0;
  for (const VerticalEdge& e : detectVerticalEdges(castRangeScan(room, pose, 0, s, nullptr), d)) {
    ASSERT_EQ(e.walls.size(), 2u);
    const Point2 w = pose.transformFrom(e.position);
    // The room's corner at (8, 0): its walls run west and north.
    if ((w - Point2(8, 0)).norm() > 0.05) continue;
    const double a = e.walls[0] + pose.theta, b = e.walls[1] + pose.theta;
    EXPECT_LT(std::min(apart(a, kPi) + apart(b, kPi / 2), apart(a, kPi / 2) + apart(b, kPi)),
              1 * kDeg);
    ++checked;
  }
  EXPECT_EQ(checked, 1);
}

TEST(WallDescriptor, MapCornersCarryTheirWallsDirections) {
  MapCornerOptions o;
  o.min_segments = 1;
  // An L at (4, 0) (walls west and north) and a T at (0, 3): the stem runs
  // east, the wall it meets south and north.
  const std::vector<MapWall> walls = {
      {{0, 0}, {4, 0}, 1}, {{4, 0}, {4, 2}, 1}, {{0, -2}, {0, 8}, 1}, {{0, 3}, {-3, 3}, 1}};
  const std::vector<MapCorner> corners = wallCornerShapes(walls, o);
  const auto at = [&](const Point2& p) -> const MapCorner* {
    for (const MapCorner& c : corners)
      if ((c.position - p).norm() < 1e-6) return &c;
    return nullptr;
  };
  const MapCorner* l = at({4, 0});
  ASSERT_NE(l, nullptr);
  ASSERT_EQ(l->walls.size(), 2u);
  EXPECT_TRUE(wallsMatch({kPi, kPi / 2}, 0, l->walls, 1e-6));
  const MapCorner* t = at({0, 3});
  ASSERT_NE(t, nullptr);
  ASSERT_EQ(t->walls.size(), 3u);
  // Either of the T's concave corners matches it, a mirrored L does not.
  EXPECT_TRUE(wallsMatch({kPi, kPi / 2}, 0, t->walls, 1e-6));
  EXPECT_TRUE(wallsMatch({-kPi / 2, kPi}, 0, t->walls, 1e-6));
  EXPECT_FALSE(wallsMatch({0, kPi / 2}, 0, t->walls, 1e-6));
}

TEST(WallDescriptor, MatchTurnsByTheHeadingWithinTheTolerance) {
  const std::vector<double> landmark = {kPi, kPi / 2};  // west and north
  // Heading north, the robot has west to its left and north ahead.
  EXPECT_TRUE(wallsMatch({kPi / 2, 0}, kPi / 2, landmark, 5 * kDeg));
  EXPECT_TRUE(wallsMatch({kPi / 2 + 4 * kDeg, -4 * kDeg}, kPi / 2, landmark, 5 * kDeg));
  EXPECT_FALSE(wallsMatch({kPi / 2 + 6 * kDeg, 0}, kPi / 2, landmark, 5 * kDeg));
  // Across the wrap: -179 degrees is 1 from 180.
  EXPECT_TRUE(wallsMatch({-179 * kDeg}, 0, landmark, 2 * kDeg));
  // Without walls on either side anything matches.
  EXPECT_TRUE(wallsMatch({}, 0, landmark, 0));
  EXPECT_TRUE(wallsMatch({0.3}, 0, {}, 0));
}

}  // namespace
}  // namespace hamal::flag
