// CarmenLog: a CARMEN robot log (the format of the Radish data sets the
// thesis' real-sensor experiments use: Intel Research Lab, ACES, Freiburg
// 079) read into laser scans, odometry and parameters, so that FLAG (thesis
// ch. 4) and MOSS (thesis ch. 5) can run on real range data.
//
// Records read (one a line, fields separated by blanks):
//   FLASER n r_1..r_n x y theta odom_x odom_y odom_theta timestamp host logger_timestamp
//   RLASER  (the same, rear laser)
//   ROBOTLASER1 type start fov resolution max_range accuracy remission_mode
//               n r_1..r_n m e_1..e_m laser_x laser_y laser_theta x y theta
//               tv rv forward_safety side_safety turn_axis timestamp host logger_timestamp
//   ODOM x y theta tv rv accel timestamp host logger_timestamp
//   PARAM name value timestamp host logger_timestamp
// Any other tag is skipped and counted per tag; '#' lines are comments.
//
// In a corrected log the scan's robot pose is the SLAM solution (the
// reference trajectory). FLASER/RLASER carry no field of view: their n
// beams span 180 degrees from -90 (the first beam to the right; RLASER
// faces backwards), and no return is written as the scanner's maximum (or
// near it). Each of the two lasers' no-return range is, first found first:
//   1. `no_return_range` when it is given (> 0);
//   2. the range the log declares, PARAM robot_front_laser_max (FLASER) or
//      robot_rear_laser_max (RLASER), unless `declared_max_range` is false
//      (Freiburg 80.99 m);
//   3. inferred: the largest range that at least k of the laser's beams
//      reach, k = max(2, 0.01% of its beams), less 0.5% (Intel 81.83 m and
//      ACES 50 m, so 81.42 m and 49.75 m): a few absurd ranges on top do not
//      move it, and a scanner whose "no return" jitters a little below its
//      maximum (51.00-51.16 m) has all of it read as no return.
// A range at or beyond it is no return (LaserScan::hit).
//
// The corrected Radish logs also hold, right after every scan, an ODOM
// record repeating the scan's corrected pose with an uninitialised
// timestamp; such an echo is counted (`odometry_echoes`), kept out of the
// odometry and out of the time checks.
//
// Bad input throws hamal::Error "file:line: reason": a truncated record or
// one whose range count disagrees with its fields, a field that is not a
// number, a non-finite or negative range or one beyond kMaxRange (no laser
// range finder measures 1 km; such a value is a damaged log, not "no
// return"), a non-finite pose or one beyond kMaxPose, a laser mounted
// farther than kMaxLaserOffset from the robot (PARAM
// robot_frontlaser_offset / robot_rearlaser_offset, ROBOTLASER1's laser
// pose), a PARAM the reader uses whose value is not wholly a number
// ("0.1junk") or a declared maximum range outside (0, kMaxRange], time
// going backwards within a stream (a laser, or the odometry) by more than
// `max_time_reversal` (the Intel log's clocks step back by up to 0.9 s), a
// line longer than 16 MB (/dev/zero, a binary file), a log with no laser
// scan ("file: reason"). Input may be gzip-compressed (zlib reads both);
// a gzip stream that ends before its end-of-stream mark (a log cut short,
// even at a line boundary) is refused ("file: reason").
#pragma once
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "core/pose2.h"

namespace hamal::carmen {

// Bounds of what a log may hold (beyond them it is damaged, not odd).
constexpr double kMaxRange = 1000;      // m, a range or a maximum range
constexpr double kMaxPose = 1e6;        // m (x, y) and rad (theta, unwrapped logs)
constexpr double kMaxLaserOffset = 10;  // m, the laser from the robot's centre

struct LaserScan {
  std::string tag;             // FLASER, RLASER or ROBOTLASER1
  double start_angle = 0;      // bearing of the first beam in the robot frame, rad
  double angular_step = 0;     // between beams, rad
  double max_range = 0;        // a range at or beyond this is no return, m
  std::vector<double> ranges;  // m
  Pose2 pose;                  // the robot's pose as logged (corrected: the reference)
  Pose2 odometry;              // the robot's odometry pose logged with the scan
  Pose2 laser_offset;          // the laser in the robot frame
  double timestamp = 0;
  int line = 0;

  double bearing(std::size_t i) const { return start_angle + angular_step * double(i); }
  bool hit(std::size_t i) const { return ranges[i] > 0 && ranges[i] < max_range; }
  // The returns as points in the robot frame, or through `robot` in the world.
  std::vector<Point2> points() const;
  std::vector<Point2> points(const Pose2& robot) const;
};

struct OdometryRecord {
  Pose2 pose;
  double tv = 0, rv = 0, accel = 0;
  double timestamp = 0;
  int line = 0;
};

// The odometry pose a fraction u of the way from record pose a to b (the
// time between them): x and y linearly, the heading along the shorter arc.
// FLAG and MOSS read the ODOM stream at scan times through it.
Pose2 interpolateOdometry(const Pose2& a, const Pose2& b, double u);

struct CarmenReadOptions {
  // Seconds a record's timestamp may fall behind the latest one of its
  // stream before it is refused as time going backwards.
  double max_time_reversal = 1.0;
  // FLASER/RLASER's no-return range, m; 0: the log's declared one, or the
  // inferred one (see the top of this file).
  double no_return_range = 0;
  // Use PARAM robot_front_laser_max / robot_rear_laser_max when the log has them.
  bool declared_max_range = true;
  // Refuse a log without any laser scan.
  bool require_laser = true;
  void validate() const;  // throws hamal::Error naming the option
};

struct CarmenLog {
  std::string file;
  std::vector<LaserScan> scans;  // in file order, every laser
  std::vector<OdometryRecord> odometry;
  std::map<std::string, std::string> params;   // the last value of each PARAM
  std::map<std::string, std::size_t> records;  // read, per tag
  std::map<std::string, std::size_t> skipped;  // tags not read, per tag
  std::size_t odometry_echoes = 0;             // ODOM repeating a scan's pose
  // FLASER/RLASER: how each laser's no-return range was found, e.g.
  // "declared by PARAM robot_front_laser_max (line 17)".
  std::map<std::string, std::string> no_return;
  std::size_t time_reversals = 0;    // within the tolerance
  double largest_time_reversal = 0;  // s

  // Scans of one tag, in order.
  std::vector<const LaserScan*> scansOf(const std::string& tag) const;
};

// Which scans a robot keeps as it drives (its key scans), for the
// applications that build a recording from a log (FLAG, MOSS).
struct KeyScanOptions {
  std::string tag = "FLASER";
  double step = 0.5;                                // m
  double turn = 15 * 3.14159265358979323846 / 180;  // rad
};

// The scans of options.tag a robot keeps: the first, then each once its
// corrected pose has moved `step` metres or turned `turn` radians from the
// last one kept. Throws hamal::Error "file: no TAG scans" for a log without
// scans of the tag.
std::vector<const LaserScan*> keyScans(const CarmenLog& log, const KeyScanOptions& options);

CarmenLog readCarmenLog(const std::string& path, const CarmenReadOptions& options = {});
// Reads `text` as the log `name` (for tests and other sources).
CarmenLog parseCarmenLog(const std::string& text, const std::string& name,
                         const CarmenReadOptions& options = {});

}  // namespace hamal::carmen
