// The detector's judge on real logs (apps/flag/detector_evaluation.h) on
// hand-made scans whose answer is known: the labels are the map corners in
// range, field of view and line of sight with both walls seen (one when
// asked), the walls at an angle and showing in the scan's returns (sought
// as far as the beams reach a grazing wall), a junction's wall running on
// counted, a return counting for the wall whose line it lies nearest; a
// detection within the radius of a label is a hit, each label matched once,
// closest first, labels closer than the radius one corner; an exact scan of
// a room judged perfect.
#include "apps/flag/detector_evaluation.h"

#include <gtest/gtest.h>

#include <sstream>

#include "apps/flag/range_scan.h"
#include "core/error.h"

namespace hamal::flag {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A 180-degree, 1-degree scan like the CARMEN logs' (only its geometry is read).
RangeScan halfCircle(double max_range) {
  RangeScan s;
  s.start_angle = -kPi / 2;
  s.angular_step = kPi / 180;
  s.max_range = max_range;
  s.ranges.assign(181, 50.0);  // every beam returns from beyond the room
  return s;
}

// A ray-cast scanner with the CARMEN logs' geometry, reaching 20 m.
RangeScannerOptions carmenScanner() {
  RangeScannerOptions s;
  s.field_of_view = kPi;
  s.angular_step = kPi / 180;
  s.max_range = 20;
  return s;
}

// `scan` with the beam nearest `p`'s bearing from `sensor` ending at
// `range` (on something in front of p), its neighbours as they were.
RangeScan endBeamAt(RangeScan scan, const Pose2& sensor, const Point2& p, double range) {
  const Point2 l = sensor.transformTo(p);
  const double beam = (std::atan2(l.y(), l.x()) - scan.start_angle) / scan.angular_step;
  scan.ranges.at(std::size_t(std::lround(beam))) = range;
  return scan;
}

// An 8 x 6 m room and a free-standing wall from (5, 1) to (5, 2.5).
const std::vector<Point2> kCorners = {{0, 0}, {8, 0}, {8, 6}, {0, 6}};
std::vector<MapWall> walls() {
  return {{{0, 0}, {8, 0}, 6},
          {{8, 0}, {8, 6}, 6},
          {{8, 6}, {0, 6}, 6},
          {{0, 6}, {0, 0}, 6},
          {{5, 1}, {5, 2.5}, 6}};
}

// The geometry alone: these scans' beams return from beyond the room.
DetectorEvaluationOptions geometry() {
  DetectorEvaluationOptions o;
  o.max_range = 20;
  o.wall_returns = 0;
  return o;
}

TEST(DetectorEvaluation, LabelsAreTheCornersInRangeFieldOfViewAndSight) {
  const Pose2 sensor(2, 3, 0);  // facing +x: (0, 0) and (0, 6) are behind it
  DetectorEvaluationOptions o = geometry();
  // (8, 0) is behind the free-standing wall (the ray crosses x = 5 at y =
  // 1.5, 3.35 m away): its beam ends there, and though a neighbour passes
  // by (half a beam off), the map's wall is in front.
  EXPECT_EQ(visibleMapCorners(kCorners, walls(), sensor,
                              endBeamAt(halfCircle(80), sensor, {8, 0}, 3.35), o),
            std::vector<std::size_t>({2}));
  // A beam at its bearing returning from beyond it passed where the map
  // has a wall: the scan, not the map, says what is in sight.
  EXPECT_EQ(visibleMapCorners(kCorners, walls(), sensor, halfCircle(80), o),
            std::vector<std::size_t>({1, 2}));
  // Without that wall both far corners show; their own walls do not hide them.
  std::vector<MapWall> room = walls();
  room.pop_back();
  EXPECT_EQ(visibleMapCorners(kCorners, room, sensor, halfCircle(80), o),
            std::vector<std::size_t>({1, 2}));
  // Turned to face -x the near corners are in view instead.
  EXPECT_EQ(visibleMapCorners(kCorners, room, Pose2(2, 3, kPi), halfCircle(80), o),
            std::vector<std::size_t>({0, 3}));
  // Range: the smaller of the option's and the scanner's (|(8, 6) - (2, 3)| = 6.7 m).
  // Something nearer than the map's walls at (8, 6)'s bearing (26.6 degrees,
  // beam 117) hides it, unless a neighbouring beam reaches it.
  RangeScan cluttered = halfCircle(80);
  for (std::size_t b : {116, 117, 118}) cluttered.ranges[b] = 3.0;
  EXPECT_EQ(visibleMapCorners(kCorners, room, sensor, cluttered, o), std::vector<std::size_t>({1}));
  cluttered.ranges[118] = 6.6;  // within the 0.2 m margin of the corner's 6.7 m
  EXPECT_EQ(visibleMapCorners(kCorners, room, sensor, cluttered, o),
            std::vector<std::size_t>({1, 2}));
  cluttered.ranges[118] = 80;  // no return reaches nothing
  EXPECT_EQ(visibleMapCorners(kCorners, room, sensor, cluttered, o), std::vector<std::size_t>({1}));
  o.max_range = 6;
  EXPECT_TRUE(visibleMapCorners(kCorners, room, sensor, halfCircle(80), o).empty());
  o.max_range = 20;
  EXPECT_TRUE(visibleMapCorners(kCorners, room, sensor, halfCircle(6.5), o).empty());
}

TEST(DetectorEvaluation, ACornerSeenWithOneWallIsNoLabelUnlessAsked) {
  // A free-standing L in the room: walls (5, 1)-(5, 2.5) and (5, 1)-(6, 1).
  // From (2, 3) its corner (5, 1) is in sight, but the wall to (6, 1) lies
  // behind the other: a wall's end there, no corner of two lines.
  std::vector<MapWall> map = walls();
  map.push_back({{5, 1}, {6, 1}, 6});
  const std::vector<Point2> corners = {{5, 1}};
  DetectorEvaluationOptions o = geometry();
  // The beam to the second wall 0.3 m along ends on the first (3.5 m away).
  const RangeScan scan = endBeamAt(halfCircle(80), Pose2(2, 3, 0), {5.3, 1}, 3.5);
  EXPECT_TRUE(visibleMapCorners(corners, map, Pose2(2, 3, 0), scan, o).empty());
  o.walls_seen = 1;
  EXPECT_EQ(visibleMapCorners(corners, map, Pose2(2, 3, 0), scan, o),
            std::vector<std::size_t>({0}));
  // From (3, 0) below it both walls show.
  o.walls_seen = 2;
  EXPECT_EQ(visibleMapCorners(corners, map, Pose2(3, 0.5, 0), halfCircle(80), o),
            std::vector<std::size_t>({0}));
}

TEST(DetectorEvaluation, OneWallInTwoPiecesMakesNoLabel) {
  // The south wall in two pieces meeting at (4, 0): both show from (2, 3),
  // but one wall's line is no corner (nor are a thin wall's two faces).
  std::vector<MapWall> map = {{{0, 0}, {4, 0}, 6}, {{4, 0}, {8, 0}, 6}, {{8, 0}, {8, 6}, 6}};
  const std::vector<Point2> corners = {{4, 0}};
  DetectorEvaluationOptions o = geometry();
  EXPECT_TRUE(visibleMapCorners(corners, map, Pose2(2, 3, 0), halfCircle(80), o).empty());
  o.walls_seen = 1;
  EXPECT_EQ(visibleMapCorners(corners, map, Pose2(2, 3, 0), halfCircle(80), o),
            std::vector<std::size_t>({0}));
}

TEST(DetectorEvaluation, AJunctionsWallRunningOnIsOneOfItsWalls) {
  // A wall from (4, 0) to (4, 1.5) meets the south wall, which runs on: from
  // (2, 3) the concave corner on its west side shows both walls.
  std::vector<MapWall> map = walls();
  map.pop_back();
  map.push_back({{4, 0}, {4, 1.5}, 6});
  const std::vector<Point2> corners = {{4, 0}};
  EXPECT_EQ(visibleMapCorners(corners, map, Pose2(2, 3, 0), halfCircle(80), geometry()),
            std::vector<std::size_t>({0}));
}

TEST(DetectorEvaluation, AWallsExtentPastItsCornerHidesNothing) {
  // A free-standing L: walls (5, 1)-(5, 2.5) and (5, 1)-(6.5, 1), a convex
  // corner at (5, 1). The map's first wall runs on 0.15 m past the corner
  // (its segments' ends scatter there; map_corners.h puts a corner within
  // 0.15 m of both walls' ends), which no scan saw.
  std::istringstream in(
      "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 0 6\nWALL 0 6 0 0\nWALL 5 1 5 2.5\nWALL 5 1 6.5 1\n"
      "CORNER 0 5 1\nPATH 2 3\nPATH 3 3\n");
  const FloorPlan plan = readFloorPlan(in, "l", 0.0, 1);
  RangeScannerOptions scanner = carmenScanner();
  std::vector<MapWall> map = walls();
  map.pop_back();
  map.push_back({{5, 0.85}, {5, 2.5}, 6});
  map.push_back({{5, 1}, {6.5, 1}, 6});
  const std::vector<Point2> corners = {{5, 1}};
  DetectorEvaluationOptions o;
  o.max_range = 20;
  // From (4.2, 0.7) both faces show (the scan has their returns); the ray
  // to the second wall 0.3 m along crosses the map's first wall past the
  // corner, where there is none.
  const Pose2 both(4.2, 0.7, 0.3);
  EXPECT_EQ(
      visibleMapCorners(corners, map, both, castRangeScan(plan, both, 0, scanner, nullptr), o),
      std::vector<std::size_t>({0}));
  // From (4, 3) the first wall's body hides the second: one wall seen.
  const Pose2 one(4, 3, -0.5);
  EXPECT_TRUE(visibleMapCorners(corners, map, one, castRangeScan(plan, one, 0, scanner, nullptr), o)
                  .empty());
  o.walls_seen = 1;
  EXPECT_EQ(visibleMapCorners(corners, map, one, castRangeScan(plan, one, 0, scanner, nullptr), o),
            std::vector<std::size_t>({0}));
}

TEST(DetectorEvaluation, AMapWallTheBeamsPassThroughHidesNothing) {
  // The free-standing L of (5, 1): the map's first wall runs on 0.25 m past
  // the corner, farther than a wall's end near it, so it reads as a
  // junction's wall running on. From (4.2, 0.7) the scan's beams pass where
  // it would be and reach the second wall: both walls show. A junction
  // whose wall does run on hides its stem from the far side: the beams end
  // on that wall.
  std::istringstream in(
      "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 0 6\nWALL 0 6 0 0\nWALL 5 1 5 2.5\nWALL 5 1 6.5 1\n"
      "WALL 7 3 7 5\nWALL 6 4 7 4\nCORNER 0 5 1\nCORNER 1 7 4\nPATH 2 3\nPATH 3 3\n");
  const FloorPlan plan = readFloorPlan(in, "lt", 0.0, 1);
  RangeScannerOptions scanner = carmenScanner();
  std::vector<MapWall> map = walls();
  map.pop_back();
  map.push_back({{5, 0.75}, {5, 2.5}, 6});
  map.push_back({{5, 1}, {6.5, 1}, 6});
  DetectorEvaluationOptions o;
  o.max_range = 20;
  const Pose2 both(4.2, 0.7, 0.3);
  EXPECT_EQ(
      visibleMapCorners({{5, 1}}, map, both, castRangeScan(plan, both, 0, scanner, nullptr), o),
      std::vector<std::size_t>({0}));
  // The T: the wall (7, 3)-(7, 5) runs on past the stem (6, 4)-(7, 4).
  map.push_back({{7, 3}, {7, 5}, 6});
  map.push_back({{6, 4}, {7, 4}, 6});
  const Pose2 near_side(5, 3, 0.5), far_side(7.6, 2.6, 2.2);
  EXPECT_EQ(visibleMapCorners({{7, 4}}, map, near_side,
                              castRangeScan(plan, near_side, 0, scanner, nullptr), o),
            std::vector<std::size_t>({0}));
  EXPECT_TRUE(visibleMapCorners({{7, 4}}, map, far_side,
                                castRangeScan(plan, far_side, 0, scanner, nullptr), o)
                  .empty());
}

TEST(DetectorEvaluation, ALabelsWallsShowInTheScansReturns) {
  // The room's far corners, in sight from (2, 3): labels when the scan's
  // returns lie on their walls, none when every beam passes beyond them
  // (the scan saw something else, or nothing, there).
  std::istringstream in(
      "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 0 6\nWALL 0 6 0 0\n"
      "CORNER 0 0 0\nCORNER 1 8 0\nCORNER 2 8 6\nCORNER 3 0 6\nPATH 2 3\nPATH 3 3\n");
  const FloorPlan plan = readFloorPlan(in, "room", 0.0, 1);
  RangeScannerOptions scanner = carmenScanner();
  const Pose2 sensor(2, 3, 0.1);
  std::vector<MapWall> room = walls();
  room.pop_back();
  DetectorEvaluationOptions o;
  o.max_range = 20;
  EXPECT_EQ(visibleMapCorners(kCorners, room, sensor,
                              castRangeScan(plan, sensor, 0, scanner, nullptr), o),
            std::vector<std::size_t>({1, 2}));
  EXPECT_TRUE(visibleMapCorners(kCorners, room, sensor, halfCircle(80), o).empty());
  o.wall_returns = 0;
  EXPECT_EQ(visibleMapCorners(kCorners, room, sensor, halfCircle(80), o),
            std::vector<std::size_t>({1, 2}));
}

TEST(DetectorEvaluation, AWallSeenGrazingShowsInItsSparseReturns) {
  // The room's corner (8, 0) from (2, 0.6): the south wall at 6 degrees to
  // the beams, whose returns lie 0.5 to 1 m apart there, two at most in the
  // first metre from the corner; the east wall seen face on. Both walls
  // show: the returns asked of a wall lie within as many beams' spacing on
  // it as they number.
  std::istringstream in(
      "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 0 6\nWALL 0 6 0 0\n"
      "CORNER 0 0 0\nCORNER 1 8 0\nCORNER 2 8 6\nCORNER 3 0 6\nPATH 2 3\nPATH 3 3\n");
  const FloorPlan plan = readFloorPlan(in, "room", 0.0, 1);
  RangeScannerOptions scanner = carmenScanner();
  std::vector<MapWall> room = walls();
  room.pop_back();
  DetectorEvaluationOptions o;
  o.max_range = 20;
  const Pose2 sensor(2, 0.6, 0);
  const RangeScan scan = castRangeScan(plan, sensor, 0, scanner, nullptr);
  int first_metre = 0;  // the south wall's returns 0.15 to 1 m from (8, 0)
  for (std::size_t b = 0; b < scan.ranges.size(); ++b) {
    const Point2 p = sensor.transformFrom(scan.point(b));
    first_metre += scan.hit(b) && std::abs(p.y()) < 0.05 && p.x() >= 7 && p.x() <= 7.85;
  }
  ASSERT_LT(first_metre, o.wall_returns);
  EXPECT_EQ(visibleMapCorners({{8, 0}}, room, sensor, scan, o), std::vector<std::size_t>({0}));
  // A wall with too few returns anywhere near the corner still does not
  // show: the south wall cut 1.5 m from the corner leaves one return on it.
  RangeScan cut = scan;
  for (std::size_t b = 0; b < cut.ranges.size(); ++b) {
    const Point2 p = sensor.transformFrom(cut.point(b));
    if (std::abs(p.y()) < 0.05 && p.x() < 6.5) cut.ranges[b] = 80;
  }
  EXPECT_TRUE(visibleMapCorners({{8, 0}}, room, sensor, cut, o).empty());
}

TEST(DetectorEvaluation, AGrazingWallsReturnsAreSoughtAsFarAsTheBeamsReachIt) {
  // The convex corner (0, 0) from (-1.8, 5.8), as ACES's held-out scan 304
  // saw one: its wall down the x = 0 line recedes from the sensor, the
  // beams' spacing on it growing from 0.36 m at the corner. Returns 0.48,
  // 0.92, 1.42 m along it: three beams past arm / 2 reach it within 1.42 m,
  // while three spacings as at the corner end at 1.22 m, where only two lie.
  std::istringstream in(
      "WALL 0 0 0 -3\nWALL 0 0 2 0\nWALL -3 8 3 8\nCORNER 0 0 0\nPATH -1 4\nPATH -1 5\n");
  const FloorPlan plan = readFloorPlan(in, "room", 0.0, 1);
  RangeScannerOptions scanner = carmenScanner();
  const Pose2 sensor(-1.8, 5.8, -kPi / 2);
  const RangeScan scan = castRangeScan(plan, sensor, 0, scanner, nullptr);
  DetectorEvaluationOptions o;
  o.max_range = 20;
  const Point2 ray = Point2(0, 0) - sensor.t();
  const double spacing = ray.norm() * scanner.angular_step / std::abs(ray.normalized().x());
  int near = 0;  // the wall's returns within three spacings as at the corner
  for (std::size_t b = 0; b < scan.ranges.size(); ++b) {
    const Point2 p = sensor.transformFrom(scan.point(b));
    near += scan.hit(b) && std::abs(p.x()) < 0.05 && -p.y() >= 0.5 * o.arm &&
            -p.y() <= 0.5 * o.arm + o.wall_returns * spacing;
  }
  ASSERT_LT(near, o.wall_returns);
  const std::vector<MapWall> map = {{{0, 0}, {0, -3}, 6}, {{0, 0}, {2, 0}, 6}};
  EXPECT_EQ(visibleMapCorners({{0, 0}}, map, sensor, scan, o), std::vector<std::size_t>({0}));
}

TEST(DetectorEvaluation, AReturnCountsForTheCornersWallWhoseLineItLiesNearest) {
  // The concave corner (0, 0) of wall A (towards 230 degrees) and wall B
  // (towards 180), seen from inside the 50-degree wedge between them, in a
  // 12 x 9 m box whose far walls return the beams that miss both. With a
  // wide on_wall band A's returns 0.23-0.52 m from the corner lie within it
  // of B's line and ahead along B: they are nearer A's, so B shows only when
  // the scan holds B.
  const std::string box = "WALL -6 3 6 3\nWALL 6 3 6 -6\nWALL 6 -6 -6 -6\nWALL -6 -6 -6 3\n";
  const Point2 a_end(3 * std::cos(230 * kPi / 180), 3 * std::sin(230 * kPi / 180));
  const std::string wall_a =
      "WALL 0 0 " + std::to_string(a_end.x()) + " " + std::to_string(a_end.y()) + "\n";
  const std::string rest = "CORNER 0 0 0\nPATH -2 -1\nPATH -2 -2\n";
  std::istringstream only_a(box + wall_a + rest), both(box + wall_a + "WALL 0 0 -3 0\n" + rest);
  const Point2 from(2 * std::cos(205 * kPi / 180), 2 * std::sin(205 * kPi / 180));
  const Pose2 sensor(from.x(), from.y(), std::atan2(-from.y(), -from.x()));
  const RangeScan scan_a =
      castRangeScan(readFloorPlan(only_a, "a", 0.0, 1), sensor, 0, carmenScanner(), nullptr);
  const RangeScan scan_ab =
      castRangeScan(readFloorPlan(both, "ab", 0.0, 1), sensor, 0, carmenScanner(), nullptr);
  const std::vector<MapWall> map = {{{0, 0}, a_end, 6}, {{0, 0}, {-3, 0}, 6}};
  DetectorEvaluationOptions o;
  o.max_range = 20;
  o.on_wall = 0.4;
  // Without the rule B would show: enough of A's returns lie in B's band.
  int in_b_band = 0;
  for (std::size_t b = 0; b < scan_a.ranges.size(); ++b) {
    const Point2 p = sensor.transformFrom(scan_a.point(b));
    in_b_band += scan_a.hit(b) && -p.x() >= 0.5 * o.arm && -p.x() <= o.wall_extent &&
                 std::abs(p.y()) <= o.on_wall;
  }
  ASSERT_GE(in_b_band, o.wall_returns);
  EXPECT_TRUE(visibleMapCorners({{0, 0}}, map, sensor, scan_a, o).empty());
  EXPECT_EQ(visibleMapCorners({{0, 0}}, map, sensor, scan_ab, o), std::vector<std::size_t>({0}));
}

TEST(DetectorEvaluation, LabelsCloserThanTheRadiusAreOneCorner) {
  // Two labels 0.2 m apart (a wall mapped twice a little apart makes two
  // corners of one): one detection finds the corner, a second one near the
  // other label is right too; labels 0.35 m apart stay two, and a chain of
  // labels each within the radius of the next is one.
  const Pose2 sensor(0, 0, 0);
  const auto at = [](double x, double y) {
    VerticalEdge e;
    e.position = Point2(x, y);
    return e;
  };
  const DetectorEvaluationOptions o;
  const std::vector<Point2> pair = {{4, 1}, {4.2, 1}};
  DetectorScore s = scoreScan({at(4.05, 1)}, sensor, pair, {0, 1}, o);
  EXPECT_EQ(s.labels, 1u);
  EXPECT_EQ(s.matched_labels, 1u);
  EXPECT_EQ(s.true_positives, 1u);
  s = scoreScan({at(4, 1), at(4.2, 1)}, sensor, pair, {0, 1}, o);
  EXPECT_EQ(s.labels, 1u);
  EXPECT_EQ(s.true_positives, 2u);
  EXPECT_EQ(s.precision(), 1.0);
  EXPECT_EQ(s.recall(), 1.0);
  s = scoreScan({at(4.05, 1)}, sensor, {{4, 1}, {4.35, 1}}, {0, 1}, o);
  EXPECT_EQ(s.labels, 2u);
  EXPECT_DOUBLE_EQ(s.recall(), 0.5);
  // 4.5 joins 4.25's corner after 4 has: all three are one.
  s = scoreScan({}, sensor, {{4, 1}, {4.5, 1}, {4.25, 1}}, {0, 1, 2}, o);
  EXPECT_EQ(s.labels, 1u);
}

TEST(DetectorEvaluation, EachLabelMatchedOnceClosestFirst) {
  const Pose2 sensor(2, 3, kPi / 2);  // facing +y: world (x, y) is local (y - 3, 2 - x)
  const auto at = [&](double x, double y) {
    VerticalEdge e;
    e.position = sensor.transformTo(Point2(x, y));
    return e;
  };
  // Two detections near (8, 6), the closer one wins; one 0.25 m from (8, 0);
  // one in the middle of the room; one 0.35 m from (0, 6), outside the radius.
  const std::vector<VerticalEdge> d = {at(8.2, 6), at(8.05, 6), at(8, 0.25), at(4, 3), at(0, 6.35)};
  const DetectorScore s = scoreScan(d, sensor, kCorners, {1, 2, 3}, DetectorEvaluationOptions());
  EXPECT_EQ(s.scans, 1u);
  EXPECT_EQ(s.detections, 5u);
  EXPECT_EQ(s.true_positives, 2u);
  EXPECT_EQ(s.labels, 3u);
  EXPECT_EQ(s.matched_labels, 2u);
  EXPECT_DOUBLE_EQ(s.precision(), 2.0 / 5);
  EXPECT_DOUBLE_EQ(s.recall(), 2.0 / 3);
  // A detection beyond the labels' range is not graded: neither a
  // detection nor a false positive.
  DetectorEvaluationOptions near;
  near.max_range = 5;
  const DetectorScore cut = scoreScan(d, sensor, kCorners, {1, 2, 3}, near);
  std::size_t within = 0;
  for (const VerticalEdge& e : d) within += e.position.norm() <= 5;
  ASSERT_LT(within, d.size());
  EXPECT_EQ(cut.detections, within);
  // A detection near a corner that is no label (here (0, 0)) is a false positive.
  EXPECT_EQ(
      scoreScan({at(0.1, 0)}, sensor, kCorners, {1, 2}, DetectorEvaluationOptions()).true_positives,
      0u);
  DetectorScore total = s;
  total += s;
  EXPECT_EQ(total.detections, 10u);
  EXPECT_DOUBLE_EQ(total.precision(), 2.0 / 5);
  EXPECT_DOUBLE_EQ(DetectorScore().precision(), 1.0);  // nothing detected, nothing wrong
}

TEST(DetectorEvaluation, ExactScanOfARoomIsJudgedPerfect) {
  std::istringstream in(
      "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 0 6\nWALL 0 6 0 0\n"
      "CORNER 0 0 0\nCORNER 1 8 0\nCORNER 2 8 6\nCORNER 3 0 6\nPATH 2 3\nPATH 3 3\n");
  const FloorPlan plan = readFloorPlan(in, "room", 0.0, 1);
  RangeScannerOptions scanner = carmenScanner();
  const Pose2 sensor(2, 3, 0.1);
  const RangeScan scan = castRangeScan(plan, sensor, 0, scanner, nullptr);
  std::vector<MapWall> room = walls();
  room.pop_back();
  DetectorEvaluationOptions o;
  o.max_range = 20;
  const std::vector<std::size_t> labels = visibleMapCorners(kCorners, room, sensor, scan, o);
  ASSERT_EQ(labels, std::vector<std::size_t>({1, 2}));
  const DetectorScore s =
      scoreScan(detectVerticalEdges(scan, realLogDetectorOptions()), sensor, kCorners, labels, o);
  EXPECT_EQ(s.detections, 2u);
  EXPECT_EQ(s.precision(), 1.0);
  EXPECT_EQ(s.recall(), 1.0);
}

TEST(DetectorEvaluation, MapCoverageIsTheShareOfReturnsOnMapWalls) {
  RangeScan scan = halfCircle(80);
  const Pose2 sensor(2, 3, 0);
  // Beam 90 (bearing 0) returns from the east wall at x = 8, beam 0 (-90
  // degrees) from the south wall at y = 0; beam 45 from 1 m: off every wall.
  scan.ranges.assign(181, 80.0);  // no returns
  DetectorEvaluationOptions o;
  o.max_range = 20;
  EXPECT_EQ(mapCoverage(scan, sensor, walls(), o), 0.0);
  scan.ranges[90] = 6.1;  // 0.1 m past the wall: on it
  scan.ranges[0] = 3.0;
  scan.ranges[45] = 1.0;
  EXPECT_DOUBLE_EQ(mapCoverage(scan, sensor, walls(), o), 2.0 / 3);
  o.max_range = 5;  // beam 90 no longer counts
  EXPECT_DOUBLE_EQ(mapCoverage(scan, sensor, walls(), o), 1.0 / 2);
}

TEST(DetectorEvaluation, OptionsOutOfRangeRefused) {
  DetectorEvaluationOptions o;
  o.radius = 0;
  EXPECT_THROW(o.validate(), Error);
  o = DetectorEvaluationOptions();
  o.occlusion_margin = -1;
  EXPECT_THROW(o.validate(), Error);
  o = DetectorEvaluationOptions();
  o.walls_seen = 3;
  EXPECT_THROW(o.validate(), Error);
  o = DetectorEvaluationOptions();
  o.mapped_share = 1.5;
  EXPECT_THROW(o.validate(), Error);
  o = DetectorEvaluationOptions();
  o.wall_returns = -1;
  EXPECT_THROW(o.validate(), Error);
  o = DetectorEvaluationOptions();
  o.min_wall_angle = 0;
  EXPECT_THROW(o.validate(), Error);
}

}  // namespace
}  // namespace hamal::flag
