// CarmenLog (apps/carmen/carmen_log.h) on small logs written here, and the
// Freiburg 079 log when ../shared/data/carmen holds it.
#include "apps/carmen/carmen_log.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ctime>
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
      "PARAM robot_front_laser_max 81.83 0 host 0\n"
      "PARAM robot_rear_laser_max 81.83 0 host 0\n"
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
  EXPECT_EQ(log.records.at("PARAM"), 4u);
  EXPECT_EQ(log.skipped.at("NEFF"), 2u);
  EXPECT_EQ(log.skipped.at("TRUEPOS"), 1u);
  EXPECT_EQ(log.odometry_echoes, 1u);
  ASSERT_EQ(log.odometry.size(), 2u);
  EXPECT_DOUBLE_EQ(log.odometry[1].pose.x, 0.1);
  EXPECT_DOUBLE_EQ(log.odometry[1].tv, 0.1);
  EXPECT_EQ(log.params.at("robot_use_laser"), "on");

  const LaserScan& f = log.scans[0];
  EXPECT_EQ(f.tag, "FLASER");
  EXPECT_EQ(f.line, 7);
  EXPECT_DOUBLE_EQ(f.pose.theta, 0.5);
  EXPECT_DOUBLE_EQ(f.timestamp, 1.0);
  EXPECT_DOUBLE_EQ(f.bearing(0), -kPi / 2);
  EXPECT_DOUBLE_EQ(f.bearing(2), kPi / 2);
  // The declared maximum range is the scanner's "no return".
  EXPECT_DOUBLE_EQ(f.max_range, 81.83);
  EXPECT_EQ(log.no_return.at("FLASER"), "declared by PARAM robot_front_laser_max (line 3)");
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
  bad.no_return_range = std::nan("");
  expectRefused(head, "no_return_range", "must be >= 0", bad);
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

// A gzip log cut short anywhere is refused, also where the bytes inflated so
// far end at a line boundary and would read as a whole (shorter) log.
TEST(CarmenLog, AGzipLogCutShortAnywhereIsRefused) {
  const std::string dir = ::testing::TempDir() + "carmen_gzip_cut";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string plain = dir + "/whole.log";
  {
    std::ofstream out(plain);
    for (int i = 0; i < 60; ++i)
      out << flaser({std::to_string(1 + i % 7), std::to_string(2 + i % 5), "81.83"},
                    std::to_string(0.1 * i) + " 0 0", std::to_string(i))
          << odom(std::to_string(0.1 * i + 0.05) + " 0 0", std::to_string(i + 0.5));
  }
  ASSERT_EQ(testing::runCommand("gzip -c " + plain + " > " + plain + ".gz").status, 0);
  std::ifstream in(plain + ".gz", std::ios::binary);
  const std::string gz((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(gz.size(), 200u);
  EXPECT_EQ(readCarmenLog(plain + ".gz").scans.size(), 60u);
  const std::string cut = dir + "/cut.log.gz";
  std::size_t read = 0, named = 0;
  for (std::size_t n = 1; n < gz.size(); n += 2) {
    std::ofstream(cut, std::ios::binary) << gz.substr(0, n);
    try {
      readCarmenLog(cut);
      ++read;
      ADD_FAILURE() << "the log cut after " << n << " of " << gz.size() << " bytes was read";
    } catch (const Error& e) {
      if (std::string(e.what()) ==
          cut +
              ": the gzip stream is cut short (unexpected end of file): a truncated file, not "
              "a whole log")
        ++named;
    }
  }
  EXPECT_EQ(read, 0u);
  EXPECT_GT(named, gz.size() / 4) << "most cuts are found by zlib, before the records are read";
  std::filesystem::remove_all(dir);
}

// No return: the range given, else the one the log declares, else the
// largest range many beams reach less 0.5%, which one absurd range does not
// move and which takes in a "no return" jittering below the maximum.
TEST(CarmenLog, NoReturnIsGivenDeclaredOrInferredWithoutBeingFooled) {
  // An infinite corridor: beams 0-2 hit the walls, 3-9 see nothing and read
  // 51.00-51.16 m; one beam of one scan reads an absurd 900 m.
  std::string text;
  for (int i = 0; i < 20; ++i) {
    std::vector<std::string> r = {"1.5", "2", "2.5"};
    for (int j = 3; j < 10; ++j) {
      std::ostringstream v;
      v << 51.0 + 0.01 * ((i * 7 + j * 3) % 17);
      r.push_back(v.str());
    }
    if (i == 7) r[9] = "900";
    text += flaser(r, std::to_string(0.5 * i) + " 0 0", std::to_string(i));
  }
  const CarmenLog log = parseCarmenLog(text, "corridor.log");
  for (const LaserScan& s : log.scans)
    for (std::size_t b = 0; b < s.ranges.size(); ++b)
      EXPECT_EQ(s.hit(b), b < 3) << "line " << s.line << " beam " << b << ": " << s.ranges[b];
  EXPECT_NEAR(log.scans[0].max_range, 51.16 * 0.995, 1e-9);
  EXPECT_EQ(log.no_return.at("FLASER"), "inferred: 2 of 200 beams reach 51.16 m, less 0.5%");

  // A range no laser measures is a damaged log, refused where it is.
  std::string absurd = text;
  absurd.replace(absurd.find(" 900 "), 5, " 1e308 ");
  EXPECT_EQ(refusal(absurd),
            "log:8: range 1e+308 is beyond 1000 m (the bound of a CARMEN log's values) (beam 9)");

  // The declared maximum, unless told not to; the given one before both.
  const std::string declared = "PARAM robot_front_laser_max 20.5 0 host 0\n" + text;
  EXPECT_DOUBLE_EQ(parseCarmenLog(declared, "log").scans[0].max_range, 20.5);
  CarmenReadOptions o;
  o.declared_max_range = false;
  EXPECT_NEAR(parseCarmenLog(declared, "log", o).scans[0].max_range, 51.16 * 0.995, 1e-9);
  o.no_return_range = 2.2;
  const CarmenLog given = parseCarmenLog(declared, "log", o);
  EXPECT_DOUBLE_EQ(given.scans[0].max_range, 2.2);
  EXPECT_EQ(given.no_return.at("FLASER"), "given (no_return_range)");
  EXPECT_TRUE(given.scans[0].hit(1));
  EXPECT_FALSE(given.scans[0].hit(2));
  // The rear laser has its own.
  const CarmenLog rear = parseCarmenLog(
      "PARAM robot_rear_laser_max 4 0 host 0\n" + text + "RLASER 2 3 4 0 0 0 0 0 0 30 host 30\n",
      "log");
  EXPECT_DOUBLE_EQ(rear.scansOf("RLASER")[0]->max_range, 4);
  EXPECT_NEAR(rear.scansOf("FLASER")[0]->max_range, 51.16 * 0.995, 1e-9);
}

// Values beyond the bounds of carmen_log.h, and a PARAM the reader uses
// that is not wholly a number, are refused by file, line and reason.
TEST(CarmenLog, ValuesBeyondTheirBoundsAreRefusedWithLineAndReason) {
  const std::string head = flaser({"1", "2", "3"}, "0 0 0", "1");
  const auto expectRefused = [](const std::string& text, const std::string& message) {
    EXPECT_EQ(refusal(text), message);
  };
  expectRefused(head + flaser({"1", "2", "3"}, "1e300 0 0", "2"),
                "log:2: pose x 1e+300 is beyond 1e+06 m (the bound of a CARMEN log's values)");
  expectRefused(head + "FLASER 3 1 2 3 0 0 0 0 -2e6 0 2 host 2\n",
                "log:2: odometry y -2e+06 is beyond 1e+06 m (the bound of a CARMEN log's values)");
  expectRefused(head + odom("0 0 1e300", "2"),
                "log:2: pose theta 1e+300 is beyond 1e+06 rad (the bound of a CARMEN log's "
                "values)");
  expectRefused(head + "PARAM robot_frontlaser_offset 1e308 0 host 0\n",
                "log:2: PARAM robot_frontlaser_offset 1e+308 m is outside [-10, 10] m");
  expectRefused("PARAM robot_rearlaser_offset 0.1junk 0 host 0\n" + head,
                "log:1: PARAM robot_rearlaser_offset is not a number: '0.1junk'");
  expectRefused("PARAM robot_front_laser_max 80.9x 0 host 0\n" + head,
                "log:1: PARAM robot_front_laser_max is not a number: '80.9x'");
  expectRefused("PARAM robot_front_laser_max 0 0 host 0\n" + head,
                "log:1: PARAM robot_front_laser_max must be > 0 m");
  expectRefused("PARAM robot_front_laser_max 1e308 0 host 0\n" + head,
                "log:1: PARAM robot_front_laser_max 1e+308 m is outside [0, 1000] m");
  // A declared maximum the reader is told not to use is not read.
  CarmenReadOptions o;
  o.declared_max_range = false;
  EXPECT_EQ(refusal("PARAM robot_front_laser_max 80.9x 0 host 0\n" + head, o), "");
  // ROBOTLASER1: its maximum range, and a laser 1e5 m from the robot.
  expectRefused("ROBOTLASER1 0 -1.5 3 1.5 2e3 0.01 0 3 1 10 2 0 7 6 0 5 6 0 0 0 0 0 0 1.3 h 1.3\n",
                "log:1: maximum range 2000 is beyond 1000 m (the bound of a CARMEN log's "
                "values)");
  expectRefused(
      "ROBOTLASER1 0 -1.5 3 1.5 10 0.01 0 3 1 10 2 0 1e5 6 0 5 6 0 0 0 0 0 0 1.3 h 1.3\n",
      "log:1: the laser's distance from the robot 99995 is beyond 10 m (the bound of a CARMEN "
      "log's values)");
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
  EXPECT_NE(r.output.find("FLASER: 2 scans, 3 beams from -90 deg every 90 deg, no return at 49.75 "
                          "m (2 of 6 beams), farthest return 2 m\n  no return: inferred: 2 of 6 "
                          "beams reach 50 m, less 0.5%"),
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

// hamal_log takes the reader's flags (carmen_log_flags.h, shared with
// hamal_flag and hamal_moss), --max_range as the old spelling of
// --no_return_range, and refuses a gzip log cut short.
TEST(HamalLog, TakesTheReaderFlagsAndRefusesACutGzipLog) {
  const std::string dir = ::testing::TempDir() + "hamal_log_flags";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string log = dir + "/back.log";  // FLASER steps 0.8 s back on line 3
  std::ofstream(log) << "PARAM robot_front_laser_max 40 0 host 0\n"
                     << flaser({"1", "50", "2"}, "1 0 0", "10")
                     << flaser({"1", "1", "50"}, "2 0 0", "9.2");
  const std::string exe = testing::buildPath("apps/hamal_log") + " --data " + log;
  const auto ok = testing::runCommand(exe);
  ASSERT_EQ(ok.status, 0) << ok.output;
  EXPECT_NE(ok.output.find("no return at 40 m (2 of 6 beams)"), std::string::npos) << ok.output;
  EXPECT_NE(ok.output.find("no return: declared by PARAM robot_front_laser_max (line 1)"),
            std::string::npos)
      << ok.output;
  const auto strict = testing::runCommand(exe + " --max_time_reversal 0.5");
  EXPECT_EQ(strict.status, 1);
  EXPECT_NE(strict.output.find(log + ":3: time goes backwards: FLASER at 9.2 s after 10 s on line "
                                     "2 (0.8 s back; tolerance 0.5 s, max_time_reversal)"),
            std::string::npos)
      << strict.output;
  const auto inferred = testing::runCommand(exe + " --declared_max_range=false");
  EXPECT_NE(inferred.output.find("no return at 49.75 m"), std::string::npos) << inferred.output;
  const auto given = testing::runCommand(exe + " --no_return_range 1.5");
  EXPECT_NE(given.output.find("no return at 1.5 m (3 of 6 beams)"), std::string::npos)
      << given.output;
  const auto old = testing::runCommand(exe + " --max_range 1.5");
  EXPECT_NE(old.output.find("no return at 1.5 m (3 of 6 beams)"), std::string::npos) << old.output;
  const auto bad = testing::runCommand(exe + " --no_return_range=-1");
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.output.find("--no_return_range -1: must be a number of metres >= 0"),
            std::string::npos)
      << bad.output;

  ASSERT_EQ(testing::runCommand("gzip -c " + log + " | head -c 60 > " + log + ".gz").status, 0);
  const auto cut = testing::runCommand(testing::buildPath("apps/hamal_log") + " --data " + log +
                                       ".gz --max_time_reversal 1");
  EXPECT_EQ(cut.status, 1) << cut.output;
  EXPECT_NE(cut.output.find(log + ".gz: the gzip stream is cut short"), std::string::npos)
      << cut.output;
  std::filesystem::remove_all(dir);
}

// The real Freiburg 079 log reads whole, and fast: the reader is meant for
// logs of this size in a loop of experiments.
TEST(CarmenLog, ReadsFreiburg079InUnderASecond) {
  HAMAL_REQUIRE_DATA(path, "carmen/freiburg-079.log");
  // Processor time, not wall time: the claim is about the reader's work,
  // and CI runs two tests at once on two cores shared with whatever else.
  const std::clock_t start = std::clock();
  const CarmenLog log = readCarmenLog(path);
  const double seconds = static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC;
  EXPECT_EQ(log.scans.size(), 4791u);
  EXPECT_EQ(log.scans[0].ranges.size(), 360u);
  // Its no return, 81.91 m, is beyond the maximum range it declares.
  EXPECT_DOUBLE_EQ(log.scans[0].max_range, 80.99);
  EXPECT_EQ(log.no_return.at("FLASER").rfind("declared by PARAM robot_front_laser_max", 0), 0u);
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
