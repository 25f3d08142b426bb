// FLAG's vertical-edge detector (apps/flag/vertical_edge_detector.h) on
// scans ray cast in rooms whose corners are known (range_scan.h): every
// corner in view found, convex and concave, at the right place; occluding
// edges and furniture under 1 m refused; a corner whose second wall shows
// only as a stub found; grazing walls kept whole; silhouette edges on the
// near side of a range jump only, none on a person; precision and recall on
// noisy scans of the office world; the real logs' options refuse corners far
// from square, without a long wall, of walls that fit poorly or of a short
// wall ending in the open; options out of range refused by name.
#include "apps/flag/vertical_edge_detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <sstream>
#include <string>

#include "apps/flag/builtin_worlds.h"
#include "apps/flag/corner_visibility.h"
#include "apps/flag/simulator.h"
#include "core/error.h"

namespace hamal::flag {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

FloorPlan plan(const std::string& text) {
  std::istringstream in(text + "PATH 1 1\nPATH 1.5 1\n");
  return readFloorPlan(in, "room", 0.0, 1);
}

// An 8 x 6 m room with a niche 1.5 m wide and 1 m deep in its north wall.
const char kRoom[] =
    "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 5.5 6\nWALL 5.5 6 5.5 7\nWALL 5.5 7 4 7\n"
    "WALL 4 7 4 6\nWALL 4 6 0 6\nWALL 0 6 0 0\n"
    "CORNER 0 0 0\nCORNER 1 8 0\nCORNER 2 8 6\nCORNER 3 5.5 6\nCORNER 4 5.5 7\n"
    "CORNER 5 4 7\nCORNER 6 4 6\nCORNER 7 0 6\n";

// An 8 x 6 m room, its corners labelled 0-3; tests add what stands in it.
const std::string kBox =
    "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 8 6 0 6\nWALL 0 6 0 0\n"
    "CORNER 0 0 0\nCORNER 1 8 0\nCORNER 2 8 6\nCORNER 3 0 6\n";

RangeScannerOptions exact() {
  RangeScannerOptions o;
  o.max_range = 20;
  return o;
}

// The detections as world points, with the nearest plan corner's id (or -1).
struct Found {
  long id;
  Point2 at;
  bool convex;
};
std::vector<Found> find(const FloorPlan& p, const Pose2& pose, const RangeScannerOptions& s,
                        const VerticalEdgeDetectorOptions& d, std::mt19937_64* rng = nullptr) {
  std::vector<Found> out;
  for (const VerticalEdge& e : detectVerticalEdges(castRangeScan(p, pose, 0, s, rng), d)) {
    const Point2 w = pose.transformFrom(e.position);
    const Source src = sourceOf(p, w, 0, s, 0.3);
    out.push_back({src.kind == Source::kCorner ? long(src.id) : -1, w, e.convex});
  }
  std::sort(out.begin(), out.end(), [](const Found& a, const Found& b) { return a.id < b.id; });
  return out;
}

// Two-line corners alone: the detector without step 4.
VerticalEdgeDetectorOptions silhouettes(bool on) {
  VerticalEdgeDetectorOptions d;
  d.silhouettes.enabled = on;
  return d;
}

TEST(VerticalEdgeDetector, FindsEveryCornerInViewConvexAndConcave) {
  const FloorPlan room = plan(kRoom);
  const Pose2 pose(2, 3, 0.3);
  // From (2, 3) the niche's west side hides behind the north wall: its
  // corners 5 and 6 show one wall each (6 a silhouette edge, found as such
  // below).
  const VisibleCorners v = visibleCorners(room, pose, 0, exact(), 0.3, 0.1);
  EXPECT_EQ(v.in_view, (std::vector<std::uint64_t>{0, 1, 2, 3, 4, 7}));
  const std::vector<Found> f = find(room, pose, exact(), silhouettes(false));
  ASSERT_EQ(f.size(), 6u);
  const long ids[] = {0, 1, 2, 3, 4, 7};
  for (std::size_t k = 0; k < f.size(); ++k) {
    EXPECT_EQ(f[k].id, ids[k]);
    EXPECT_LT((f[k].at - room.corner(ids[k])->truth).norm(), 0.01) << "corner " << ids[k];
    EXPECT_EQ(f[k].convex, ids[k] == 3) << "corner " << ids[k];  // the niche's mouth
  }
  // The segments step 2 keeps are the visible walls.
  EXPECT_GE(extractLineSegments(castRangeScan(room, pose, 0, exact(), nullptr), {}).size(), 6u);
}

// A free-standing wall: its ends, and where its shadow falls on the far
// wall, are no corners (its ends are silhouette edges: see below).
TEST(VerticalEdgeDetector, RefusesOccludingEdges) {
  const FloorPlan room = plan(kBox + "WALL 3 4 5 4\n");
  const std::vector<Found> f = find(room, Pose2(4, 1.5, 0), exact(), silhouettes(false));
  ASSERT_EQ(f.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(f[k].id, long(k));
}

// Options without the stub rule: both walls of a corner full segments.
VerticalEdgeDetectorOptions twoWalls() {
  VerticalEdgeDetectorOptions d = silhouettes(false);
  d.corners.min_stub_points = d.segments.min_points;
  d.corners.min_stub_length = d.segments.min_length;
  return d;
}

bool foundAt(const std::vector<Found>& f, const Point2& p) {
  return std::any_of(f.begin(), f.end(), [&](const Found& d) { return (d.at - p).norm() < 0.05; });
}

// A free-standing wall hides the room's east wall but for its first 0.22 m
// from the south-east corner (4 beams): that corner is a long wall and a
// stub, found by the stub rule and not without it. The free-standing wall's
// ends, where the scan jumps away to the stub and to the east wall behind,
// are no corners (silhouette edges, off here).
TEST(VerticalEdgeDetector, FindsACornerWhoseSecondWallIsAStubButNoOccludingEdge) {
  const FloorPlan room = plan(kBox + "WALL 7 0.35 7 3\n");
  const Pose2 pose(2, 1, 0);
  const std::vector<Found> with_stubs = find(room, pose, exact(), silhouettes(false));
  const std::vector<Found> without = find(room, pose, exact(), twoWalls());
  EXPECT_TRUE(foundAt(with_stubs, {8, 0}));
  EXPECT_FALSE(foundAt(without, {8, 0}));
  for (const auto& f : {with_stubs, without}) {
    EXPECT_FALSE(foundAt(f, {7, 0.35}));
    EXPECT_FALSE(foundAt(f, {7, 3}));
    for (const Found& d : f) EXPECT_GE(d.id, 0) << "a detection at " << d.at.transpose();
  }
  // The ground truth agrees: (8, 0) is in view with a stub, not with two walls.
  const auto inView = [&](double stub) {
    const auto v = visibleCorners(room, pose, 0, exact(), 0.3, stub).in_view;
    return std::find(v.begin(), v.end(), 1u) != v.end();
  };
  EXPECT_TRUE(inView(0.15));
  EXPECT_FALSE(inView(0.3));
}

// Far along a corridor the wall is seen at 5-10 degrees to the beam: the
// breakpoint rule at Borges & Aldon's 10 degrees cuts it into single
// points, at 5 degrees it stays one surface and the niche's far corner
// shows.
TEST(VerticalEdgeDetector, GrazingWallsNeedTheSmallerBreakpointAngle) {
  const FloorPlan corridor = plan(
      "WALL 0 0 7 0\nWALL 7 0 7 -0.7\nWALL 7 -0.7 8.5 -0.7\nWALL 8.5 -0.7 8.5 0\n"
      "WALL 8.5 0 20 0\nWALL 20 0 20 2\nWALL 20 2 0 2\nWALL 0 2 0 0\n"
      "CORNER 0 7 0\nCORNER 1 7 -0.7\nCORNER 2 8.5 -0.7\nCORNER 3 8.5 0\n");
  const Pose2 pose(1, 1, 0);
  VerticalEdgeDetectorOptions wide;
  wide.breakpoints.lambda = 10 * kDeg;
  EXPECT_TRUE(foundAt(find(corridor, pose, exact(), {}), {8.5, 0}));
  EXPECT_FALSE(foundAt(find(corridor, pose, exact(), wide), {8.5, 0}));
}

// The niche's mouth seen from (2, 3): the north wall ends at corner 6
// (4, 6) and the scan jumps into the niche, onto its back wall at (4.67,
// 7). The near side's end is corner 6, a silhouette edge, found with the
// option, half a beam past the wall's last return (beams 3.8 cm apart
// there); the far side's end is where the back wall goes on behind the
// north wall, never an edge.
TEST(VerticalEdgeDetector, SilhouetteEdgeOnTheNearSideOfAJumpOnly) {
  const FloorPlan room = plan(kRoom);
  const Pose2 pose(2, 3, 0.3);
  const std::vector<Found> off = find(room, pose, exact(), silhouettes(false));
  const std::vector<Found> on = find(room, pose, exact(), silhouettes(true));
  EXPECT_FALSE(foundAt(off, {4, 6}));
  ASSERT_EQ(on.size(), off.size() + 1);
  const auto six = std::find_if(on.begin(), on.end(), [](const Found& f) { return f.id == 6; });
  ASSERT_NE(six, on.end());
  EXPECT_LT((six->at - Point2(4, 6)).norm(), 0.02);
  EXPECT_TRUE(six->convex);
  for (const Found& f : on) EXPECT_GE(f.id, 0) << "a detection at " << f.at.transpose();
  // Where exactly: between the last beam on the wall and the next.
  const RangeScan scan = castRangeScan(room, pose, 0, exact(), nullptr);
  const std::vector<VerticalEdge> edges = detectVerticalEdges(scan, silhouettes(true));
  const auto e =
      std::find_if(edges.begin(), edges.end(), [](const VerticalEdge& v) { return v.silhouette; });
  ASSERT_NE(e, edges.end());
  // The beams sweep counter-clockwise, from the niche onto the north wall.
  std::size_t first = scan.ranges.size();
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const Point2 w = pose.transformFrom(scan.point(i));
    if (std::abs(w.y() - 6) < 1e-6 && w.x() < 4) first = std::min(first, i);
  }
  ASSERT_LT(first, scan.ranges.size());
  EXPECT_NEAR(e->bearing, scan.bearing(first) - 0.5 * scan.angular_step, 1e-9);
  EXPECT_LT(std::abs(pose.transformFrom(e->position).y() - 6), 1e-6);
}

// A free-standing wall: its ends are silhouette edges (a wall's end is a
// vertical edge), where its shadow falls on the north wall behind is not;
// they are no corners of the plan, as RefusesOccludingEdges finds without
// the option.
TEST(VerticalEdgeDetector, AWallsEndsAreSilhouetteEdgesItsShadowsAreNot) {
  const FloorPlan room = plan(kBox + "WALL 3 4 5 4\n");
  const std::vector<Found> f = find(room, Pose2(4, 1.5, 0), exact(), silhouettes(true));
  ASSERT_EQ(f.size(), 6u);
  EXPECT_TRUE(foundAt(f, {3, 4}));
  EXPECT_TRUE(foundAt(f, {5, 4}));
  for (const Found& d : f) EXPECT_TRUE(d.id >= 0 || std::abs(d.at.y() - 4) < 1e-6);
}

// Real logs keep silhouette edges off (realLogDetectorOptions): the
// free-standing wall's ends are no detections there.
TEST(VerticalEdgeDetector, RealLogOptionsMakeNoSilhouetteEdges) {
  const FloorPlan room = plan(kBox + "WALL 3 4 5 4\n");
  const Pose2 pose(4, 1.5, 0);
  VerticalEdgeDetectorOptions real = realLogDetectorOptions();
  EXPECT_FALSE(foundAt(find(room, pose, exact(), real), {3, 4}));
  real.silhouettes.enabled = true;
  EXPECT_TRUE(foundAt(find(room, pose, exact(), real), {3, 4}));
}

// A person (a 0.25 m circle) or a cabinet's 0.4 m face before a wall: no
// outline or side that short makes a silhouette edge (the wall's ends
// beside them are the far side of the jumps).
TEST(VerticalEdgeDetector, NoSilhouetteEdgeOnAPersonOrACabinetsFace) {
  for (const char* thing : {"PERSON 4 3.5 4 3.6 0 0.01\n", "OBJECT 4 3 1.8\n"}) {
    const FloorPlan room = plan(kBox + thing);
    for (double heading : {0.0, 1.2, 1.57, 2.5}) {
      const Pose2 pose(4, 1.5, heading);
      EXPECT_EQ(find(room, pose, exact(), silhouettes(true)).size(),
                find(room, pose, exact(), silhouettes(false)).size())
          << thing << " heading " << heading;
    }
  }
  // The cabinet's face seen square on, both its ends at jumps: long enough
  // for a 0.3 m minimum, not for the default.
  VerticalEdgeDetectorOptions short_walls = silhouettes(true);
  short_walls.silhouettes.min_length = 0.3;
  const FloorPlan cabinet = plan(kBox + "OBJECT 4 3 1.8\n");
  const std::vector<Found> f = find(cabinet, Pose2(4, 1.5, 1.57), exact(), short_walls);
  EXPECT_TRUE(foundAt(f, {3.8, 2.8}));
  EXPECT_TRUE(foundAt(f, {4.2, 2.8}));
}

// Where the scan ends nothing is known past the last beam: a wall running
// out of the scanner's 10 m, or past the edge of a partial field of view,
// makes no silhouette edge; the wall's own end does.
TEST(VerticalEdgeDetector, NoSilhouetteEdgeWhereTheScanEnds) {
  // A 30 x 9 m hall seen from (15, 1): the north wall leaves the 10 m range
  // at x = 9 and 21, where the beams fall 11 cm apart on it.
  const FloorPlan hall = plan(
      "WALL 0 0 30 0\nWALL 30 0 30 9\nWALL 30 9 0 9\nWALL 0 9 0 0\nCORNER 0 0 0\nCORNER 1 30 0\n");
  RangeScannerOptions ten = exact();
  ten.max_range = 10;
  EXPECT_TRUE(find(hall, Pose2(15, 1, 0), ten, silhouettes(true)).empty());
  // A 350-degree scan from (1, 1) whose first beam falls on a wall that
  // goes on into the 10 degrees behind the scanner, where it ends; a wall
  // 4 m east runs out of the 8 m range.
  const FloorPlan wall = plan("WALL -1 -4 -1 1\nWALL 5 -10 5 10\nCORNER 0 -1 -4\n");
  RangeScannerOptions most = exact();
  most.field_of_view = 350 * kDeg;
  most.max_range = 8;
  const std::vector<Found> f = find(wall, Pose2(1, 1, 0), most, silhouettes(true));
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].id, 0);
}

// 2.5D: a box under 1 m is furniture; a cabinet's convex edge is a vertical edge.
TEST(VerticalEdgeDetector, DiscardsEdgesLowerThanTheMinimumHeight) {
  const FloorPlan room = plan(kBox + "OBJECT 4 3 0.8\nOBJECT 6 3 1.8\n");
  const Pose2 pose(4.5, 1.5, 0);
  const auto edgesAt = [&](const Point2& p, double min_height) {
    VerticalEdgeDetectorOptions d;
    d.min_height = min_height;
    int n = 0;
    for (const Found& f : find(room, pose, exact(), d)) n += (f.at - p).norm() < 0.03;
    return n;
  };
  EXPECT_EQ(edgesAt({5.8, 2.8}, 1.0), 1);  // the cabinet's corner facing the scanner
  EXPECT_EQ(edgesAt({4.2, 2.8}, 1.0), 0);  // the low box's
  EXPECT_EQ(edgesAt({4.2, 2.8}, 0.5), 1);
}

// The real logs' options (a 180-degree, 1-degree scan like CARMEN's) refuse
// clutter's corners: each rule on its own.
RangeScannerOptions carmenScanner() {
  RangeScannerOptions s = exact();
  s.field_of_view = 3.14159265358979323846;
  s.angular_step = kDeg;
  return s;
}

// A room's 120-degree corner (its walls turn by 60 degrees) at (5, 0): a
// building's corners are square; angles this far off are furniture or
// clutter's pieces on real scans.
TEST(VerticalEdgeDetector, RealLogOptionsRefuseCornersFarFromSquare) {
  const FloorPlan room = plan(
      "WALL 0 0 5 0\nWALL 5 0 6.5 2.598\nWALL 6.5 2.598 0 2.598\nWALL 0 2.598 0 0\n"
      "CORNER 0 5 0\n");
  const Pose2 pose(3, 1.5, -0.6);
  VerticalEdgeDetectorOptions d = realLogDetectorOptions();
  EXPECT_FALSE(foundAt(find(room, pose, carmenScanner(), d), {5, 0}));
  d.corners.min_angle = 45 * kDeg;
  d.corners.max_angle = 135 * kDeg;
  EXPECT_TRUE(foundAt(find(room, pose, carmenScanner(), d), {5, 0}));
}

// A 0.6 m box standing in a hall: its corner has two walls shorter than
// `corners.min_long_wall` (a sawtooth of short pieces is chairs, a person, a
// shelf's contents); a room's corner with long walls is kept.
TEST(VerticalEdgeDetector, RealLogOptionsRefuseCornersWithoutALongWall) {
  const FloorPlan hall = plan(
      "WALL -5 -5 15 -5\nWALL 15 -5 15 15\nWALL 15 15 -5 15\nWALL -5 15 -5 -5\n"
      "WALL 4 1 4.6 1\nWALL 4.6 1 4.6 1.6\nWALL 4.6 1.6 4 1.6\nWALL 4 1.6 4 1\nCORNER 0 4 1\n");
  const Pose2 pose(2, -0.5, 0.5);
  VerticalEdgeDetectorOptions d = realLogDetectorOptions();
  EXPECT_FALSE(foundAt(find(hall, pose, carmenScanner(), d), {4, 1}));
  d.corners.min_long_wall = 0;
  EXPECT_TRUE(foundAt(find(hall, pose, carmenScanner(), d), {4, 1}));
  const FloorPlan room = plan(kBox);
  EXPECT_TRUE(
      foundAt(find(room, Pose2(2, 3, -0.3), carmenScanner(), realLogDetectorOptions()), {8, 0}));
}

// Walls whose returns scatter about their lines by more than `corners.max_fit_rms`
// (4 cm RMS here; an uneven surface's, not a flat wall's at the scanner's
// noise) make no corner; the same room scanned exactly does.
TEST(VerticalEdgeDetector, RealLogOptionsRefuseCornersOfWallsThatFitPoorly) {
  const FloorPlan room = plan(kBox);
  const Pose2 pose(2, 3, -0.3);
  RangeScannerOptions rough = carmenScanner();
  rough.range_sigma = 0.04;
  VerticalEdgeDetectorOptions d = realLogDetectorOptions();
  d.segments.fit_tolerance = 0.2;  // one segment per wall however rough
  std::mt19937_64 rng(5);
  EXPECT_FALSE(foundAt(find(room, pose, rough, d, &rng), {8, 0}));
  EXPECT_TRUE(foundAt(find(room, pose, carmenScanner(), d), {8, 0}));
  d.corners.max_fit_rms = 0;
  rng.seed(5);
  const std::vector<Found> f = find(room, pose, rough, d, &rng);
  EXPECT_TRUE(std::any_of(f.begin(), f.end(), [](const Found& x) { return x.id == 1; }));
}

// A door recess 0.45 m deep in a wall: each jamb is a wall shorter than
// `corners.min_open_wall` whose outer end turns again (into the recess's
// back wall, or out of it into the wall): a real edge, no plan's corner,
// refused (found without the rule), as is a wall that stops 0.45 m from
// the corner with a far wall behind its end. The same 0.45 m of wall seen
// because something nearer hides the rest is cut from sight, not ended: its
// corner is kept.
TEST(VerticalEdgeDetector, RealLogOptionsRefuseCornersOfShortWallsEndingInTheOpen) {
  const Pose2 pose(4.5, 5.2, 1.6);
  const FloorPlan recess = plan(
      "WALL 0 0 8 0\nWALL 8 0 8 6\nWALL 0 6 0 0\nWALL 0 6 3 6\nWALL 3 6 3 6.45\n"
      "WALL 3 6.45 6 6.45\nWALL 6 6.45 6 6\nWALL 6 6 8 6\nCORNER 0 3 6\n");
  VerticalEdgeDetectorOptions d = realLogDetectorOptions();
  EXPECT_FALSE(foundAt(find(recess, pose, carmenScanner(), d), {3, 6}));
  d.corners.min_open_wall = 0;
  EXPECT_TRUE(foundAt(find(recess, pose, carmenScanner(), d), {3, 6}));
  // The wall from (3, 6) runs on north behind a panel 1 m from the sensor
  // that hides all of it past 0.45 m: the scan past the seen piece jumps nearer.
  const FloorPlan hidden = plan(
      "WALL 0 0 8 0\nWALL 8 0 8 9\nWALL 0 6 0 0\nWALL 0 6 3 6\nWALL 3 6 3 9\n"
      "WALL 3.70 5.82 4.16 6.20\nCORNER 0 3 6\n");
  EXPECT_TRUE(foundAt(find(hidden, pose, carmenScanner(), realLogDetectorOptions()), {3, 6}));
  // Without the panel, a wall that stops 0.45 m from the corner, the beam
  // past its end reaching a wall 3 m behind: it ends in the open.
  const FloorPlan stops = plan(
      "WALL 0 0 8 0\nWALL 8 0 8 9.5\nWALL 0 9.5 0 0\nWALL 0 9.5 8 9.5\nWALL 0 6 3 6\n"
      "WALL 3 6 3 6.45\nCORNER 0 3 6\n");
  d.corners.min_open_wall = 0.5;
  EXPECT_FALSE(foundAt(find(stops, pose, carmenScanner(), d), {3, 6}));
  d.corners.min_open_wall = 0;
  EXPECT_TRUE(foundAt(find(stops, pose, carmenScanner(), d), {3, 6}));
}

// Noisy scans from 100 random places in the room: precision and recall.
TEST(VerticalEdgeDetector, PrecisionAndRecallOnNoisyScansOfTheRoom) {
  const FloorPlan room = plan(kRoom);
  RangeScannerOptions s = exact();
  s.range_sigma = 0.015;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> x(0.5, 7.5), y(0.5, 5.5), th(-3.14, 3.14);
  std::size_t detections = 0, right = 0, in_view = 0, found = 0;
  for (int k = 0; k < 100; ++k) {
    const Pose2 pose(x(rng), y(rng), th(rng));
    const std::vector<Found> f = find(room, pose, s, {}, &rng);
    detections += f.size();
    for (const Found& d : f) right += d.id >= 0;
    for (std::uint64_t id : visibleCorners(room, pose, 0, s, 0.3, 0.1).in_view) {
      ++in_view;
      found += std::any_of(f.begin(), f.end(), [&](const Found& d) { return d.id == long(id); });
    }
  }
  ASSERT_GT(in_view, 400u);
  EXPECT_GE(double(right) / double(detections), 0.98);
  EXPECT_GE(double(found) / double(in_view), 0.90);
}

// The office world with its cabinets and people, as FLAG's simulator runs
// it: the precision and recall the README states, and the errors the
// detections carry. Silhouette edges find most corners in line of sight
// that two lines miss, each within half the beams' spacing on its wall
// (up to 0.25 m), so the range error grows.
TEST(VerticalEdgeDetector, PrecisionAndRecallOnTheOfficeWorld) {
  const FloorPlan office = builtinWorld("office", 0.1, 1);
  SimulatorOptions o;
  o.seed = 2;
  const DetectionScore d = scoreDetections(office, simulate(office, o), o);
  o.edges.silhouettes.enabled = false;
  const DetectionScore two_lines = scoreDetections(office, simulate(office, o), o);
  for (const DetectionScore& s : {d, two_lines}) {
    EXPECT_GT(s.detections, 1000u);
    EXPECT_GE(s.precision(), 0.95);
    EXPECT_GE(s.recall(), 0.80);
    EXPECT_GT(s.from_object, 0u);  // the cabinets' edges are seen, and are not corners
    EXPECT_LT(s.bearing_rms, 0.3 * kDeg);
  }
  EXPECT_GE(d.recallInSight(), 0.75);
  EXPECT_LT(two_lines.recallInSight(), 0.5);
  EXPECT_LT(d.range_rms, 0.05);
  EXPECT_LT(two_lines.range_rms, 0.02);
}

TEST(VerticalEdgeDetector, OptionsOutOfRangeAreRefusedByName) {
  const auto refusal = [](auto change) {
    VerticalEdgeDetectorOptions o;
    change(o);
    try {
      o.validate();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  using O = VerticalEdgeDetectorOptions;
  EXPECT_EQ(refusal([](O& o) { o.segments.fit_tolerance = 0; }), "fit_tolerance must be > 0");
  EXPECT_EQ(refusal([](O& o) { o.segments.min_points = 2; }), "min_segment_points must be >= 3");
  EXPECT_EQ(refusal([](O& o) { o.segments.min_length = -1; }), "min_segment_length must be > 0");
  EXPECT_EQ(refusal([](O& o) { o.corners.tolerance = std::nan(""); }),
            "corner_tolerance must be > 0");
  EXPECT_EQ(refusal([](O& o) { o.corners.min_long_wall = -1; }), "min_long_wall must be >= 0");
  EXPECT_EQ(refusal([](O& o) { o.corners.max_fit_rms = std::nan(""); }),
            "max_fit_rms must be >= 0");
  EXPECT_EQ(refusal([](O& o) { o.corners.min_open_wall = -1; }), "min_open_wall must be >= 0");
  EXPECT_NE(refusal([](O& o) {
              o.corners.min_angle = 100 * kDeg;
              o.corners.max_angle = 90 * kDeg;
            }).find("min_corner_angle < max_corner_angle"),
            std::string::npos);
  EXPECT_NE(refusal([](O& o) { o.breakpoints.lambda = 0; }).find("breakpoint_lambda"),
            std::string::npos);
  EXPECT_EQ(refusal([](O& o) { o.min_height = -1; }), "min_height must be >= 0");
  EXPECT_NE(refusal([](O& o) { o.corners.min_stub_points = 2; }).find("min_stub_points"),
            std::string::npos);
  EXPECT_NE(refusal([](O& o) { o.corners.min_stub_length = 0.5; }).find("min_stub_length"),
            std::string::npos);
  EXPECT_EQ(refusal([](O& o) { o.silhouettes.margin = 0; }), "silhouette_margin must be > 0");
  EXPECT_EQ(refusal([](O& o) { o.silhouettes.max_spacing = std::nan(""); }),
            "max_silhouette_spacing must be > 0");
  EXPECT_NE(refusal([](O& o) { o.silhouettes.min_length = 0.2; }).find("min_silhouette_length"),
            std::string::npos);
  EXPECT_EQ(refusal([](O&) {}), "");
  RangeScannerOptions s;
  s.angular_step = 0;
  EXPECT_THROW(s.validate(), Error);
}

}  // namespace
}  // namespace hamal::flag
