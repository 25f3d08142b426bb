// hamal_flag: FLAG, global localization in a floor plan (thesis ch. 4), from
// the command line: write a built-in world, run one localization and print
// its errors, or run the trials of one experiment of sec. 4.4 as CSV rows
// (scripts/flag.sh drives those in parallel and draws the figures).
#include <gflags/gflags.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

#include "apps/bench/percentiles.h"
#include "apps/carmen/carmen_log.h"
#include "apps/carmen/carmen_log_flags.h"
#include "apps/common/cli.h"
#include "apps/flag/builtin_worlds.h"
#include "apps/flag/carmen_recording.h"
#include "apps/flag/corner_visibility.h"
#include "apps/flag/data_association_experiments.h"
#include "apps/flag/detector_evaluation.h"
#include "apps/flag/flag_options.h"
#include "apps/flag/flag_run.h"
#include "apps/flag/odometry_calibration.h"
#include "apps/flag/simulator.h"
#include "apps/flag/victoria_park.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/output_file.h"

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180;
}

// The world and the simulated robot.
DEFINE_string(world, "office", "built-in world (office, corridor) or a floor-plan file");
DEFINE_uint64(seed, 1, "seed of the labels and the simulation (trials: the first seed)");
DEFINE_double(label_sigma, 0.10, "label noise of corners without a label, m (thesis 10 cm)");
DEFINE_double(step, 0.5, "metres between poses");
DEFINE_double(speed, 2.0, "robot speed, m/s (thesis about 2 m/s)");
// The noise the factors assume (the recording's stated sigmas)...
DEFINE_double(odom_sigma_x, 0.10,
              "odometry sigma in x per metre travelled the factors assume, m (thesis 10 cm)");
DEFINE_double(odom_sigma_y, 0.05,
              "odometry sigma in y per metre travelled the factors assume, m (thesis 5 cm)");
DEFINE_double(odom_sigma_theta_deg, 0.1,
              "odometry heading sigma per metre the factors assume, degrees (thesis 0.1)");
DEFINE_double(range_sigma, 0.05, "range sigma the factors assume, m (thesis 5 cm)");
DEFINE_double(bearing_sigma_deg, 0.5, "bearing sigma the factors assume, degrees (ours)");
// ... and the noise the simulated world draws.
DEFINE_double(world_odom_sigma_x, 0.10, "odometry noise drawn in x per metre, m");
DEFINE_double(world_odom_sigma_y, 0.05, "odometry noise drawn in y per metre, m");
DEFINE_double(world_odom_sigma_theta_deg, 0.1, "odometry heading noise drawn per metre, degrees");
DEFINE_double(world_range_sigma, 0.05, "oracle detector: range noise drawn, m");
DEFINE_double(world_bearing_sigma_deg, 0.5, "oracle detector: bearing noise drawn, degrees");
DEFINE_double(scan_range_sigma, 0.015, "scan detector: range noise drawn per beam, m");
DEFINE_double(scan_step_deg, 0.5, "scan detector: the scanner's angular step, degrees");
DEFINE_double(sensor_range, 10.0, "detector range, m");
DEFINE_double(min_height, 1.0,
              "the detector discards vertical edges lower than this, m (thesis 1 m)");
// The detector (vertical_edge_detector.h).
DEFINE_string(detector, "scan",
              "scan: corners found in ray-cast 2.5D scans; oracle: the true corners plus noise "
              "(an ablation arm); oracle_in_view: the oracle without the corners seen with one "
              "wall only (the two-line corners' reach)");
DEFINE_double(fit_tolerance, 0.05, "scan detector: a point's largest distance from its line, m");
DEFINE_int32(min_segment_points, 6, "scan detector: fewest points of a wall segment");
DEFINE_double(min_segment_length, 0.30, "scan detector: shortest wall segment, m");
DEFINE_double(breakpoint_lambda_deg, 5,
              "scan detector: a surface seen at less than this to the beam breaks the scan, deg "
              "(carmen: 10 unless given)");
DEFINE_int32(min_stub_points, 3,
             "scan detector: fewest points of a corner's second wall (carmen: "
             "--min_segment_points unless given)");
DEFINE_double(min_stub_length, 0.15,
              "scan detector: shortest second wall of a corner, m (carmen: "
              "--min_segment_length unless given)");
DEFINE_bool(silhouette_edges, true,
            "scan detector: a segment's end where the scan jumps away from the sensor is a "
            "vertical edge (a convex corner seen with one wall, a wall's end; carmen: off "
            "unless given)");
DEFINE_double(silhouette_margin, 0.2,
              "scan detector: the beam past a silhouette edge returns this far beyond the "
              "segment's line, m");
DEFINE_double(min_silhouette_length, 0.5,
              "scan detector: shortest segment that makes a silhouette edge, m");
DEFINE_double(max_silhouette_spacing, 0.5,
              "scan detector: widest spacing of the beams on a wall at its silhouette edge "
              "(twice the edge's largest position error), m");
DEFINE_string(detector_dump, "",
              "carmen: write the detector's detections and missed labels on the held-out scans, "
              "judged against the whole log's corners, with each error's cause, as CSV to this "
              "file (detector_evaluation.h)");
DEFINE_double(min_corner_angle_deg, 45,
              "scan detector: least angle between a corner's walls (carmen: 75)");
DEFINE_double(max_corner_angle_deg, 135,
              "scan detector: largest angle between a corner's walls (carmen: 105)");
DEFINE_double(min_long_wall, 0,
              "scan detector: the longer of a corner's walls is at least this long, m; 0: not "
              "asked (carmen: 0.8)");
DEFINE_double(min_open_wall, 0,
              "scan detector: a corner's wall shorter than this must not end in the open (turn "
              "again or stop before something farther), m; 0: not asked (carmen: 0.5)");
DEFINE_double(max_fit_rms, 0,
              "scan detector: a corner's walls fit their lines within this RMS, m; 0: not asked "
              "(carmen: 0.025)");
DEFINE_double(corner_tolerance, 0.15,
              "scan detector: a corner lies this close to both walls' near ends, m");
// A real CARMEN log (carmen_recording.h).
DEFINE_double(carmen_step, 0.5, "carmen: keep a scan every this many metres (or 15 degrees)");
DEFINE_double(cluster_radius, 0.30, "carmen: detections this close in the world are one corner, m");
DEFINE_int32(min_sightings, 5, "carmen --nomap_corners: a corner seen this often is a landmark");
DEFINE_bool(map_junctions, true,
            "carmen: a map wall ending at another's side makes a corner (map_corners.h)");
DEFINE_int32(label_wall_returns, 3,
             "carmen: a detector's label shows each wall with this many of the scan's returns "
             "(detector_evaluation.h; 0: not asked)");
DEFINE_int32(wall_min_segments, 6, "carmen: a map wall is kept when seen in this many scans");
DEFINE_double(map_corner_tolerance, 0.15,
              "carmen: two map walls make a corner within this of an end of each, m");
DEFINE_string(odometry, "log",
              "carmen: log: the log's ODOM stream, its noise model fitted on the map part "
              "(--odom_sigma_* given: those); synthetic: the reference motion plus "
              "--world_odom_sigma_* noise (an ablation arm)");
DEFINE_double(map_fraction, 0.5,
              "carmen: the first this fraction of the log's time span makes the map and "
              "calibrates the odometry, FLAG is evaluated on the rest from a start the seed "
              "picks; 0: the whole log is both (circular)");
DEFINE_bool(map_corners, true,
            "carmen: landmarks are the corners of the map's walls (apps/flag/map_corners.h); "
            "false: clusters of the detector's own corners");
// The multi-scan stability check on a log's corners (stable_edge_filter.h).
DEFINE_bool(stable_edges, false,
            "carmen: keep a corner only when the neighbouring scans see it again at the same "
            "place, moved by the log's odometry (FLAG and the detector's evaluation alike)");
DEFINE_bool(exact_detections, false,
            "carmen: an ablation: each detection of a map corner at the range and bearing the "
            "corner has from the reference pose (FLAG without the detector's error)");
DEFINE_int32(stable_window, 2, "carmen --stable_edges: neighbouring scans before and after");
DEFINE_int32(stable_min_scans, 1,
             "carmen --stable_edges: neighbours that must see the corner again (fewer at the "
             "log's ends: as many as there are)");
DEFINE_double(stable_radius, 0.50,
              "carmen --stable_edges: a neighbour's corner this close is the same one, m");
DEFINE_double(stable_spacing, 0,
              "carmen --stable_edges: a neighbour's laser this far from the last neighbour's "
              "(or turned --stable_spacing_turn_deg) by the odometry, m; 0: every scan");
DEFINE_double(stable_spacing_turn_deg, 15,
              "carmen --stable_edges: or turned this far from the last neighbour, degrees");
// The pipeline (FlagOptions).
DEFINE_double(landmark_sigma, 0.10, "prior sigma of a labelled landmark, m (thesis 10 cm)");
DEFINE_bool(fixed_landmarks, false, "hold landmarks fixed at their labels (fig. 4.11 ablation)");
DEFINE_double(gate, 0.5,
              "nearest-neighbour association gate, m (thesis 50 cm); with --pose_gate its floor");
DEFINE_bool(pose_gate, true,
            "grow the gate with the pose's covariance (odometry in, accepted measurements out)");
DEFINE_double(odometry_scale, 1.0,
              "odometry sigmas times this, in the odometry factors and the gate; victoria: "
              "measured against the known-association solution unless given "
              "(odometry_calibration.h)");
DEFINE_double(odometry_jitter_xy, 0,
              "odometry poses' jitter (an error that does not accumulate), m; 0: none; carmen: "
              "measured on the map part unless given");
DEFINE_double(odometry_jitter_theta_deg, 0, "... and in heading, degrees");
DEFINE_bool(odometry_jitter_fit, true,
            "carmen, log odometry: fit a jitter and a drift on the map part (false: a drift "
            "alone)");
DEFINE_uint64(calibration_window, 0,
              "victoria: the longest window of odometry steps the scale is measured over (0: "
              "the longest stretch without a detection)");
DEFINE_double(
    gate_sigmas, 3.0,
    "pose_gate: Mahalanobis radius of the gate, in sigmas (--gate is this many floor sigmas)");
DEFINE_double(max_gate_sigma, 0, "pose_gate: the gate's largest sigma, m (0: unbounded)");
DEFINE_double(wall_sigma_deg, 0,
              "the corner's walls as a descriptor: the detector's error in a wall's direction, "
              "degrees; a landmark whose walls do not match the detection's within gate_sigmas "
              "x sqrt(heading variance + this^2) is no candidate (0: off)");
DEFINE_bool(reject_ambiguous, false,
            "leave out a detection with more than one landmark within its gate");
DEFINE_bool(corrected_guess, true,
            "start a new pose at the Kalman update of its prediction by its accepted "
            "measurements (the gate's filter) instead of at the odometry's prediction");
DEFINE_bool(pairwise_check, true, "pairwise consistency check (sec. 4.3.3.1)");
DEFINE_double(consistency_threshold, 0.10,
              "projections this close are consistent, m (thesis 10 cm)");
DEFINE_double(consistency_sigmas, 0,
              "projections are also consistent within this many sigmas of their difference "
              "(pose and detection covariance when associated; 0: the fixed threshold only)");
DEFINE_int32(min_links, 2, "consistent partners a measurement needs to be accepted");
DEFINE_int32(window, 20, "poses a measurement waits for partners");
DEFINE_bool(max_clique, false,
            "accept the maximum clique (PCM, via igraph) instead of link counts");
DEFINE_bool(max_mixture, true, "max-mixture range-bearing factors (sec. 4.3.3.2)");
DEFINE_double(null_weight, 0.1, "weight of the null hypothesis");
DEFINE_double(null_scale, 1e-3, "information scale of the null hypothesis");
DEFINE_int32(lost_after, 40, "localization is lost after this many poses without a factor");
DEFINE_double(lost_sigma, 1.0,
              "... or when the gate's filter gives the position a sigma beyond this, m");
DEFINE_double(start_sigma_xy, 0.10, "prior sigma of the start position, m");
DEFINE_double(start_sigma_theta_deg, 1.0, "prior sigma of the start heading, degrees");
DEFINE_string(backend, hamal::flag::kDefaultBackend,
              "back-end spec from the registry (--list_backends); the default is AprilSAM with "
              "n_lc=1 (apps/flag/flag_options.h says why)");
// Outputs and trials.
DEFINE_string(trajectory, "",
              "run: write truth, FLAG and dead reckoning per pose (CSV); victoria: every arm's "
              "online error and wrong factors so far per pose; carmen: per seed, arm and pose "
              "the reference, the estimate the ATE grades and the factors so far");
DEFINE_string(landmarks_out, "", "run: write each landmark's truth, label and estimate (CSV)");
DEFINE_uint64(trials, 1, "trials, carmen: how many seeds, from --seed on");
DEFINE_bool(raycast, false,
            "trials dynamic|static: the scene ray cast and seen by --detector, instead of the "
            "thesis' hand-made point measurements");
DEFINE_double(radius, 0.3, "trials static: the obstacle's largest distance from the landmark, m");
DEFINE_double(stated_sigma, 0.10,
              "trials static: the point noise the detections state (their factors' sigma), m; "
              "they are drawn with 10 cm (thesis 4.4.3.2)");
DEFINE_string(output, "",
              "world / trials / victoria: write here instead of standard output; carmen: CSV "
              "rows here");
DEFINE_string(data, "../shared/data/victoria_park.txt",
              "victoria: the GTSAM Victoria Park file; carmen: the CARMEN log (no default)");
DEFINE_string(arms, "known,flag,nocheck,nomixture,neither",
              "victoria: the arms to run (known, flag, nocheck, nomixture, neither)");
DEFINE_string(reference_backend, "aprilsam",
              "victoria: back-end of the known-association solution (thesis protocol)");

namespace hamal::apps {
namespace {

const char kUsage[] =
    "FLAG: global localization against landmarks labelled in a floor plan (thesis ch. 4).\n\n"
    "  hamal_flag world office > office.plan      write a built-in world's floor plan\n"
    "  hamal_flag run --world office --seed 1     localize one run, print its errors\n"
    "  hamal_flag trials dynamic|static|office    one experiment's trials as CSV rows\n"
    "  hamal_flag victoria --gate 3 ...\n"
    "                                             Victoria Park with the tree ids hidden\n"
    "  hamal_flag carmen --data intel.log         a real laser log (apps/carmen)\n\n"
    "See apps/flag/README.md; scripts/flag.sh runs the experiments of sec. 4.4.";

flag::SimulatorOptions simulatorOptions(std::uint64_t seed) {
  flag::SimulatorOptions s;
  s.step = FLAGS_step;
  s.speed = FLAGS_speed;
  s.noise.odom_sigma_x = FLAGS_world_odom_sigma_x;
  s.noise.odom_sigma_y = FLAGS_world_odom_sigma_y;
  s.noise.odom_sigma_theta = FLAGS_world_odom_sigma_theta_deg * kDeg;
  s.noise.range_sigma = FLAGS_world_range_sigma;
  s.noise.bearing_sigma = FLAGS_world_bearing_sigma_deg * kDeg;
  s.stated.odom_sigma_x = FLAGS_odom_sigma_x;
  s.stated.odom_sigma_y = FLAGS_odom_sigma_y;
  s.stated.odom_sigma_theta = FLAGS_odom_sigma_theta_deg * kDeg;
  s.stated.range_sigma = FLAGS_range_sigma;
  s.stated.bearing_sigma = FLAGS_bearing_sigma_deg * kDeg;
  s.sensor_range = FLAGS_sensor_range;
  s.min_height = FLAGS_min_height;
  if (FLAGS_detector == "scan")
    s.detector = flag::SimulatorOptions::kScan;
  else if (FLAGS_detector == "oracle")
    s.detector = flag::SimulatorOptions::kOracle;
  else if (FLAGS_detector == "oracle_in_view")
    s.detector = flag::SimulatorOptions::kOracleInView;
  else
    throw Error("--detector must be scan, oracle or oracle_in_view, not '" + FLAGS_detector + "'");
  s.scanner.range_sigma = FLAGS_scan_range_sigma;
  s.scanner.angular_step = FLAGS_scan_step_deg * kDeg;
  s.edges.breakpoints.range_sigma = FLAGS_scan_range_sigma;
  s.edges.segments.fit_tolerance = FLAGS_fit_tolerance;
  s.edges.segments.min_points = FLAGS_min_segment_points;
  s.edges.segments.min_length = FLAGS_min_segment_length;
  s.edges.corners.min_stub_points = FLAGS_min_stub_points;
  s.edges.breakpoints.lambda = FLAGS_breakpoint_lambda_deg * kDeg;
  s.edges.corners.min_stub_length = FLAGS_min_stub_length;
  s.edges.corners.min_angle = FLAGS_min_corner_angle_deg * kDeg;
  s.edges.corners.max_angle = FLAGS_max_corner_angle_deg * kDeg;
  s.edges.corners.tolerance = FLAGS_corner_tolerance;
  s.edges.corners.min_long_wall = FLAGS_min_long_wall;
  s.edges.corners.max_fit_rms = FLAGS_max_fit_rms;
  s.edges.corners.min_open_wall = FLAGS_min_open_wall;
  s.edges.silhouettes.enabled = FLAGS_silhouette_edges;
  s.edges.silhouettes.margin = FLAGS_silhouette_margin;
  s.edges.silhouettes.min_length = FLAGS_min_silhouette_length;
  s.edges.silhouettes.max_spacing = FLAGS_max_silhouette_spacing;
  s.seed = seed;
  s.validate();
  // The localizer weighs a detection by 1 / sigma^2: a noiseless simulation
  // still needs a sigma to weigh with.
  if (FLAGS_range_sigma == 0) throw Error("--range_sigma 0: must be > 0 (the ranges' weight)");
  if (FLAGS_bearing_sigma_deg == 0)
    throw Error("--bearing_sigma_deg 0: must be > 0 (the bearings' weight)");
  return s;
}

flag::FlagOptions flagOptions() {
  flag::FlagOptions o;
  o.landmarks.sigma = FLAGS_landmark_sigma;
  o.landmarks.fixed = FLAGS_fixed_landmarks;
  o.association.gate = FLAGS_gate;
  o.association.pose_gate = FLAGS_pose_gate;
  o.association.gate_sigmas = FLAGS_gate_sigmas;
  o.association.max_gate_sigma = FLAGS_max_gate_sigma;
  o.association.wall_sigma = FLAGS_wall_sigma_deg * kDeg;
  o.odometry.scale = FLAGS_odometry_scale;
  o.odometry.jitter_xy = FLAGS_odometry_jitter_xy;
  o.odometry.jitter_theta = FLAGS_odometry_jitter_theta_deg * kDeg;
  o.odometry.corrected_guess = FLAGS_corrected_guess;
  o.association.reject_ambiguous = FLAGS_reject_ambiguous;
  o.consistency.check = FLAGS_pairwise_check;
  o.consistency.threshold = FLAGS_consistency_threshold;
  o.consistency.sigmas = FLAGS_consistency_sigmas;
  o.consistency.min_links = FLAGS_min_links;
  o.consistency.window = FLAGS_window;
  o.consistency.max_clique = FLAGS_max_clique;
  o.max_mixture.enabled = FLAGS_max_mixture;
  o.max_mixture.null_weight = FLAGS_null_weight;
  o.max_mixture.null_scale = FLAGS_null_scale;
  o.lost.after = FLAGS_lost_after;
  o.lost.sigma = FLAGS_lost_sigma;
  o.start.sigma_xy = FLAGS_start_sigma_xy;
  o.start.sigma_theta = FLAGS_start_sigma_theta_deg * kDeg;
  o.backend = FLAGS_backend;
  o.validate();
  return o;
}

// Standard output, or --output written through OutputFile (whole at the
// end, so an interrupted trial batch leaves no half file behind).
class Output {
 public:
  Output() {
    if (!FLAGS_output.empty()) file_ = std::make_unique<OutputFile>(FLAGS_output);
  }
  std::ostream& out() { return file_ ? file_->stream() : std::cout; }
  void commit() {
    if (file_) file_->commit();
  }

 private:
  std::unique_ptr<OutputFile> file_;
};

int world(const std::vector<std::string>& args) {
  if (args.size() != 2) throw Error("world: give one world name (office, corridor)");
  const flag::FloorPlan plan = flag::builtinWorld(args[1], FLAGS_label_sigma, FLAGS_seed);
  Output o;
  flag::writeFloorPlan(o.out(), plan);
  o.commit();
  return 0;
}

struct OfficeRow {
  std::string arm;
  flag::RunErrors errors;
  double p99_ms = 0, max_ms = 0, cpu_p99_ms = 0;
  flag::AssociationStats stats;
  bool ok = true;
};

flag::FlagRun runWorld(const Registry& registry, const flag::FloorPlan& plan, std::uint64_t seed,
                       const flag::FlagOptions& options) {
  const flag::Recording rec = flag::simulate(plan, simulatorOptions(seed));
  return flag::runFlag(flag::labelsOf(plan), rec, options, registry);
}

double ms(const std::vector<double>& seconds, double p) { return 1e3 * percentile(seconds, p); }

int run(const Registry& registry, const std::vector<std::string>& args) {
  if (args.size() != 1) throw Error("run: unexpected argument '" + args[1] + "'");
  const flag::FloorPlan plan = flag::loadWorld(FLAGS_world, FLAGS_label_sigma, FLAGS_seed);
  const flag::FlagOptions options = flagOptions();
  const flag::SimulatorOptions sim = simulatorOptions(FLAGS_seed);
  const flag::Recording rec = flag::simulate(plan, sim);
  const flag::FlagRun r = flag::runFlag(flag::labelsOf(plan), rec, options, registry);
  std::cout << std::fixed << std::setprecision(3);
  std::cout << "hamal_flag: " << plan.name << ", " << plan.corners.size() << " landmarks, "
            << r.truth.size() << " poses over " << plan.pathLength() << " m, seed " << FLAGS_seed
            << ", back-end " << options.backend
            << (options.landmarks.fixed ? ", landmarks fixed" : "") << "\n";
  const auto line = [](const char* name, const flag::RunErrors& e) {
    std::cout << "  " << std::left << std::setw(15) << name << std::right << " mean |error| "
              << e.position << " m  longitudinal " << e.longitudinal << " m  lateral " << e.lateral
              << " m  heading " << e.heading / kDeg << " deg  last pose " << e.last_position
              << " m\n";
  };
  line("FLAG", r.flag);
  line("dead reckoning", r.odometry);
  const flag::AssociationStats& s = r.stats;
  std::cout << "  association: " << s.detections << " detections (" << s.corner_detections
            << " of corners), " << s.associated << " within the gate, " << s.accepted
            << " factors (precision " << s.precision() << ", recall " << s.recall() << "), "
            << s.rejected << " dropped by the pairwise check (" << s.rejected_correct
            << " right); status "
            << (r.lost.steps ? "lost at " + std::to_string(r.lost.steps) + " poses from pose " +
                                   std::to_string(r.lost.first)
                             : std::string("ok"))
            << "\n";
  const flag::DetectionScore d = flag::scoreDetections(plan, rec, sim);
  std::cout << "  detector " << FLAGS_detector << ": " << d.detections << " detections, precision "
            << d.precision() << " (" << d.from_corner << " of corners, " << d.from_object
            << " of objects, " << d.from_person << " of people, " << d.from_nothing
            << " of nothing); recall " << d.recall() << " of " << d.in_view
            << " corners in view (both walls), " << d.recallInSight() << " of " << d.in_sight
            << " in line of sight; error RMS range " << d.range_rms << " m, bearing "
            << d.bearing_rms / kDeg << " deg\n";
  std::cout << "  step time (association + check + update): wall clock p50 "
            << ms(r.steps.seconds, 50) << " ms  p99 " << ms(r.steps.seconds, 99) << " ms  max "
            << ms(r.steps.seconds, 100) << " ms; thread CPU p50 " << ms(r.steps.cpu_seconds, 50)
            << " ms  p99 " << ms(r.steps.cpu_seconds, 99) << " ms  max "
            << ms(r.steps.cpu_seconds, 100) << " ms\n";
  const flag::UpdateSummary u = flag::summarizeUpdates(r);
  std::cout << "  updates: " << u.steps << " steps, " << u.batch << " batch";
  for (std::size_t k = 0; k < u.batch_reasons.size(); ++k)
    std::cout << (k ? ", " : " (") << u.batch_reasons[k].second << " " << u.batch_reasons[k].first
              << (k + 1 == u.batch_reasons.size() ? ")" : "");
  std::cout << ", " << u.incremental << " incremental (" << u.mode_switches
            << " with a mode switch); thread CPU p99 of the batch steps "
            << (u.batch ? ms(u.batch_cpu_seconds, 99) : 0.0) << " ms, of the incremental "
            << (u.incremental ? ms(u.incremental_cpu_seconds, 99) : 0.0) << " ms\n";
  if (!FLAGS_trajectory.empty()) {
    OutputFile file(FLAGS_trajectory);
    std::ostream& f = file.stream();
    f << std::setprecision(10)
      << "pose,truth_x,truth_y,truth_theta,flag_x,flag_y,flag_theta,odom_x,odom_y,odom_theta\n";
    for (std::size_t i = 0; i < r.truth.size(); ++i) {
      const Pose2 &t = r.truth[i], &e = r.online[i], &d = r.dead_reckoning[i];
      f << i << ',' << t.x << ',' << t.y << ',' << t.theta << ',' << e.x << ',' << e.y << ','
        << e.theta << ',' << d.x << ',' << d.y << ',' << d.theta << '\n';
    }
    file.commit();
  }
  if (!FLAGS_landmarks_out.empty()) {
    OutputFile file(FLAGS_landmarks_out);
    std::ostream& f = file.stream();
    f << std::setprecision(10) << "id,truth_x,truth_y,label_x,label_y,estimate_x,estimate_y\n";
    for (const flag::Corner& c : plan.corners) {
      const Point2 e = r.final_estimate.point(L(c.id));
      f << c.id << ',' << c.truth.x() << ',' << c.truth.y() << ',' << c.label.x() << ','
        << c.label.y() << ',' << e.x() << ',' << e.y() << '\n';
    }
    file.commit();
  }
  if (!r.ok) throw Error("the back-end failed: " + r.status);
  return 0;
}

// The most trials one invocation runs (trials()).
constexpr std::uint64_t kMaxTrials = 1000000;

int trials(const Registry& registry, const std::vector<std::string>& args) {
  if (args.size() != 2) throw Error("trials: give one experiment (dynamic, static, office)");
  const std::string& experiment = args[1];
  // Seeds run from --seed to --seed + --trials - 1; past 2^64 - 1 the loop
  // bound would wrap and run nothing. A count no run could finish (a trial
  // takes milliseconds to seconds, and its rows wait in memory or in a
  // temporary file until the end) is refused whatever the seed, rather than
  // left to fill the disk.
  if (FLAGS_trials == 0) throw Error("--trials must be at least 1");
  if (FLAGS_trials > kMaxTrials)
    throw Error("--trials " + std::to_string(FLAGS_trials) + ": at most " +
                std::to_string(kMaxTrials) +
                " trials per run; split more over several runs with --seed");
  if (FLAGS_trials - 1 > std::numeric_limits<std::uint64_t>::max() - FLAGS_seed)
    throw Error("--seed " + std::to_string(FLAGS_seed) + " --trials " +
                std::to_string(FLAGS_trials) + ": the last seed would exceed 2^64 - 1");
  const flag::FlagOptions base = flagOptions();
  Output o;
  std::ostream& out = o.out();
  out << std::setprecision(10);
  if (FLAGS_raycast && experiment != "static" && experiment != "dynamic")
    throw Error("--raycast: only the dynamic and static experiments have ray-cast scenes");
  if (FLAGS_raycast && !gflags::GetCommandLineFlagInfoOrDie("stated_sigma").is_default)
    throw Error(
        "--stated_sigma: the ray-cast scene's detections state --range_sigma and "
        "--bearing_sigma_deg");
  if (experiment == "dynamic") {
    out << "seed,arm,last_error,mean_error,factors,precision,ok\n";
    for (std::uint64_t s = FLAGS_seed; s - FLAGS_seed < FLAGS_trials; ++s) {
      for (bool check : {true, false}) {
        flag::FlagOptions opt = base;
        opt.consistency.check = check;
        const flag::TrialResult t =
            FLAGS_raycast ? flag::dynamicObstacleScanTrial(s, opt, simulatorOptions(s), registry)
                          : flag::dynamicObstacleTrial(s, opt, registry);
        out << s << ',' << (check ? "pairwise check" : "no check") << ',' << t.last_error << ','
            << t.mean_error << ',' << t.stats.accepted << ',' << t.stats.precision() << ',' << t.ok
            << '\n';
      }
    }
  } else if (experiment == "static") {
    if (!(FLAGS_radius >= 0) || !std::isfinite(FLAGS_radius))
      throw Error("--radius must be >= 0 and finite");
    out << "seed,radius,arm,last_error,mean_error,factors,precision,null_active,ok\n";
    for (std::uint64_t s = FLAGS_seed; s - FLAGS_seed < FLAGS_trials; ++s) {
      for (bool mixture : {true, false}) {
        flag::FlagOptions opt = base;
        opt.max_mixture.enabled = mixture;
        const flag::TrialResult t =
            FLAGS_raycast
                ? flag::staticObstacleScanTrial(s, FLAGS_radius, opt, simulatorOptions(s), registry)
                : flag::staticObstacleTrial(s, FLAGS_radius, opt, registry, FLAGS_stated_sigma);
        out << s << ',' << FLAGS_radius << ',' << (mixture ? "max-mixture" : "no max-mixture")
            << ',' << t.last_error << ',' << t.mean_error << ',' << t.stats.accepted << ','
            << t.stats.precision() << ',' << t.null_active << ',' << t.ok << '\n';
      }
    }
  } else if (experiment == "office") {
    out << "seed,arm,position,longitudinal,lateral,heading_deg,last_position,p99_ms,max_ms,"
           "cpu_p99_ms,factors,precision,recall,ok\n";
    for (std::uint64_t s = FLAGS_seed; s - FLAGS_seed < FLAGS_trials; ++s) {
      const flag::FloorPlan plan = flag::loadWorld(FLAGS_world, FLAGS_label_sigma, s);
      std::vector<OfficeRow> rows;
      for (bool fixed : {false, true}) {
        flag::FlagOptions opt = base;
        opt.landmarks.fixed = fixed;
        const flag::FlagRun r = runWorld(registry, plan, s, opt);
        if (!fixed) {
          OfficeRow odo;
          odo.arm = "dead reckoning";
          odo.errors = r.odometry;
          rows.push_back(odo);
        }
        OfficeRow row;
        row.arm = fixed ? "FLAG (landmarks fixed)" : "FLAG";
        row.errors = r.flag;
        row.p99_ms = ms(r.steps.seconds, 99);
        row.max_ms = ms(r.steps.seconds, 100);
        row.cpu_p99_ms = ms(r.steps.cpu_seconds, 99);
        row.stats = r.stats;
        row.ok = r.ok;
        rows.push_back(row);
      }
      for (const OfficeRow& r : rows)
        out << s << ',' << r.arm << ',' << r.errors.position << ',' << r.errors.longitudinal << ','
            << r.errors.lateral << ',' << r.errors.heading / kDeg << ',' << r.errors.last_position
            << ',' << r.p99_ms << ',' << r.max_ms << ',' << r.cpu_p99_ms << ',' << r.stats.accepted
            << ',' << r.stats.precision() << ',' << r.stats.recall() << ',' << r.ok << '\n';
    }
  } else {
    throw Error("unknown experiment '" + experiment + "' (dynamic, static, office)");
  }
  o.commit();
  return 0;
}

// Victoria Park: the known-association baseline and FLAG with and without
// its two data-association defences, graded against the file's ids and the
// known-association solution.
int victoria(const Registry& registry, const std::vector<std::string>& args) {
  if (args.size() != 1) throw Error("victoria: unexpected argument '" + args[1] + "'");
  flag::FlagOptions base = flagOptions();
  std::cerr << "hamal_flag: making the known-association solution of " << FLAGS_data << " ("
            << FLAGS_reference_backend << ", thesis protocol)\n";
  const flag::VictoriaPark vp = flag::prepareVictoriaPark(
      FLAGS_data, registry, FLAGS_reference_backend, FLAGS_label_sigma, FLAGS_seed);
  std::cerr << "hamal_flag: " << vp.recording.steps.size() << " poses, " << vp.labels.size()
            << " trees, reference in " << vp.reference_seconds << " s\n";
  const std::vector<flag::OdometryConsistency> consistency = flag::odometryConsistency(
      vp.recording,
      FLAGS_calibration_window ? FLAGS_calibration_window : flag::longestCoast(vp.recording));
  std::cerr << "hamal_flag: odometry against the reference, scale per window of k steps:";
  for (const flag::OdometryConsistency& c : consistency)
    std::cerr << " k=" << c.window << ":" << c.scale;
  std::cerr << "\n";
  if (gflags::GetCommandLineFlagInfoOrDie("odometry_scale").is_default)
    base.odometry.scale = flag::odometryNoiseScale(consistency);
  std::cerr << "hamal_flag: odometry sigmas times " << base.odometry.scale << "\n";
  Values truth;
  for (std::size_t i = 0; i < vp.recording.steps.size(); ++i)
    truth.insert(X(i), vp.recording.steps[i].truth);
  struct Arm {
    const char* key;
    const char* name;
    bool known, check, mixture;
  };
  const Arm all_arms[] = {{"known", "known association", true, false, false},
                          {"flag", "FLAG", false, true, true},
                          {"nocheck", "FLAG without pairwise check", false, false, true},
                          {"nomixture", "FLAG without max-mixture", false, true, false},
                          {"neither", "FLAG without either", false, false, false}};
  std::vector<Arm> arms;
  {
    std::stringstream list(FLAGS_arms);
    std::string key;
    while (std::getline(list, key, ',')) {
      const auto found = std::find_if(std::begin(all_arms), std::end(all_arms),
                                      [&](const Arm& a) { return key == a.key; });
      if (found == std::end(all_arms))
        throw Error("--arms: unknown arm '" + key + "' (known, flag, nocheck, nomixture, neither)");
      arms.push_back(*found);
    }
    if (arms.empty()) throw Error("--arms: give at least one arm");
  }
  std::unique_ptr<OutputFile> trace_file;
  if (!FLAGS_trajectory.empty()) trace_file = std::make_unique<OutputFile>(FLAGS_trajectory);
  std::ostream& trace = trace_file ? trace_file->stream() : std::cout;
  if (trace_file) {
    trace << std::setprecision(8) << "arm,pose,error_m,heading_error_rad,factors,wrong_factors\n";
  }
  Output o;
  std::ostream& out = o.out();
  out << std::setprecision(6)
      << "arm,odometry_scale,precision,recall,factors,ate_m,ate_aligned_m,online_mean_m,cpu_p99_ms,"
         "wall_p99_ms,"
         "landmark_error_m,mixtures,null_active,ok\n";
  for (const Arm& arm : arms) {
    flag::FlagOptions opt = base;
    opt.association.known = arm.known;
    opt.consistency.check = arm.check;
    opt.max_mixture.enabled = arm.mixture;
    const flag::FlagRun r = flag::runFlag(vp.labels, vp.recording, opt, registry);
    Values est;
    for (std::size_t i = 0; i < r.truth.size(); ++i) est.insert(X(i), r.final_estimate.pose(X(i)));
    const TrajectoryError ate = absoluteTrajectoryError(est, truth, false);
    const TrajectoryError aligned = absoluteTrajectoryError(est, truth, true);
    double lm = 0;
    for (const flag::LandmarkLabel& l : vp.labels)
      lm += (r.final_estimate.point(L(l.id)) - vp.reference_landmarks.point(L(l.id))).norm();
    lm /= double(vp.labels.size());
    if (trace_file)
      for (std::size_t i = 0; i < r.truth.size(); ++i)
        trace << arm.key << ',' << i << ',' << (r.online[i].t() - r.truth[i].t()).norm() << ','
              << wrapAngle(r.online[i].theta - r.truth[i].theta) << ',' << r.factors.so_far[i]
              << ',' << r.factors.wrong_so_far[i] << '\n';
    out << arm.name << ',' << opt.odometry.scale << ',' << r.stats.precision() << ','
        << r.stats.recall() << ',' << r.stats.accepted << ',' << ate.translation_rmse << ','
        << aligned.translation_rmse << ',' << r.flag.position << ',' << ms(r.steps.cpu_seconds, 99)
        << ',' << ms(r.steps.seconds, 99) << ',' << lm << ',' << r.factors.mixtures << ','
        << r.factors.null_active << ',' << r.ok << std::endl;
  }
  if (trace_file) trace_file->commit();
  o.commit();
  return 0;
}

// Whether the command line gave a flag (else its default, or the log's own
// setting, applies).
bool flagGiven(const char* flag) { return !gflags::GetCommandLineFlagInfoOrDie(flag).is_default; }

// carmen's checks of its command line, before the log is read.
void checkCarmenCommandLine(const std::vector<std::string>& args) {
  if (args.size() != 1) throw Error("carmen: unexpected argument '" + args[1] + "'");
  if (gflags::GetCommandLineFlagInfoOrDie("data").is_default)
    throw Error("carmen: give the log with --data");
  if (FLAGS_trials == 0) throw Error("--trials must be at least 1");
  if (FLAGS_trials - 1 > std::numeric_limits<std::uint64_t>::max() - FLAGS_seed)
    throw Error("--seed " + std::to_string(FLAGS_seed) + " --trials " +
                std::to_string(FLAGS_trials) + ": the last seed would exceed 2^64 - 1");
  if (FLAGS_odometry != "log" && FLAGS_odometry != "synthetic")
    throw Error("--odometry must be log or synthetic, not '" + FLAGS_odometry + "'");
  if (!FLAGS_detector_dump.empty() && !FLAGS_map_corners)
    throw Error("--detector_dump judges against the map's corners: not with --nomap_corners");
}

// How one seed's map and recording are made from the log: the command line's
// settings, the log's own detector settings where it leaves them.
flag::CarmenFlagOptions carmenFlagOptions(std::uint64_t seed) {
  const flag::SimulatorOptions sim = simulatorOptions(seed);
  flag::CarmenFlagOptions c;
  c.scans.step = FLAGS_carmen_step;
  c.landmarks.cluster_radius = FLAGS_cluster_radius;
  c.landmarks.min_sightings = FLAGS_min_sightings;
  c.landmarks.map_corners = FLAGS_map_corners;
  c.landmarks.walls.min_segments = FLAGS_wall_min_segments;
  c.landmarks.walls.corner_tolerance = FLAGS_map_corner_tolerance;
  c.landmarks.walls.junctions = FLAGS_map_junctions;
  c.landmarks.label_sigma = FLAGS_label_sigma;
  c.odometry.world.x = sim.noise.odom_sigma_x;
  c.odometry.world.y = sim.noise.odom_sigma_y;
  c.odometry.world.theta = sim.noise.odom_sigma_theta;
  c.odometry.stated.x = sim.stated.odom_sigma_x;
  c.odometry.stated.y = sim.stated.odom_sigma_y;
  c.odometry.stated.theta = sim.stated.odom_sigma_theta;
  c.stated_range_sigma = sim.stated.range_sigma;
  c.stated_bearing_sigma = sim.stated.bearing_sigma;
  c.odometry.source = FLAGS_odometry == "log" ? flag::CarmenFlagOptions::Odometry::kLog
                                              : flag::CarmenFlagOptions::Odometry::kSynthetic;
  c.odometry.calibrate = !flagGiven("odom_sigma_x") && !flagGiven("odom_sigma_y") &&
                         !flagGiven("odom_sigma_theta_deg");
  c.map_fraction = FLAGS_map_fraction;
  c.odometry.fit_jitter = FLAGS_odometry_jitter_fit;
  c.edges = sim.edges;
  // The log's own detector settings where the command line leaves them.
  const flag::VerticalEdgeDetectorOptions real = flag::realLogDetectorOptions();
  if (!flagGiven("breakpoint_lambda_deg")) c.edges.breakpoints.lambda = real.breakpoints.lambda;
  if (!flagGiven("min_stub_points")) c.edges.corners.min_stub_points = c.edges.segments.min_points;
  if (!flagGiven("min_stub_length")) c.edges.corners.min_stub_length = c.edges.segments.min_length;
  if (!flagGiven("silhouette_edges")) c.edges.silhouettes.enabled = real.silhouettes.enabled;
  if (!flagGiven("min_corner_angle_deg")) c.edges.corners.min_angle = real.corners.min_angle;
  if (!flagGiven("max_corner_angle_deg")) c.edges.corners.max_angle = real.corners.max_angle;
  if (!flagGiven("min_long_wall")) c.edges.corners.min_long_wall = real.corners.min_long_wall;
  if (!flagGiven("max_fit_rms")) c.edges.corners.max_fit_rms = real.corners.max_fit_rms;
  if (!flagGiven("min_open_wall")) c.edges.corners.min_open_wall = real.corners.min_open_wall;
  c.edges.min_height = 0;  // a 2D log has no heights
  c.exact_detections = FLAGS_exact_detections;
  c.stable_edges.enabled = FLAGS_stable_edges;
  c.stable_edges.window = FLAGS_stable_window;
  c.stable_edges.min_scans = FLAGS_stable_min_scans;
  c.stable_edges.radius = FLAGS_stable_radius;
  c.stable_edges.spacing = FLAGS_stable_spacing;
  c.stable_edges.spacing_turn = FLAGS_stable_spacing_turn_deg * kDeg;
  c.seed = seed;
  return c;
}

// The detector against the map's visible corners on the held-out scans (the
// same for every seed), on those mostly on map walls, and against the whole
// log's corners.
struct CarmenDetectorScores {
  flag::DetectorScore detector, mapped, detector_log;
};

CarmenDetectorScores scoreCarmenDetector(const carmen::CarmenLog& log, const flag::CarmenFlag& cf,
                                         const flag::CarmenFlagOptions& c, std::uint64_t seed) {
  CarmenDetectorScores d;
  if (!c.landmarks.map_corners) return d;
  flag::DetectorEvaluationOptions judge;
  judge.max_range = FLAGS_sensor_range;
  judge.wall_returns = FLAGS_label_wall_returns;
  d.detector = flag::evaluateDetectorOnLog(log, cf, c.edges, judge, &d.mapped);
  d.detector_log = flag::evaluateDetectorOnLog(log, cf, c.edges, judge, nullptr, true);
  if (!FLAGS_detector_dump.empty() && seed == FLAGS_seed) {
    std::ofstream dump(FLAGS_detector_dump);
    if (!dump) throw Error("--detector_dump: cannot write '" + FLAGS_detector_dump + "'");
    flag::dumpDetectorErrors(log, cf, c.edges, judge, true, dump);
  }
  return d;
}

// What one seed's map, recording, odometry and detector are, on stdout.
// How far the evaluated detections' walls, turned by the reference heading,
// lie from the nearest of their landmark's (grading only: what
// --wall_sigma_deg states).
void printWallErrors(const flag::CarmenFlag& cf) {
  std::vector<double> errors;
  for (const flag::RecordedStep& s : cf.recording.steps)
    for (const flag::Detection& d : s.detections) {
      if (d.source.kind != flag::Source::kCorner || d.source.id >= cf.labels.size()) continue;
      const std::vector<double>& mapped = cf.labels[d.source.id].walls;
      for (double w : d.walls) {
        double best = std::numeric_limits<double>::infinity();
        for (double m : mapped) best = std::min(best, std::abs(wrapAngle(w + s.truth.theta - m)));
        if (std::isfinite(best)) errors.push_back(best / kDeg);
      }
    }
  if (errors.empty()) return;
  std::sort(errors.begin(), errors.end());
  const auto at = [&](double q) { return errors[std::size_t(q * double(errors.size() - 1))]; };
  std::cout << "  detected walls against their landmark's at the reference heading: median "
            << at(0.5) << " deg, 68% within " << at(0.68) << ", at most " << errors.back() << " ("
            << errors.size() << " walls)\n";
}

void printCarmenSetup(const carmen::CarmenLog& log, const flag::CarmenFlag& cf,
                      const flag::CarmenFlagOptions& c, const flag::FlagOptions& base,
                      const CarmenDetectorScores& d, std::uint64_t seed) {
  const std::size_t start_scan = cf.scans.evaluated.front();
  std::cout << std::fixed << std::setprecision(3) << "hamal_flag: " << FLAGS_data << ", "
            << cf.scans.map.size() << " key scans make the map, " << cf.recording.steps.size()
            << " evaluated from scan " << start_scan << " (line " << log.scans[start_scan].line
            << "), " << cf.detections << " detections, " << cf.labels.size()
            << (c.landmarks.map_corners
                    ? " landmarks at the corners of " + std::to_string(cf.clusters) + " map walls"
                    : " landmarks (clusters seen >= " + std::to_string(c.landmarks.min_sightings) +
                          " times, of " + std::to_string(cf.clusters) + ")")
            << ", " << FLAGS_odometry << " odometry (per sqrt metre "
            << cf.odometry.model.per_metre[0] << " m, " << cf.odometry.model.per_metre[1] << " m, "
            << cf.odometry.model.per_metre[2] / kDeg << " deg, per sqrt radian "
            << cf.odometry.model.per_radian / kDeg << " deg, latency " << cf.odometry.latency
            << " s, times " << base.odometry.scale << ", jitter " << base.odometry.jitter_xy
            << " m, " << base.odometry.jitter_theta / kDeg << " deg), seed " << seed << "\n";
  const flag::StableEdgeOptions& st = cf.stable_edges;
  std::ostringstream check;
  check << "stable-edge check " << (st.enabled ? "on" : "off");
  if (st.enabled)
    check << ": seen again by " << st.min_scans << " of the " << st.window
          << " scans before and after within " << st.radius << " m";
  if (st.enabled && st.spacing > 0)
    check << ", those " << st.spacing << " m or " << st.spacing_turn / kDeg << " deg apart";
  if (c.landmarks.map_corners)
    std::cout << "  detector (" << check.str() << ") on the " << d.detector.scans
              << " held-out key scans against the map's corners in view within "
              << FLAGS_sensor_range << " m (a hit within 0.3 m): precision "
              << d.detector.precision() << " (" << d.detector.true_positives << " of "
              << d.detector.detections << " detections), recall " << d.detector.recall() << " ("
              << d.detector.matched_labels << " of " << d.detector.labels
              << " corners in view); on the " << d.mapped.scans
              << " whose returns lie >= 80% on map walls: precision " << d.mapped.precision()
              << ", recall " << d.mapped.recall() << "; against the whole log's corners (the same "
              << "procedure on every key scan): precision " << d.detector_log.precision() << " ("
              << d.detector_log.true_positives << " of " << d.detector_log.detections
              << "), recall " << d.detector_log.recall() << " (" << d.detector_log.matched_labels
              << " of " << d.detector_log.labels << ")\n";
  if (!cf.odometry.consistency.empty()) {
    std::cout << "  odometry against the reference on the map part, scale per window of k steps:";
    for (const flag::OdometryConsistency& k : cf.odometry.consistency)
      std::cout << " k=" << k.window << ":" << k.scale;
    std::cout << "\n";
  }
  printWallErrors(cf);
}

// One CSV row: an arm's run on one seed (r: none for dead reckoning).
void writeCarmenRow(std::ostream& csv, std::uint64_t seed, const flag::CarmenFlag& cf,
                    const flag::CarmenFlagOptions& c, const flag::FlagOptions& base,
                    const CarmenDetectorScores& d, const char* arm, double ate, double online,
                    const flag::FlagRun* r) {
  csv << FLAGS_data.substr(FLAGS_data.find_last_of('/') + 1) << ',' << seed << ',' << FLAGS_odometry
      << ',' << FLAGS_map_fraction << ',' << cf.scans.evaluated.front() << ','
      << cf.recording.steps.size() << ',' << cf.labels.size() << ',' << base.odometry.scale << ','
      << arm << ',' << ate << ',' << online << ',';
  if (r) {
    const flag::AssociationStats& s = r->stats;
    csv << s.precision() << ',' << s.recall() << ',' << s.accepted << ',' << s.corner_detections
        << ',' << s.associated_correct << ',' << s.rejected << ',' << s.rejected_correct << ','
        << s.rejected_correct_few << ',' << s.rejected_correct_inconsistent << ','
        << s.gate_lost.outside << ',' << s.gate_lost.other_landmark << ',' << s.gate_lost.walls
        << ',' << r->factors.null_active << ',' << r->factors.null_active_right << ','
        << r->lost.steps << ',' << r->lost.first << ','
        << (!r->ok          ? "failed"
            : r->lost.steps ? "lost"
                            : "ok")
        << ',' << r->ok;
  } else {
    csv << ",,,,,,,,,,,,,,,,ok,1";
  }
  if (c.landmarks.map_corners)
    csv << ',' << d.detector.precision() << ',' << d.detector.recall() << ','
        << d.detector.detections << ',' << d.detector.labels << ',' << d.detector_log.precision()
        << ',' << d.detector_log.recall() << '\n';
  else
    csv << ",,,,,,\n";
}

// --trajectory: an arm's poses as the ATE grades them (the final estimate;
// dead reckoning with the known association's run), with the factors
// accepted so far.
void writeCarmenTrajectory(std::ostream& f, std::uint64_t seed, bool known,
                           const flag::FlagRun& r) {
  const auto row = [&](const char* arm, std::size_t i, const Pose2& p, std::size_t factors) {
    const Pose2& t = r.truth[i];
    f << seed << ',' << arm << ',' << i << ',' << t.x << ',' << t.y << ',' << t.theta << ',' << p.x
      << ',' << p.y << ',' << p.theta << ',' << factors << '\n';
  };
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    if (known) row("dead reckoning", i, r.dead_reckoning[i], 0);
    row(known ? "known association" : "FLAG", i, r.final_estimate.pose(X(i)), r.factors.so_far[i]);
  }
}

// One arm's run on stdout.
void printCarmenArm(bool known, const flag::FlagRun& r, double ate, double dr_ate) {
  const flag::AssociationStats& s = r.stats;
  std::cout << "  " << (known ? "known association" : "FLAG") << ": ATE " << ate
            << " m, online mean error " << r.flag.position << " m (dead reckoning "
            << r.odometry.position << " m, ATE " << dr_ate << " m), association precision "
            << s.precision() << " recall " << s.recall() << ", " << s.accepted
            << " factors; pairwise check: " << s.associated_correct << " of " << s.corner_detections
            << " corner detections associated right (the gate: " << s.gate_lost.outside
            << " without a landmark, " << s.gate_lost.other_landmark << " given another, "
            << s.gate_lost.walls << " refused by the walls), dropped " << s.rejected << " ("
            << s.rejected_correct << " right: " << s.rejected_correct_few << " too few sightings, "
            << s.rejected_correct_inconsistent
            << " inconsistent); max-mixture: " << r.factors.null_active << " of "
            << r.factors.mixtures << " switched off (" << r.factors.null_active_right
            << " right); p99 step " << ms(r.steps.seconds, 99) << " ms wall, "
            << ms(r.steps.cpu_seconds, 99) << " ms thread CPU"
            << (r.lost.steps ? ", lost at " + std::to_string(r.lost.steps) + " poses from pose " +
                                   std::to_string(r.lost.first)
                             : std::string())
            << (r.ok ? "" : ", back-end failed: " + r.status) << "\n";
}

// FLAG on a real laser log: a map from one part, evaluated on the other.
// Prints one run per seed, or with --output writes CSV rows (one per arm
// and seed) for scripts/flag.sh carmen.
int carmenLog(const Registry& registry, const std::vector<std::string>& args) {
  checkCarmenCommandLine(args);
  const carmen::CarmenLog log = carmen::readCarmenLog(FLAGS_data, carmen::readOptionsFromFlags());
  Output o;
  std::ostream& csv = o.out();
  const bool rows = !FLAGS_output.empty();
  if (rows)
    csv << std::setprecision(6)
        << "log,seed,odometry,map_fraction,start_scan,poses,landmarks,odometry_scale,arm,ate_m,"
           "online_mean_m,precision,recall,factors,corner_detections,associated_correct,"
           "rejected,rejected_correct,rejected_correct_few,rejected_correct_inconsistent,"
           "corner_outside_gate,corner_wrong_landmark,corner_wrong_walls,null_active,null_active_"
           "right,lost_steps,"
           "first_lost,status,ok,detector_precision,detector_recall,detector_detections,"
           "detector_labels,detector_precision_log,detector_recall_log\n";
  std::unique_ptr<OutputFile> trajectory;
  if (!FLAGS_trajectory.empty()) {
    trajectory = std::make_unique<OutputFile>(FLAGS_trajectory);
    trajectory->stream() << std::setprecision(10)
                         << "seed,arm,pose,truth_x,truth_y,truth_theta,x,y,theta,factors\n";
  }
  for (std::uint64_t seed = FLAGS_seed; seed - FLAGS_seed < FLAGS_trials; ++seed) {
    const flag::CarmenFlagOptions c = carmenFlagOptions(seed);
    const flag::CarmenFlag cf = flag::prepareCarmenFlag(log, c);
    const CarmenDetectorScores detector = scoreCarmenDetector(log, cf, c, seed);
    flag::FlagOptions base = flagOptions();
    if (!flagGiven("odometry_scale")) base.odometry.scale = cf.odometry.scale;
    if (!flagGiven("odometry_jitter_xy") && !flagGiven("odometry_jitter_theta_deg")) {
      base.odometry.jitter_xy = cf.odometry.jitter.xy;
      base.odometry.jitter_theta = cf.odometry.jitter.theta;
    }
    if (!rows) printCarmenSetup(log, cf, c, base, detector, seed);
    Values truth;
    for (std::size_t i = 0; i < cf.recording.steps.size(); ++i)
      truth.insert(X(i), cf.recording.steps[i].truth);
    for (bool known : {true, false}) {
      flag::FlagOptions opt = base;
      opt.association.known = known;
      const flag::FlagRun r = flag::runFlag(cf.labels, cf.recording, opt, registry);
      Values est, dr;
      for (std::size_t i = 0; i < r.truth.size(); ++i) {
        est.insert(X(i), r.final_estimate.pose(X(i)));
        dr.insert(X(i), r.dead_reckoning[i]);
      }
      const double ate = absoluteTrajectoryError(est, truth, false).translation_rmse;
      const double dr_ate = absoluteTrajectoryError(dr, truth, false).translation_rmse;
      if (trajectory) writeCarmenTrajectory(trajectory->stream(), seed, known, r);
      if (rows) {
        if (known)
          writeCarmenRow(csv, seed, cf, c, base, detector, "dead reckoning", dr_ate,
                         r.odometry.position, nullptr);
        writeCarmenRow(csv, seed, cf, c, base, detector, known ? "known association" : "FLAG", ate,
                       r.flag.position, &r);
        continue;
      }
      printCarmenArm(known, r, ate, dr_ate);
    }
  }
  o.commit();
  if (trajectory) trajectory->commit();
  return 0;
}

int flagMain(const std::vector<std::string>& plugins, const std::vector<std::string>& args) {
  Registry registry;
  setUpRegistry(registry, plugins);
  if (printListings(registry)) return 0;
  if (args.empty()) throw Error("give a command: world, run, trials or victoria (see --help)");
  checkOutputPaths({{"output", FLAGS_output},
                    {"trajectory", FLAGS_trajectory},
                    {"landmarks_out", FLAGS_landmarks_out}},
                   {{"world", FLAGS_world}, {"data", FLAGS_data}});
  if (args[0] == "world") return world(args);
  if (args[0] == "run") return run(registry, args);
  if (args[0] == "trials") return trials(registry, args);
  if (args[0] == "victoria") return victoria(registry, args);
  if (args[0] == "carmen") return carmenLog(registry, args);
  throw Error("unknown command '" + args[0] + "' (world, run, trials, victoria, carmen)");
}

}  // namespace
}  // namespace hamal::apps

int main(int argc, char** argv) {
  return hamal::apps::runMain("hamal_flag", [&] {
    const auto plugins = hamal::apps::repeatedFlag(argc, argv, "plugin");
    const auto positional = hamal::apps::parseCommandLine(&argc, &argv, hamal::apps::kUsage);
    return hamal::apps::flagMain(plugins, positional);
  });
}
