// FLAG on a CARMEN log (apps/flag/carmen_recording.h): a log written here
// from scans ray cast in a room with known corners, read back, turned into
// landmarks and a recording, and localized in.
#include "apps/flag/carmen_recording.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "apps/flag/flag_run.h"
#include "backends/builtins.h"
#include "core/error.h"
#include "core/registry.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal::flag {
namespace {

// A 12 x 8 m room with two niches; the robot drives a loop inside it.
FloorPlan room() {
  std::istringstream in(
      "WALL 0 0 5 0\nWALL 5 0 5 -1\nWALL 5 -1 7 -1\nWALL 7 -1 7 0\nWALL 7 0 12 0\n"
      "WALL 12 0 12 8\nWALL 12 8 4 8\nWALL 4 8 4 9\nWALL 4 9 2 9\nWALL 2 9 2 8\n"
      "WALL 2 8 0 8\nWALL 0 8 0 0\n"
      "CORNER 0 0 0\nCORNER 1 5 0\nCORNER 2 5 -1\nCORNER 3 7 -1\nCORNER 4 7 0\n"
      "CORNER 5 12 0\nCORNER 6 12 8\nCORNER 7 4 8\nCORNER 8 4 9\nCORNER 9 2 9\n"
      "CORNER 10 2 8\nCORNER 11 0 8\n"
      "PATH 2 2\nPATH 10 2\nPATH 10 6\nPATH 2 6\nPATH 2 2\n");
  return readFloorPlan(in, "room", 0.0, 1);
}

// FLASER lines (180 beams over 180 degrees, 1.5 cm noise) every 0.25 m of
// the room's path, each followed by the corrected logs' echoed ODOM.
std::string log(const FloorPlan& plan) {
  RangeScannerOptions s;
  s.field_of_view = 3.14159265358979323846;
  s.angular_step = s.field_of_view / 179;
  s.max_range = 30;
  std::mt19937_64 rng(7);
  std::ostringstream out;
  out << std::setprecision(10) << "PARAM robot_frontlaser_offset 0.0 nohost 0\n";
  double t = 0;
  for (const Pose2& p : samplePath(plan.path, 0.25)) {
    const RangeScan scan = castRangeScan(plan, p, 0, s, &rng);
    out << "FLASER " << scan.ranges.size();
    for (double r : scan.ranges) out << " " << (r < 30 ? r : 81.83);
    const std::string pose =
        " " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.theta);
    out << pose << pose << ' ' << t << " host " << t << "\n";
    out << "ODOM" << pose << " 0 0 0 0 host 0\n";
    t += 0.5;
  }
  return out.str();
}

TEST(CarmenRecording, LandmarksAreTheRoomsCornersAndFlagLocalizes) {
  const FloorPlan plan = room();
  const carmen::CarmenLog l = carmen::parseCarmenLog(log(plan), "room.log");
  ASSERT_EQ(l.odometry_echoes, l.scans.size());
  CarmenFlagOptions o;
  o.scans.step = 0.25;
  const CarmenFlag cf = prepareCarmenFlag(l, o);
  ASSERT_GE(cf.landmarks.size(), 8u);
  // Every landmark is one of the room's corners (seen from inside: its
  // walls and niches), within 5 cm.
  for (const Point2& lm : cf.landmarks) {
    double nearest = 1e9;
    for (const Corner& c : plan.corners) nearest = std::min(nearest, (c.truth - lm).norm());
    EXPECT_LT(nearest, 0.05) << lm.transpose();
  }
  EXPECT_GT(cf.detections, cf.recording.steps.size());
  Registry registry;
  registerBuiltins(registry);
  const FlagRun r = runFlag(cf.labels, cf.recording, FlagOptions(), registry);
  ASSERT_TRUE(r.ok) << r.status;
  EXPECT_GE(r.stats.precision(), 0.95);
  EXPECT_LT(r.flag.position, r.odometry.position);
  EXPECT_LT(r.flag.position, 0.15);

  // The same odometry whatever the landmarks: the detections' clusters
  // instead of the map's corners, fewer of them.
  CarmenFlagOptions fewer = o;
  fewer.map_corners = false;
  const CarmenFlag clusters = prepareCarmenFlag(l, fewer);
  fewer.min_sightings = 40;
  const CarmenFlag cf2 = prepareCarmenFlag(l, fewer);
  EXPECT_LT(cf2.landmarks.size(), clusters.landmarks.size());
  EXPECT_EQ(cf2.recording.steps[5].odometry.x, cf.recording.steps[5].odometry.x);
  fewer.min_sightings = 100000;
  EXPECT_THROW(prepareCarmenFlag(l, fewer), Error);
  fewer.cluster_radius = 0;
  EXPECT_THROW(prepareCarmenFlag(l, fewer), Error);
}

// FLAG on a real log as `hamal_flag carmen` runs it (seed 1).
FlagRun flagOn(const std::string& path, bool map_corners, std::size_t* labels) {
  CarmenFlagOptions o;
  o.map_corners = map_corners;
  o.edges.min_height = 0;
  const CarmenFlag cf = prepareCarmenFlag(carmen::readCarmenLog(path), o);
  *labels = cf.labels.size();
  Registry registry;
  registerBuiltins(registry);
  return runFlag(cf.labels, cf.recording, FlagOptions(), registry);
}

// ACES with landmarks at the map walls' corners: FLAG keeps a real robot
// well within dead reckoning's error, with few wrong associations.
TEST(CarmenRecording, FlagOnTheAcesLog) {
  HAMAL_REQUIRE_DATA(path, "carmen/aces.log");
  std::size_t labels = 0;
  const FlagRun r = flagOn(path, true, &labels);
  EXPECT_GT(labels, 15u);
  ASSERT_TRUE(r.ok) << r.status;
  EXPECT_GE(r.stats.precision(), 0.9);
  EXPECT_LT(r.flag.position, 0.8 * r.odometry.position);
}

// The Intel Research Lab log with the detections' clusters as landmarks
// (`--nomap_corners`): the same. (With the map walls' corners it does not:
// apps/flag/README.md.)
TEST(CarmenRecording, FlagOnTheIntelLogWithClusteredLandmarks) {
  HAMAL_REQUIRE_DATA(path, "carmen/intel.log");
  std::size_t labels = 0;
  const FlagRun r = flagOn(path, false, &labels);
  EXPECT_GT(labels, 50u);
  ASSERT_TRUE(r.ok) << r.status;
  EXPECT_GE(r.stats.precision(), 0.9);
  EXPECT_LT(r.flag.position, 0.5 * r.odometry.position);
}

TEST(CarmenRecording, HamalFlagCarmenNeedsALog) {
  const auto r = testing::runCommand(testing::buildPath("apps/hamal_flag") + " carmen");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.output.find("carmen: give the log with --data"), std::string::npos) << r.output;
}

// hamal_flag carmen reads the log with the reader's flags
// (apps/carmen/carmen_log_flags.h) and refuses a gzip log cut short.
TEST(CarmenRecording, HamalFlagCarmenTakesTheReaderFlags) {
  const std::string dir = ::testing::TempDir() + "/flag_reader_" + std::to_string(getpid());
  std::filesystem::create_directories(dir);
  const std::string log = dir + "/back.log";  // FLASER steps 0.8 s back on line 2
  std::ofstream(log) << "FLASER 3 1 2 50 0 0 0 0 0 0 10 host 10\n"
                     << "FLASER 3 1 2 50 0.1 0 0 0.1 0 0 9.2 host 9.2\n";
  const std::string exe = testing::buildPath("apps/hamal_flag") + " carmen --data ";
  const auto strict = testing::runCommand(exe + log + " --max_time_reversal 0.5");
  EXPECT_EQ(strict.status, 1);
  EXPECT_NE(strict.output.find(log + ":2: time goes backwards: FLASER at 9.2 s after 10 s on line "
                                     "1 (0.8 s back; tolerance 0.5 s, max_time_reversal)"),
            std::string::npos)
      << strict.output;
  const auto bad = testing::runCommand(exe + log + " --no_return_range=-1");
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.output.find("--no_return_range -1: must be a number of metres >= 0"),
            std::string::npos)
      << bad.output;
  ASSERT_EQ(testing::runCommand("gzip -c " + log + " | head -c 50 > " + log + ".gz").status, 0);
  const auto cut = testing::runCommand(exe + log + ".gz --declared_max_range=false");
  EXPECT_EQ(cut.status, 1);
  EXPECT_NE(cut.output.find(log + ".gz: the gzip stream is cut short"), std::string::npos)
      << cut.output;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hamal::flag
