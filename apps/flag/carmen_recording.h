// FLAG on a real laser log (a CARMEN log of apps/carmen/, e.g. the Radish
// Intel and ACES logs): the labelled floor plan and the recording FLAG
// localizes in, made by a documented procedure since a real log has no
// labelled plan.
//
// - Poses: the log's key scans (carmen::keyScans) at their corrected poses,
//   the reference trajectory.
// - Detections: the vertical-edge detector (vertical_edge_detector.h) on
//   each kept real scan, in the robot frame (the laser's mounting offset
//   applied), stated with the thesis' range and bearing sigmas. A 2D log
//   carries no heights: the 1 m rule cannot apply. With `stable_edges`
//   enabled only the corners the neighbouring scans see again
//   (stable_edge_filter.h), here and in the detector's evaluation alike.
// - Landmarks, from the map part's scans only (`landmarks.map_corners`, default):
//   the corners of the map's walls, extracted from the scans' line
//   segments at their reference poses (map_corners.h), independently of
//   the corner detector. Without `landmarks.map_corners`: every map-part detection
//   placed in the world, clustered greedily (a detection joins the first
//   cluster whose mean is within `landmarks.cluster_radius`); a cluster seen
//   `landmarks.min_sightings` times is a landmark at its mean. A detection's source
//   (for grading only) is the landmark nearest it in the world (through its
//   reference pose) within `landmarks.cluster_radius`, else nothing. The labels are
//   the landmarks moved by N(0, label_sigma^2 I) (thesis sec. 4.4.2: a hand
//   labelling of a 0.1 m/pixel plan).
// - Odometry (`odometry.source`): kLog (default): the robot's own odometry, the
//   log's ODOM stream (the FLASER line's odom fields repeat its corrected
//   pose in the Radish logs, so they are not used): the odometry pose at a
//   scan is interpolated at its timestamp between the ODOM records around
//   its line in the file, walked on or back to the scan's time (the nearer
//   of the two where the clocks disagree, as Intel's step back), and a step is the motion between
//   two kept scans' odometry poses. Its noise model is calibrated on the map part only (below): the
//   odometry clock's latency (the offset whose steps agree best with the reference), and
//   OdometryModel fitted to the steps' errors against the reference, times the
//   odometry_calibration.h scale at the longest coast's window (`odometry.scale`; the scale at the
//   longest window, not the largest over windows as Victoria Park's: the
//   Radish logs' ODOM errors shrink with the window, a jitter rather than
//   a drift). kSynthetic (an ablation arm):
//   the motion between consecutive reference poses plus noise drawn with
//   the world's per-metre sigmas, stated as `odometry.stated`. Either way a step's
//   sigmas are those of max(d, `odometry.min_distance`) metres, so turning in place
//   is not exact.
// - The split (`map_fraction` > 0, default 0.5): the key scans whose
//   timestamp lies in the first `map_fraction` of the log's time span make
//   the map (walls, corners, labels) and calibrate the odometry; FLAG is
//   evaluated on the others, from a start the seed picks among the first
//   half of them (so a seed chooses a real start, not only noise), to the
//   end of the log: seedStart (below), so that seeds 1..n start from n
//   different scans while n <= the candidates, and a seed's start does not
//   depend on the other seeds run with it. The two sets are disjoint.
//   map_fraction 0: the whole log makes the map and is evaluated from its
//   first scan (the circular protocol, kept as an ablation).
#pragma once
#include <cstdint>
#include <vector>

#include "apps/carmen/carmen_log.h"
#include "apps/flag/flag_localizer.h"
#include "apps/flag/map_corners.h"
#include "apps/flag/odometry_calibration.h"
#include "apps/flag/simulator.h"
#include "apps/flag/stable_edge_filter.h"

namespace hamal::flag {

// The noise of a log's odometry step (x, y, theta in the step's frame):
// sigma_c^2 = per_metre_c^2 max(d, min_distance), plus per_radian^2 |turn|
// in theta (a clock offset between laser and odometry shows in turns).
struct OdometryModel {
  Eigen::Vector3d per_metre = Eigen::Vector3d::Zero();
  double per_radian = 0;
  Eigen::Vector3d sigma(const Pose2& step, double min_distance) const;
};
struct CarmenFlagOptions {
  carmen::KeyScanOptions scans;  // the poses: the log's key scans

  // The landmarks and their labels.
  struct Landmarks {
    // true: the landmarks are the corners of the map's walls (map_corners.h);
    // false: the clusters of the detector's corners (`cluster_radius`,
    // `min_sightings`).
    bool map_corners = true;
    MapCornerOptions walls;
    double cluster_radius = 0.30;  // m
    int min_sightings = 5;
    double label_sigma = 0.10;  // m
  };
  Landmarks landmarks;

  double stated_range_sigma = 0.05;
  double stated_bearing_sigma = 0.5 * 3.14159265358979323846 / 180;
  VerticalEdgeDetectorOptions edges = realLogDetectorOptions();
  // map_corners: the line extraction (step 2) the map's walls are made of,
  // apart from the detector's `edges` so that tuning the detector leaves
  // its labelled set (detector_evaluation.h) as it is.
  VerticalEdgeDetectorOptions map_segments = realLogDetectorOptions();
  // The multi-scan stability check on every key scan's corners (the
  // log's odometry at the calibrated latency moves the neighbours' corners).
  StableEdgeOptions stable_edges;
  // An ablation: each evaluated detection that has a source (a map corner
  // within cluster_radius) made exact, at the range and bearing its corner
  // has from the scan's reference pose; the others stay as detected. FLAG's
  // error is then that of its labels, odometry and estimator alone, without
  // the detector's error against the map's corners.
  bool exact_detections = false;

  enum class Odometry { kLog, kSynthetic };
  // Odometry sigmas per metre: x, y (m) and theta (rad).
  struct OdometrySigmas {
    double x = 0.10, y = 0.05;
    double theta = 0.1 * 3.14159265358979323846 / 180;
  };
  // Where the odometry's steps come from and the noise they are stated with.
  struct OdometryOptions {
    Odometry source = Odometry::kLog;
    double min_distance = 0.1;  // m
    // The world's odometry noise and what the recording states, per metre.
    OdometrySigmas world, stated;
    // kLog: fit the odometry's model on the map part (false: state the
    // `stated` sigmas and scale 1).
    bool calibrate = true;
    // kLog, calibrating: model the odometry's error as a jitter on each pose
    // plus a drift (odometry_calibration.h's odometryJitter and driftScale;
    // FlagOptions::odometry.jitter_*), not as a drift alone. The Radish
    // logs' ODOM is read at the laser's time through clocks whose delay
    // varies: an error that comes and goes while turning, which a drift model
    // (per-step sigmas that add up) mistakes for a large heading drift.
    bool fit_jitter = true;
    // kLog, calibrating: the odometry's clock offset is fitted over
    // [-max_latency, max_latency] s (0: none).
    double max_latency = 0.5;
  };
  OdometryOptions odometry;

  double map_fraction = 0.5;  // [0, 1)
  std::uint64_t seed = 1;
  void validate() const;  // throws hamal::Error naming the option
};

struct CarmenFlag {
  Recording recording;  // truth = the reference poses
  std::vector<LandmarkLabel> labels;
  std::vector<Point2> landmarks;             // the clusters' means, by id
  std::size_t detections = 0, clusters = 0;  // clusters: or walls, with map_corners
  // Indices into log.scans.
  struct Scans {
    // The scans that made the map (and calibrated the odometry), and the
    // evaluated ones (the recording's poses, in order).
    std::vector<std::size_t> map, evaluated;
    // All key scans after the map part (evaluated is a suffix of these,
    // from the seed's start): the detector's labelled set
    // (detector_evaluation.h). With map_fraction 0: every key scan.
    std::vector<std::size_t> held_out;
  };
  Scans scans;
  std::vector<MapWall> walls;  // map_corners: the map's walls
  // map_corners: the walls and corners the same procedure makes from every
  // key scan of the log, map part and held-out alike: a labelled set for
  // the detector (detector_evaluation.h) that covers what the held-out
  // scans see, where the map part's does not (never FLAG's landmarks).
  std::vector<MapWall> log_walls;
  std::vector<Point2> log_corners;
  // The stability check the detections passed; the detector's evaluation
  // (detector_evaluation.h) applies the same, so its figures are FLAG's.
  StableEdgeOptions stable_edges;
  // The odometry as the recording states it and FLAG should take it.
  struct Odometry {
    // kLog: the calibrated model the recording states, the latency of the
    // odometry's clock and the scale FLAG's odometry factors and gate should
    // use; kSynthetic: the stated sigmas per metre, 0 and 1.
    OdometryModel model;
    double latency = 0;  // s, kLog: fitted on the map part
    double scale = 1.0;
    // kLog, calibrating with fit_jitter: the jitter, and scale is then the
    // drift's scale (driftScale at the longest coast's window).
    OdometryJitter jitter;
    std::vector<OdometryConsistency> consistency;  // kLog: per window, on the map part
  };
  Odometry odometry;
};

// The robot's odometry pose at `scan` from the log's ODOM stream (see
// above), at the scan's timestamp + `latency`. Throws hamal::Error "file:
// no ODOM records" for a log without.
Pose2 logOdometryAt(const carmen::CarmenLog& log, const carmen::LaserScan& scan,
                    double latency = 0);

// The model fitted to `steps` (odometry and reference increment, the
// odometry's length), e the odometry's error in the step's frame: x and y
// the mean of e^2 / max(d, min_distance); theta e^2 = a max(d, min_distance)
// + b |turn| by least squares (b >= 0, a >= 0). Throws hamal::Error for no
// steps.
struct OdometryStepSample {
  Pose2 odometry, reference;
  double distance = 0;
};
OdometryModel fitOdometryModel(const std::vector<OdometryStepSample>& steps, double min_distance);

// The start seed `seed` takes among `choices` candidate starts (0-based):
// entry (seed - 1) mod choices of one fixed pseudo-random permutation of
// 0..choices-1. A function of (seed, choices) alone, so a seed run alone
// starts where it does among others; seeds 1..choices take every start once
// (drawn independently per seed, ten seeds among ~100 starts would share
// one about a third of the time). Throws hamal::Error for choices 0.
std::size_t seedStart(std::uint64_t seed, std::size_t choices);

// The scan as the detector reads it (no heights).
RangeScan rangeScanOf(const carmen::LaserScan& scan);

// Throws hamal::Error for a log without scans of the tag or without a landmark.
CarmenFlag prepareCarmenFlag(const carmen::CarmenLog& log, const CarmenFlagOptions& options);

}  // namespace hamal::flag
