// The simulated robot and sensor of FLAG's evaluation (thesis sec. 4.3.2,
// 4.4.2): a robot driven along a floor plan's path at constant speed, its
// odometry, and its detections of vertical edges.
//
// Odometry: the true motion between two poses plus Gaussian noise whose
// sigma in x, y, theta is noise.odom_sigma_* x sqrt(d) for d metres
// travelled, so that after one metre it is the thesis' 10 cm, 5 cm and 0.1
// degree (a random walk's "per metre travelled").
//
// Detections, by `detector`:
// - kScan (the default): a 2.5D range scan ray cast in the plan's walls,
//   objects and people (range_scan.h) and the corners the vertical-edge
//   detector finds in it (vertical_edge_detector.h); the 1 m rule applies
//   to the heights the scan carries. Each detection is graded by what it
//   came from (corner_visibility.h's sourceOf).
// - kOracle (an ablation arm): every corner within `sensor_range`, in line of
//   sight (walls occlude) and not hidden by an object standing in front of
//   it; every static object's edge at least `min_height` tall; every person
//   walking at that time, with noise noise.range_sigma (thesis: 5 cm) and
//   noise.bearing_sigma (ours: 0.5 degree, the order of a VLP-16 corner
//   detector's angular error) drawn on the truth.
// - kOracleInView (an ablation arm): the oracle's detections less the
//   corners not in view as corner_visibility.h grades the scan detector
//   (a wall segment and a stub), i.e. a perfect detector of two-line
//   corners: what the scan detector could reach without silhouette edges.
// The noise the world draws (`noise`, and the scanner's range noise) and the
// sigmas the recording states, which FLAG's factors assume (`stated`), are
// separate options: an estimator may be wrong about its own errors. The true
// source of each detection is kept for grading; FLAG never reads it.
//
// Deterministic for a seed: the same plan, options and seed give the same
// recording, bit for bit; the odometry draws do not depend on the detector.
#pragma once
#include <cstdint>
#include <random>
#include <vector>

#include "apps/flag/floor_plan.h"
#include "apps/flag/range_scan.h"
#include "apps/flag/vertical_edge_detector.h"
#include "core/pose2.h"

namespace hamal::flag {

struct SimulatorOptions {
  // The odometry's sigmas (a random walk's, per sqrt of the metres
  // travelled) and a detection's; the thesis' values (sec. 4.4.2; bearing:
  // ours).
  struct Sigmas {
    double odom_sigma_x = 0.10;                                    // m per sqrt(m)
    double odom_sigma_y = 0.05;                                    // m per sqrt(m)
    double odom_sigma_theta = 0.1 * 3.14159265358979323846 / 180;  // rad per sqrt(m)
    double range_sigma = 0.05;                                     // m
    double bearing_sigma = 0.5 * 3.14159265358979323846 / 180;     // rad
  };
  double step = 0.5;   // metres between poses
  double speed = 2.0;  // m/s (thesis: about 2 m/s)
  // The noise the world draws (the scanner's range noise: scanner.range_sigma).
  Sigmas noise;
  // The sigmas the recording states (FLAG's odometry and range-bearing
  // factors).
  Sigmas stated;
  double sensor_range = 10.0;  // m
  double min_height = 1.0;     // m: lower edges are not detected
  enum Detector { kScan, kOracle, kOracleInView } detector = kScan;
  RangeScannerOptions scanner;        // kScan: its max_range is sensor_range
  VerticalEdgeDetectorOptions edges;  // kScan: its min_height is min_height
  double match_radius = 0.30;         // m: a detection this close to a corner came from it
  std::uint64_t seed = 1;
  // Throws hamal::Error for a negative noise, a non-positive stated sigma, step,
  // speed or range, or scanner or detector options out of range.
  void validate() const;
};

// What produced a detection (ground truth, for grading only).
struct Source {
  // kNone: a detection that came from nothing in the world (a detector's false alarm).
  enum Kind { kCorner, kObject, kPerson, kNone } kind = kCorner;
  std::uint64_t id = 0;  // corner id, object index or person index
};

struct Detection {
  double range = 0, bearing = 0;
  double range_sigma = 0, bearing_sigma = 0;  // the noise it states (FLAG's factors)
  Source source;
  // The directions its walls leave it in, robot frame (rad); empty: not
  // known (association then goes by position alone).
  std::vector<double> walls;
};

// One pose of the recording. odometry is this pose seen from the previous
// one (identity for pose 0).
struct RecordedStep {
  double time = 0;
  Pose2 truth;
  Pose2 odometry;
  double distance = 0;  // metres travelled since the previous pose
  // A dataset's own odometry sigmas (x, y, theta); zero: the recording's
  // per-metre model below.
  Eigen::Vector3d odometry_sigma = Eigen::Vector3d::Zero();
  std::vector<Detection> detections;
};

struct Recording {
  std::vector<RecordedStep> steps;
  // The odometry noise the recording states (FLAG's odometry factors).
  double odom_sigma_x = 0, odom_sigma_y = 0, odom_sigma_theta = 0;
};

// Poses every `step` metres along the path, heading along the path.
std::vector<Pose2> samplePath(const std::vector<Point2>& path, double step);

// The oracle: noise-free detections of the true features from `pose` at `time`.
std::vector<Detection> detect(const FloorPlan& plan, const Pose2& pose, double time,
                              const SimulatorOptions& options);

// The scan detector: the corners found in a scan taken at `pose`; `rng`
// draws the scan's noise (nullptr: exact ranges).
std::vector<Detection> detectInScan(const FloorPlan& plan, const Pose2& pose, double time,
                                    const SimulatorOptions& options, std::mt19937_64* rng);

Recording simulate(const FloorPlan& plan, const SimulatorOptions& options);

// Odometry noise of one step of d metres (sigmas in x, y, theta).
Eigen::Vector3d odometrySigmas(double ox, double oy, double otheta, double d);

}  // namespace hamal::flag
