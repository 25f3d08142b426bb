// MOSS on a real laser log (thesis ch. 5 on a CARMEN log of apps/carmen/,
// e.g. the Radish Intel and ACES logs): the prior map and the localization
// trials cut from one recording, since a real log has no separate mapping
// run. The procedure, where the thesis is silent:
//
// - Poses: the log's key scans (carmen::keyScans) at their corrected poses
//   (the reference trajectory). A scan keeps
//   its returns up to `max_range` (in the robot frame, the laser's mounting
//   offset applied): the matcher's normals need a few returns within 25 cm,
//   which 1-degree beams give only up to a few metres.
// - The cut: the first `map_fraction` of the reference path's length is the
//   first traversal, the mapping run. Its kept poses, one every
//   `node_spacing` metres of path, are the map nodes with their real scans
//   (sec. 5.3.1: the map poses are the reference, as in the simulated
//   worlds).
// - Trials: after the cut, every maximal run of kept poses that stays within
//   `revisit_radius` of a map node (the stretches revisiting mapped areas) is
//   cut into trials of `trial_poses` consecutive poses, each starting at the
//   previous one's last pose; a shorter tail is dropped. Each trial starts
//   at its reference pose (the known start), which is not estimated and
//   not matched: trials that share it share no odometry step and no match,
//   and a run of R poses gives (R - 1) / (N - 1) trials, not R / N.
// - Training and test are disjoint in time: the earlier `train_fraction` of
//   the trials (in log order) train MOSS, the later ones test every method
//   (the first test trial may start at the last training one's last pose,
//   its known start).
// - The map is not the test run: its nodes and scans come from the mapping
//   run's time span, every trial's from after it (`map_until` < every
//   trial's first timestamp), so no scan is localised against itself.
// - Odometry (`odometry`): kLog (default) the log's own ODOM records, the
//   robot's wheel odometry: its pose interpolated at each scan's timestamp,
//   the step between consecutive trial poses being the relative pose of
//   those interpolated poses. Its noise, which the localizer weighs it
//   with, is estimated on the mapping run only (the reference steps against
//   the odometry's; estimateOdometryNoise) in the model of trials.h (sigma
//   per noise_distance driven, the variance growing with the step's
//   length). kSynthetic, an ablation: the reference relative pose plus the
//   simulated trials' noise (trials.h: 30 cm and 0.1 degree per 10 m
//   driven, thesis sec. 5.5), drawn from `seed`, weighed with that noise.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "apps/carmen/carmen_log.h"
#include "apps/moss/trials.h"

namespace hamal::moss {

// Where a log's trials take their odometry from (above).
enum class LogOdometry { kLog, kSynthetic };
// "log" or "synthetic" (anything else is an Error naming the choices).
LogOdometry parseLogOdometry(const std::string& name);
const char* toString(LogOdometry odometry);

struct CarmenTrialsOptions {
  carmen::KeyScanOptions scans;  // the poses: the log's key scans
  double max_range = 8.0;        // m
  double map_fraction = 0.3;     // of the path length
  double node_spacing = 1.0;     // m of path between map nodes
  double revisit_radius = 2.0;   // m
  int trial_poses = 10;          // N
  double train_fraction = 0.5;
  LogOdometry odometry = LogOdometry::kLog;
  // kSynthetic: the odometry noise drawn, per noise_distance driven (trials.h).
  double sigma_xy = 0.30, sigma_theta = 0.1 * 3.14159265358979323846 / 180;
  double noise_distance = 10.0;
  std::uint64_t seed = 1;
  void validate() const;  // throws hamal::Error naming the option
};

struct CarmenTrials {
  PriorMap map;
  std::vector<Trial> train, test;
  std::vector<Point2> map_points;          // the map nodes' returns in the world (for plots)
  std::size_t kept_poses = 0;              // poses kept from the log
  std::size_t cut_pose = 0;                // the first kept pose after the mapping run
  double cut_time = 0;                     // its timestamp, s
  double map_length = 0, path_length = 0;  // m
  std::size_t revisiting_poses = 0;        // after the cut, within revisit_radius of the map
  double train_until = 0, test_from = 0;   // timestamps, s: the last training, first test pose
  double map_until = 0;                    // timestamp of the mapping run's last scan, s
  // Per trial, the timestamps of its first and last pose, s.
  std::vector<std::pair<double, double>> train_spans, test_spans;
  // The odometry noise the localizer weighs the trials' odometry with: the
  // one estimated on the mapping run (kLog) or the one drawn (kSynthetic).
  double sigma_xy = 0, sigma_theta = 0;
  std::size_t odometry_steps = 0;  // mapping-run steps the estimate used (kLog)
};

// The robot's odometry pose at `time`: the log's ODOM records (sorted by
// time) interpolated linearly (the heading along the shorter arc). Throws
// hamal::Error "file: reason" for a log without ODOM records or a time
// outside their span by more than `slack` seconds (then the nearest).
class OdometryTrack {
 public:
  explicit OdometryTrack(const carmen::CarmenLog& log, double slack = 1.0);
  Pose2 at(double time) const;

 private:
  std::string file_;
  std::vector<std::pair<double, Pose2>> records_;
  double slack_;
};

// Maximum-likelihood sigmas (per noise_distance) of trials.h's noise model
// for the odometry steps `odometry` of the reference steps `reference`
// (each a relative pose): per step, the error's variance is sigma^2 * d /
// noise_distance, d the step's length (at least min_step, as the
// localizer weighs it).
void estimateOdometryNoise(const std::vector<Pose2>& reference, const std::vector<Pose2>& odometry,
                           double noise_distance, double min_step, double* sigma_xy,
                           double* sigma_theta);

// Throws hamal::Error "file: reason" for a log without scans of the tag, or
// one whose later part revisits the map too little for a training and a test
// trial.
CarmenTrials carmenTrials(const carmen::CarmenLog& log, const CarmenTrialsOptions& options);

// The options as "name value" lines (an experiment folder's config.txt).
std::string describe(const CarmenTrialsOptions& options);

}  // namespace hamal::moss
