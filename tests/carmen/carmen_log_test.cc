// CarmenLog (apps/carmen/carmen_log.h) on small logs written here, and the
// Freiburg 079 log when ../shared/data/carmen holds it.
#include "apps/carmen/carmen_log.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "testing/command.h"
#include "testing/test_data.h"

namespace hamal::carmen {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A FLASER line with the given ranges at pose (x, y, theta) and time t.
std::string flaser(const std::vector<std::string>& ranges, const std::string& pose,
                   const std::string& t) {
  std::string line = "FLASER " + std::to_string(ranges.size());
  for (const std::string& r : ranges) line += " " + r;
  return line + " " + pose + " " + pose + " " + t + " host " + t + "\n";
}

std::string odom(const std::string& pose, const std::string& t) {
  return "ODOM " + pose + " 0.1 0 0 " + t + " host " + t + "\n";
}

// The message parseCarmenLog throws for `text`, or "" when it reads.
std::string refusal(const std::string& text, const CarmenReadOptions& options = {}) {
  try {
    parseCarmenLog(text, "log", options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(CarmenLog, ReadsEveryRecordKindAndCountsTheRest) {
  const std::string text =
      "# message formats defined: PARAM SYNC ODOM FLASER RLASER\n"
      "PARAM robot_frontlaser_offset 0.25 0 host 0\n"
      "PARAM robot_use_laser on nohost 0\n" +  // the older form
      odom("0 0 0", "0.5") +
      flaser({"1", "2", "81.83"}, "1 2 0.5", "1.0") +
      odom("1 2 0.5", "0") +  // the corrected logs' echo of the scan's pose
      "NEFF 15\n" + odom("0.1 0 0", "1.1") +
      "RLASER 2 3 4 1 2 0.5 1 2 0.5 1.2 host 1.2\n"
      "ROBOTLASER1 0 -1.5 3 1.5 10 0.01 0 3 1 10 2 1 7 7 6 0 5 6 0 0 0 0 0 0 1.3 host 1.3\n"
      "TRUEPOS 1 2 3 4 5 6 1.3 host 1.3\n"
      "NEFF 14\n";
  const CarmenLog log = parseCarmenLog(text, "mini.log");
  ASSERT_EQ(log.scans.size(), 3u);
  EXPECT_EQ(log.records.at("FLASER"), 1u);
  EXPECT_EQ(log.records.at("RLASER"), 1u);
  EXPECT_EQ(log.records.at("ROBOTLASER1"), 1u);
  EXPECT_EQ(log.records.at("ODOM"), 3u);
  EXPECT_EQ(log.records.at("PARAM"), 2u);
  EXPECT_EQ(log.skipped.at("NEFF"), 2u);
  EXPECT_EQ(log.skipped.at("TRUEPOS"), 1u);
  EXPECT_EQ(log.odometry_echoes, 1u);
  ASSERT_EQ(log.odometry.size(), 2u);
  EXPECT_DOUBLE_EQ(log.odometry[1].pose.x, 0.1);
  EXPECT_DOUBLE_EQ(log.odometry[1].tv, 0.1);
  EXPECT_EQ(log.params.at("robot_use_laser"), "on");

  const LaserScan& f = log.scans[0];
  EXPECT_EQ(f.tag, "FLASER");
  EXPECT_EQ(f.line, 5);
  EXPECT_DOUBLE_EQ(f.pose.theta, 0.5);
  EXPECT_DOUBLE_EQ(f.timestamp, 1.0);
  EXPECT_DOUBLE_EQ(f.bearing(0), -kPi / 2);
  EXPECT_DOUBLE_EQ(f.bearing(2), kPi / 2);
  // The largest FLASER/RLASER range is the scanner's "no return".
  EXPECT_DOUBLE_EQ(f.max_range, 81.83);
  EXPECT_TRUE(f.hit(1));
  EXPECT_FALSE(f.hit(2));
  // Beam 0 points to the right of a laser mounted 25 cm ahead: robot frame (0.25, -1).
  const std::vector<Point2> p = f.points();
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR(p[0].x(), 0.25, 1e-12);
  EXPECT_NEAR(p[0].y(), -1, 1e-12);
  const std::vector<Point2> w = f.points(f.pose);
  EXPECT_NEAR(w[1].x(), 1 + 2.25 * std::cos(0.5), 1e-12);  // beam 1 looks ahead

  // The rear laser faces backwards: its first beam points to the robot's left.
  const LaserScan& r = log.scans[1];
  EXPECT_EQ(r.tag, "RLASER");
  EXPECT_NEAR(r.points()[0].y(), 3, 1e-12);

  const LaserScan& rl = log.scans[2];
  EXPECT_DOUBLE_EQ(rl.start_angle, -1.5);
  EXPECT_DOUBLE_EQ(rl.angular_step, 1.5);
  EXPECT_DOUBLE_EQ(rl.max_range, 10);
  EXPECT_FALSE(rl.hit(1));                   // at the maximum range
  EXPECT_NEAR(rl.laser_offset.x, 2, 1e-12);  // laser at (7, 6), robot at (5, 6)
  EXPECT_EQ(log.scansOf("FLASER").size(), 1u);
}

// Each bad log is refused with "log:<line>: <reason>".
TEST(CarmenLog, RefusalsNameTheFileLineAndReason) {
  const std::string head = flaser({"1", "2", "3"}, "0 0 0", "1");
  const auto expectRefused = [](const std::string& text, const std::string& where,
                                const std::string& reason, const CarmenReadOptions& o = {}) {
    const std::string m = refusal(text, o);
    EXPECT_EQ(m.rfind(where, 0), 0u) << m;
    EXPECT_NE(m.find(reason), std::string::npos) << m;
  };
  // A line cut short (a log copied while it was written).
  std::string cut = flaser({"1", "2", "3"}, "0 0 0", "2");
  cut = cut.substr(0, 18);
  expectRefused(head + cut, "log:2: ", "truncated FLASER record: it declares 3 ranges");
  // A count that disagrees with the line, either way.
  expectRefused(head + "FLASER 4 1 2 3 0 0 0 0 0 0 2 host 2\n", "log:2: ", "truncated FLASER");
  expectRefused(head + "FLASER 2 1 2 3 0 0 0 0 0 0 2 host 2\n",
                "log:2: ", "it declares 2 ranges, so 11 fields must follow the count");
  expectRefused(head + flaser({"1", "nan", "3"}, "0 0 0", "2"), "log:2: ", "non-finite range");
  expectRefused(head + flaser({"1", "inf", "3"}, "0 0 0", "2"), "log:2: ", "non-finite range");
  expectRefused(head + flaser({"1", "-2", "3"}, "0 0 0", "2"), "log:2: ", "negative range");
  expectRefused(head + flaser({"1", "2", "x"}, "0 0 0", "2"), "log:2: ", "range is not a number");
  expectRefused(head + flaser({"1", "2", "3"}, "0 nan 0", "2"), "log:2: ", "non-finite pose y");
  expectRefused(head + odom("0 0 1e999", "2"), "log:2: ", "non-finite pose theta");
  expectRefused(head + "ODOM 1 2 3 0 0 0 2 host\n", "log:2: ", "truncated ODOM record");
  expectRefused(head +
                    "ROBOTLASER1 0 -1.5 3 1.5 10 0.01 0 3 1 2 3 0 1 2 0 1 2 0 0 0 0 0 "
                    "2 host 2\n",
                "log:2: ", "truncated ROBOTLASER1 record: it declares 3 ranges");
  expectRefused(head + "PARAM name\n", "log:2: ", "truncated PARAM record: no parameter value");
  expectRefused(head + "PARAM robot_frontlaser_offset front nohost 0\n",
                "log:2: ", "PARAM robot_frontlaser_offset is not a number: 'front'");
  // Time going backwards within a stream, by more than the tolerance.
  expectRefused(
      head + flaser({"1", "2", "3"}, "0 0 0", "5") + flaser({"1", "2", "3"}, "0 0 0", "3"),
      "log:3: ", "time goes backwards: FLASER at 3 s after 5 s on line 2");
  expectRefused(odom("0 0 0", "5") + odom("0 0 0", "3.9") + head,
                "log:2: ", "time goes backwards: ODOM");
  // No laser at all, and options out of range.
  expectRefused(odom("0 0 0", "1"), "log: ", "no laser scan");
  CarmenReadOptions bad;
  bad.max_time_reversal = -1;
  expectRefused(head, "max_time_reversal", "must be >= 0", bad);
  bad = {};
  bad.max_range = std::nan("");
  expectRefused(head, "max_range", "must be >= 0", bad);
}

// Clocks of different hosts jitter: a step back within the tolerance is
// counted, not refused, and each stream keeps its own clock.
TEST(CarmenLog, TimeJitterWithinTheToleranceIsCounted) {
  const std::string text = flaser({"1", "2"}, "0 0 0", "10") + odom("0 0 0", "2") +
                           flaser({"1", "2"}, "0 0 0", "9.2") + flaser({"1", "2"}, "0 0 0", "11");
  const CarmenLog log = parseCarmenLog(text, "log");
  EXPECT_EQ(log.time_reversals, 1u);
  EXPECT_NEAR(log.largest_time_reversal, 0.8, 1e-12);
  CarmenReadOptions strict;
  strict.max_time_reversal = 0.5;
  EXPECT_NE(refusal(text, strict).find("log:3: time goes backwards"), std::string::npos);
}

// The key scans: the first, then each once the robot moved `step` or
// turned `turn` from the last one kept (not from the previous scan).
TEST(CarmenLog, KeyScansKeepAScanOnceTheRobotMovedOrTurnedEnough) {
  const std::string text = flaser({"1"}, "0 0 0", "1") + flaser({"1"}, "0.3 0 0", "2") +
                           flaser({"1"}, "0.6 0 0", "3") + flaser({"1"}, "0.7 0 0", "4") +
                           flaser({"1"}, "0.7 0 0.3", "5") + flaser({"1"}, "0.7 0.1 0.3", "6");
  const CarmenLog log = parseCarmenLog(text, "log");
  KeyScanOptions o;
  o.step = 0.5;
  o.turn = 0.25;
  std::vector<double> kept;
  for (const LaserScan* s : keyScans(log, o)) kept.push_back(s->timestamp);
  EXPECT_EQ(kept, (std::vector<double>{1, 3, 5}));
  o.tag = "RLASER";
  try {
    keyScans(log, o);
    ADD_FAILURE() << "no RLASER scans, no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "log: no RLASER scans");
  }
}

// A gzip-compressed log reads as the plain one; a missing file says so.
TEST(CarmenLog, ReadsGzipAndPlainFilesAlike) {
  const std::string dir = ::testing::TempDir() + "carmen_gzip";
  std::filesystem::create_directories(dir);
  const std::string plain = dir + "/a.log";
  std::ofstream(plain) << flaser({"1", "2", "3"}, "1 2 3", "1") << odom("0 0 0", "2");
  ASSERT_EQ(testing::runCommand("gzip -c " + plain + " > " + plain + ".gz").status, 0);
  const CarmenLog a = readCarmenLog(plain), b = readCarmenLog(plain + ".gz");
  ASSERT_EQ(b.scans.size(), 1u);
  EXPECT_EQ(a.scans[0].ranges, b.scans[0].ranges);
  EXPECT_EQ(b.odometry.size(), 1u);
  // A file that never ends a line is refused before it fills the memory.
  try {
    readCarmenLog("/dev/zero");
    ADD_FAILURE() << "/dev/zero was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero:1: a line longer than 16 MB"),
              std::string::npos)
        << e.what();
  }
  try {
    readCarmenLog(dir + "/none.log");
    ADD_FAILURE() << "a missing file was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("none.log: cannot open"), std::string::npos) << e.what();
  }
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// hamal_log prints the summary and writes the cloud and the trajectory;
// on a bad log it names file, line and reason and writes nothing.
TEST(HamalLog, SummaryPointCloudAndTrajectory) {
  const std::string dir = ::testing::TempDir() + "hamal_log";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string log = dir + "/small.log";
  std::ofstream(log) << "PARAM robot_use_laser on 0 host 0\n"
                     << flaser({"1", "50", "2"}, "1 0 0", "1") << "NEFF 3\n"
                     << flaser({"1", "1", "50"}, "2 0 1.5707963267948966", "3");
  const std::string exe = testing::buildPath("apps/hamal_log");
  const auto r = testing::runCommand(exe + " --data " + log + " --output " + dir + "/out");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("records: FLASER 2 PARAM 1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("skipped: NEFF 1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("FLASER: 2 scans, 3 beams from -90 deg every 90 deg, no return at 50 m "
                          "(2 of 6 beams), farthest return 2 m"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("duration 2 s"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("reference path 1 m"), std::string::npos) << r.output;
  EXPECT_EQ(slurp(dir + "/out_trajectory.csv"),
            "scan,tag,timestamp,x,y,theta\n0,FLASER,1,1,0,0\n1,FLASER,3,2,0,1.57079633\n");
  // Scan 0 at (1, 0) facing +x: beam 0 hits (1, -1), beam 2 hits (1, 2).
  const std::string cloud = slurp(dir + "/out_points.csv");
  EXPECT_EQ(cloud.substr(0, cloud.find("\n1,")), "scan,x,y\n0,1,-1\n0,1,2");
  EXPECT_EQ(std::count(cloud.begin(), cloud.end(), '\n'), 5);

  const std::string bad = dir + "/bad.log";
  std::ofstream(bad) << flaser({"1", "2"}, "0 0 0", "1") << "FLASER 3 1 2\n";
  const auto b = testing::runCommand(exe + " --data " + bad + " --output " + dir + "/bad");
  EXPECT_EQ(b.status, 1) << b.output;
  EXPECT_NE(b.output.find("hamal_log: error: " + bad + ":2: truncated FLASER"), std::string::npos)
      << b.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad_points.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad_trajectory.csv"));
  const auto m = testing::runCommand(exe + " --data " + dir + "/none.log");
  EXPECT_EQ(m.status, 1);
  EXPECT_NE(m.output.find("none.log: cannot open the log"), std::string::npos) << m.output;
}

// The real Freiburg 079 log reads whole, and fast: the reader is meant for
// logs of this size in a loop of experiments.
TEST(CarmenLog, ReadsFreiburg079InUnderASecond) {
  HAMAL_REQUIRE_DATA(path, "carmen/freiburg-079.log");
  const auto start = std::chrono::steady_clock::now();
  const CarmenLog log = readCarmenLog(path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(log.scans.size(), 4791u);
  EXPECT_EQ(log.scans[0].ranges.size(), 360u);
  EXPECT_DOUBLE_EQ(log.scans[0].max_range, 81.91);
  EXPECT_EQ(log.odometry_echoes, 4791u);
  EXPECT_EQ(log.odometry.size(), 9725u - 4791u);
  EXPECT_EQ(log.records.at("PARAM"), 187u);
  EXPECT_EQ(log.skipped.at("NEFF"), 4791u);
#if defined(NDEBUG) && !defined(__SANITIZE_ADDRESS__)
  EXPECT_LT(seconds, 1.0);
#else
  std::cout << "read in " << seconds << " s (timed only in an optimised, unsanitised build)\n";
#endif
}

}  // namespace
}  // namespace hamal::carmen
