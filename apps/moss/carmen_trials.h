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
// - Map and trials, one rule for every log (a log has no separate mapping
//   run, and one may revisit its early part too little to cut a prefix
//   off as the map): a pose within `revisit_radius` of a pose driven
//   `revisit_gap` metres of path or more before it revisits; the other
//   poses are first visits. The map nodes are first visits, one every
//   `node_spacing` metres, with their real scans (sec. 5.3.1: the map poses
//   are the reference, as in the simulated worlds), less any within 2
//   `revisit_radius` (beyond the localizer's match range from a predicted
//   pose) of a revisit less than `revisit_gap` of path away: a scan of the
//   trial's own pass, which it would be matched against.
// - Trials: every maximal run of revisits within `revisit_radius` of a map
//   node is cut into trials of `trial_poses` consecutive poses, each
//   starting at the previous one's last pose; a shorter tail is dropped.
//   Each trial starts at its reference pose (the known start), which is not
//   estimated and not matched: trials that share it share no odometry step
//   and no match, and a run of R poses gives (R - 1) / (N - 1) trials.
// - Training and test are disjoint in time: the earlier `train_fraction` of
//   the trials (in log order) train MOSS, the later ones test every method
//   (the first test trial may start at the last training one's last pose,
//   its known start).
// - The map is never the trial's own pass: every map node within the match
//   range of a trial pose was recorded `revisit_gap` metres of driving or
//   more before or after it, so no scan is localised against itself or a
//   neighbour of its own pass. Map nodes may be recorded after a trial (the
//   prior map is the building's, from its first visits).
// - Odometry (`odometry`): kLog (default) the log's own ODOM records, the
//   robot's wheel odometry: its pose interpolated at each scan's timestamp,
//   the step between consecutive trial poses being the relative pose of
//   those interpolated poses. Its noise, which the localizer weighs it
//   with, is estimated on the steps between first visits only (the reference steps against
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
  double revisit_gap = 20.0;     // m of path
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

// How the log's poses were divided by the rule above.
struct LogCut {
  std::size_t kept_poses = 0;         // poses kept from the log
  double path_length = 0;             // m
  std::size_t revisiting_poses = 0;   // within revisit_radius of a pose revisit_gap before
  std::size_t first_visit_poses = 0;  // the others: the map's ground
  std::size_t dropped_nodes = 0;      // first visits next to a revisit of their own pass
  std::size_t trial_poses = 0;        // revisits near a map node: the trials' poses
};

// When the training and the test trials were recorded.
struct TrialTimes {
  double train_until = 0, test_from = 0;  // timestamps, s: the last training, first test pose
  // Per trial, the timestamps of its first and last pose, s.
  std::vector<std::pair<double, double>> train_spans, test_spans;
};

// The odometry noise the localizer weighs the trials' odometry with: the
// one estimated on the first visits (kLog) or the one drawn (kSynthetic).
struct LogOdometryNoise {
  double sigma_xy = 0, sigma_theta = 0;
  std::size_t odometry_steps = 0;  // first-visit steps the estimate used (kLog)
};

struct CarmenTrials {
  PriorMap map;
  std::vector<Trial> train, test;
  std::vector<Point2> map_points;  // the map nodes' returns in the world (for plots)
  std::vector<double> node_times;  // per map node, its scan's timestamp, s
  LogCut cut;
  TrialTimes times;
  LogOdometryNoise noise;
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
