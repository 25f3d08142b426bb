// The multi-scan stability check (apps/flag/stable_edge_filter.h) on logs
// written here from scans ray cast in a room: a corner fixed in the world,
// seen from moving poses, is kept; one that moves with the viewpoint, or
// shows in one scan only, is dropped; a log's first and last scans ask only
// as many neighbours as they have. On the ACES log the check is what both
// FLAG's recording and the detector's evaluation see.
#include "apps/flag/stable_edge_filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>

#include "apps/flag/carmen_recording.h"
#include "apps/flag/detector_evaluation.h"
#include "apps/flag/floor_plan.h"
#include "apps/flag/range_scan.h"
#include "core/error.h"
#include "testing/test_data.h"

namespace hamal::flag {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A 6 x 6 m room; its far corners (6, -3) and (6, 3) face a robot driving
// along y = 0 towards them.
FloorPlan room() {
  FloorPlan plan;
  plan.walls = {{{0, -3}, {6, -3}}, {{6, -3}, {6, 3}}, {{6, 3}, {0, 3}}, {{0, 3}, {0, -3}}};
  return plan;
}

// A free-standing wedge (two 1 m walls at 90 degrees) whose convex corner
// at `c` points back along -x at a robot driving along y = 0 (a cabinet, a
// person, a door swung open), clear of the lines of sight to the room's
// corners.
void addWedge(FloorPlan& plan, const Point2& c) {
  plan.walls.push_back({c, c + Point2(0.7, 0.7)});
  plan.walls.push_back({c, c + Point2(0.7, -0.7)});
}

struct Shot {
  FloorPlan scene;  // what the laser sees
  Pose2 scanned;    // where it is scanned from
  Pose2 odometry;   // what the log's ODOM says
};

// A FLASER line per shot (180 beams over 180 degrees, 1.5 cm noise), each
// after an ODOM record at its time.
carmen::CarmenLog log(const std::vector<Shot>& shots) {
  RangeScannerOptions s;
  s.field_of_view = kPi;
  s.angular_step = s.field_of_view / 179;
  s.max_range = 30;
  std::mt19937_64 rng(3);
  std::ostringstream out;
  out << std::setprecision(10) << "PARAM robot_frontlaser_offset 0.0 nohost 0\n"
      << "PARAM robot_front_laser_max 30 nohost 0\n";
  double t = 0;
  for (const Shot& shot : shots) {
    const Pose2& o = shot.odometry;
    out << "ODOM " << o.x << ' ' << o.y << ' ' << o.theta << " 0 0 0 " << t << " host " << t
        << "\n";
    const RangeScan scan = castRangeScan(shot.scene, shot.scanned, 0, s, &rng);
    out << "FLASER " << scan.ranges.size();
    for (double r : scan.ranges) out << ' ' << (r < 30 ? r : 81.83);
    const Pose2& p = shot.scanned;
    out << ' ' << p.x << ' ' << p.y << ' ' << p.theta << ' ' << p.x << ' ' << p.y << ' ' << p.theta
        << ' ' << t << " host " << t << "\n";
    t += 0.5;
  }
  return carmen::parseCarmenLog(out.str(), "stable.log");
}

// Poses along y = 0 from x = 1.4, `step` apart, facing +x (slightly turned
// each time so that the odometry's heading is at work too).
std::vector<Pose2> drive(int n, double step) {
  std::vector<Pose2> poses;
  for (int i = 0; i < n; ++i) poses.emplace_back(1.4 + step * i, 0.1 * std::sin(i), 0.02 * i);
  return poses;
}

VerticalEdgeDetectorOptions detector() {
  VerticalEdgeDetectorOptions d = realLogDetectorOptions();
  d.min_height = 0;
  return d;
}

StableEdgeOptions check(int window, int min_scans, double radius) {
  StableEdgeOptions o;
  o.enabled = true;
  o.window = window;
  o.min_scans = min_scans;
  o.radius = radius;
  return o;
}

// How many of `edges` (sensor frame of `sensor`) lie within 0.15 m of `world`.
int near(const std::vector<VerticalEdge>& edges, const Pose2& sensor, const Point2& world) {
  int n = 0;
  for (const VerticalEdge& e : edges) n += (sensor.transformFrom(e.position) - world).norm() < 0.15;
  return n;
}

TEST(StableEdgeFilter, KeepsACornerFixedInTheWorldSeenFromMovingPoses) {
  std::vector<Shot> shots;
  for (const Pose2& p : drive(7, 0.4)) shots.push_back({room(), p, p});
  const carmen::CarmenLog l = log(shots);
  StableEdgeFilter off(
      l, "FLASER", detector(),
      [] {
        StableEdgeOptions o;
        o.enabled = false;
        return o;
      }(),
      0);
  StableEdgeFilter on(l, "FLASER", detector(), check(2, 2, 0.2), 0);
  for (std::size_t i = 0; i < l.scans.size(); ++i) {
    const std::vector<VerticalEdge> all = off.detect(i), kept = on.detect(i);
    ASSERT_EQ(near(all, shots[i].scanned, {6, -3}), 1) << i;
    ASSERT_EQ(near(all, shots[i].scanned, {6, 3}), 1) << i;
    EXPECT_EQ(kept.size(), all.size()) << i;  // both corners, first and last scans too
  }
}

TEST(StableEdgeFilter, DropsACornerMovingWithTheViewpoint) {
  // The laser stands still (the same scene from the same pose every time)
  // while the odometry says it drives 0.4 m a scan: every corner keeps its
  // place in the laser's frame, so it moves 0.4 m in the world each scan,
  // as an occlusion's edge or a person walking along moves.
  const std::vector<Pose2> poses = drive(7, 0.4);
  std::vector<Shot> shots;
  for (const Pose2& p : poses) shots.push_back({room(), poses[0], p});
  const carmen::CarmenLog l = log(shots);
  StableEdgeFilter on(l, "FLASER", detector(), check(2, 1, 0.2), 0);
  for (std::size_t i = 0; i < l.scans.size(); ++i) EXPECT_TRUE(on.detect(i).empty()) << i;
  // A radius wider than the motion takes it for the same corner.
  StableEdgeFilter wide(l, "FLASER", detector(), check(2, 1, 1.0), 0);
  EXPECT_EQ(wide.detect(3).size(), 2u);
}

TEST(StableEdgeFilter, DropsACornerOneScanSeesAndKeepsTheRest) {
  // A wedge stands at (4, 0) in the third scan only (a person, a door
  // swinging): its corner is dropped there, the room's corners kept.
  const std::vector<Pose2> poses = drive(5, 0.4);
  std::vector<Shot> shots;
  for (const Pose2& p : poses) shots.push_back({room(), p, p});
  addWedge(shots[2].scene, {4, 0});
  const carmen::CarmenLog l = log(shots);
  StableEdgeOptions off_options;
  off_options.enabled = false;
  StableEdgeFilter off(l, "FLASER", detector(), off_options, 0);
  StableEdgeFilter on(l, "FLASER", detector(), check(2, 1, 0.3), 0);
  ASSERT_EQ(near(off.detect(2), poses[2], {4, 0}), 1);
  const std::vector<VerticalEdge> kept = on.detect(2);
  EXPECT_EQ(near(kept, poses[2], {4, 0}), 0);
  EXPECT_EQ(near(kept, poses[2], {6, -3}), 1);
}

TEST(StableEdgeFilter, TheLogsFirstAndLastScansAskAsManyNeighboursAsTheyHave) {
  // Five scans, window 2, 4 neighbours asked of: the middle scan has 4,
  // the first and last 2 (and are judged on them), the second 3.
  std::vector<Shot> shots;
  for (const Pose2& p : drive(5, 0.4)) shots.push_back({room(), p, p});
  // A wedge in the first scan only: no neighbour sees it.
  addWedge(shots[0].scene, {4, 0});
  const carmen::CarmenLog l = log(shots);
  StableEdgeFilter on(l, "FLASER", detector(), check(2, 4, 0.2), 0);
  for (std::size_t i = 0; i < l.scans.size(); ++i) {
    const std::vector<VerticalEdge> kept = on.detect(i);
    EXPECT_EQ(near(kept, shots[i].scanned, {6, -3}), 1) << i;
    EXPECT_EQ(near(kept, shots[i].scanned, {6, 3}), 1) << i;
  }
  EXPECT_EQ(near(on.detect(0), shots[0].scanned, {4, 0}), 0);
  // A log of one scan has nothing to check against: all kept.
  const carmen::CarmenLog one = log({shots[0]});
  StableEdgeFilter alone(one, "FLASER", detector(), check(2, 1, 0.2), 0);
  EXPECT_EQ(near(alone.detect(0), shots[0].scanned, {4, 0}), 1);
  // The core alone: min(min_scans, neighbours).
  VerticalEdge e;
  e.position = Point2(2, 0);
  EXPECT_EQ(keepStableEdges({e}, {{Point2(2.1, 0)}}, check(2, 3, 0.2)).size(), 1u);
  EXPECT_EQ(keepStableEdges({e}, {{Point2(2.1, 0)}, {}}, check(2, 3, 0.2)).size(), 0u);
  EXPECT_EQ(keepStableEdges({e}, {}, check(2, 3, 0.2)).size(), 1u);
}

TEST(StableEdgeFilter, RefusesBadOptionsAndALogWithoutOdometry) {
  std::vector<Shot> shots;
  for (const Pose2& p : drive(2, 0.4)) shots.push_back({room(), p, p});
  const carmen::CarmenLog l = log(shots);
  EXPECT_THROW(StableEdgeFilter(l, "FLASER", detector(), check(-1, 1, 0.2), 0), Error);
  EXPECT_THROW(StableEdgeFilter(l, "FLASER", detector(), check(2, -1, 0.2), 0), Error);
  EXPECT_THROW(StableEdgeFilter(l, "FLASER", detector(), check(2, 1, 0), 0), Error);
  EXPECT_THROW(StableEdgeFilter(l, "RLASER", detector(), check(2, 1, 0.2), 0), Error);
  StableEdgeFilter on(l, "FLASER", detector(), check(2, 1, 0.2), 0);
  EXPECT_THROW(on.detect(l.scans.size()), std::exception);
  const carmen::CarmenLog no_odometry =
      carmen::parseCarmenLog("FLASER 3 1 1 1 5 5 0 5 5 0 1.5 host 0\n", "none.log");
  try {
    StableEdgeFilter f(no_odometry, "FLASER", detector(), check(2, 1, 0.2), 0);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--nostable_edges"), std::string::npos) << e.what();
  }
}

// On a real log the check is FLAG's and the judge's alike: fewer detections
// in the recording and in the evaluation, and (measured on ACES, the log
// its constants were chosen on) a more precise detector.
TEST(StableEdgeFilter, OnTheAcesLogFlagAndTheJudgeSeeTheSameCheck) {
  HAMAL_REQUIRE_DATA(path, "carmen/aces.log");
  const carmen::CarmenLog l = carmen::readCarmenLog(path);
  CarmenFlagOptions c;
  c.edges.min_height = 0;
  EXPECT_FALSE(c.stable_edges.enabled);  // off unless asked (README, "Detector")
  c.stable_edges.enabled = true;
  const CarmenFlag on = prepareCarmenFlag(l, c);
  c.stable_edges.enabled = false;
  const CarmenFlag off = prepareCarmenFlag(l, c);
  EXPECT_TRUE(on.stable_edges.enabled);
  EXPECT_LT(on.detections, off.detections);
  const DetectorEvaluationOptions judge;
  const DetectorScore with = evaluateDetectorOnLog(l, on, c.edges, judge, nullptr, true);
  const DetectorScore without = evaluateDetectorOnLog(l, off, c.edges, judge, nullptr, true);
  EXPECT_LT(with.detections, without.detections);
  EXPECT_GT(with.precision(), without.precision() + 0.03);
  EXPECT_GE(with.recall(), 0.5);
}

}  // namespace
}  // namespace hamal::flag
