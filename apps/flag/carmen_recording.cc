// FLAG's labelled map and recording from a real CARMEN log (carmen_recording.h).
#include "apps/flag/carmen_recording.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>

#include "apps/flag/odometry_calibration.h"
#include "core/error.h"

namespace hamal::flag {

void CarmenFlagOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string(name) + " must be > 0");
  };
  positive(scans.step, "carmen step");
  positive(scans.turn, "carmen turn");
  positive(landmarks.cluster_radius, "cluster_radius");
  positive(odometry.min_distance, "carmen min distance");
  positive(odometry.stated.x, "odometry sigma x");
  positive(odometry.stated.y, "odometry sigma y");
  positive(odometry.stated.theta, "odometry sigma theta");
  positive(stated_range_sigma, "range sigma");
  positive(stated_bearing_sigma, "bearing sigma");
  if (landmarks.min_sightings < 1) throw Error("min_sightings must be >= 1");
  if (!(odometry.max_latency >= 0) || !std::isfinite(odometry.max_latency))
    throw Error("carmen max latency must be >= 0");
  if (!(map_fraction >= 0 && map_fraction < 1))
    throw Error("map_fraction must be in [0, 1), not " + std::to_string(map_fraction));
  for (double v : {landmarks.label_sigma, odometry.world.x, odometry.world.y, odometry.world.theta})
    if (!(v >= 0) || !std::isfinite(v)) throw Error("label and world odometry sigmas must be >= 0");
  edges.validate();
  map_segments.validate();
  stable_edges.validate();
}

RangeScan rangeScanOf(const carmen::LaserScan& scan) {
  RangeScan r;
  r.start_angle = scan.start_angle;
  r.angular_step = scan.angular_step;
  r.max_range = scan.max_range;
  r.ranges = scan.ranges;
  return r;
}

Pose2 logOdometryAt(const carmen::CarmenLog& log, const carmen::LaserScan& scan, double latency) {
  const std::vector<carmen::OdometryRecord>& odo = log.odometry;
  if (odo.empty()) throw Error(log.file + ": no ODOM records: the log has no odometry of its own");
  const double t = scan.timestamp + latency;
  // The records around the scan's line in the file, then (with a latency)
  // a few records on while the stream's time has not reached t, or back
  // while it is past it: clocks that step back (Intel) stay local.
  auto after =
      std::lower_bound(odo.begin(), odo.end(), scan.line,
                       [](const carmen::OdometryRecord& o, int line) { return o.line < line; });
  for (int k = 0; k < 64 && after != odo.end() && after->timestamp < t; ++k) ++after;
  for (int k = 0; k < 64 && after != odo.begin() && std::prev(after)->timestamp > t; ++k) --after;
  if (after == odo.begin()) return after->pose;
  if (after == odo.end()) return std::prev(after)->pose;
  const carmen::OdometryRecord& a = *std::prev(after);
  const carmen::OdometryRecord& b = *after;
  if (a.timestamp <= t && t <= b.timestamp && b.timestamp > a.timestamp) {
    const double u = (t - a.timestamp) / (b.timestamp - a.timestamp);
    return carmen::interpolateOdometry(a.pose, b.pose, u);
  }
  return std::abs(t - a.timestamp) <= std::abs(b.timestamp - t) ? a.pose : b.pose;
}

Eigen::Vector3d OdometryModel::sigma(const Pose2& step, double min_distance) const {
  const double d = std::max(std::hypot(step.x, step.y), min_distance);
  const Eigen::Vector3d v(
      per_metre[0] * per_metre[0] * d, per_metre[1] * per_metre[1] * d,
      per_metre[2] * per_metre[2] * d + per_radian * per_radian * std::abs(step.theta));
  return v.cwiseSqrt();
}

OdometryModel fitOdometryModel(const std::vector<OdometryStepSample>& steps, double min_distance) {
  if (steps.empty()) throw Error("odometry calibration: no odometry steps to fit");
  // x, y: sigma^2 = k^2 d, the mean of e^2 / d. theta: e^2 = a d + b |turn|
  // by least squares, b dropped if negative (then a as x and y).
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (const OdometryStepSample& s : steps) {
    const Eigen::Vector3d e(s.odometry.x - s.reference.x, s.odometry.y - s.reference.y,
                            wrapAngle(s.odometry.theta - s.reference.theta));
    const double d = std::max(s.distance, min_distance);
    sum += e.cwiseProduct(e) / d;
    const Eigen::Vector2d f(d, std::abs(s.odometry.theta));
    A += f * f.transpose();
    rhs += f * e[2] * e[2];
  }
  OdometryModel m;
  m.per_metre = (sum / double(steps.size())).cwiseSqrt();
  const Eigen::Vector2d ab = A.ldlt().solve(rhs);
  if (ab.allFinite() && ab[0] >= 0 && ab[1] >= 0) {
    m.per_metre[2] = std::sqrt(ab[0]);
    m.per_radian = std::sqrt(ab[1]);
  } else if (ab.allFinite() && ab[1] > 0 && A(1, 1) > 0) {
    m.per_metre[2] = 0;
    m.per_radian = std::sqrt(rhs[1] / A(1, 1));
  }
  // A floor keeps a perfect odometry's factors finite.
  m.per_metre = m.per_metre.cwiseMax(Eigen::Vector3d(1e-4, 1e-4, 1e-6));
  return m;
}

std::size_t seedStart(std::uint64_t seed, std::size_t choices) {
  if (choices == 0) throw Error("seedStart: no start to choose from");
  // A Fisher-Yates shuffle of 0..choices-1 by a fixed generator (written
  // out: std::shuffle's draws differ between standard libraries), so the
  // order depends on the log only through `choices`.
  std::vector<std::size_t> order(choices);
  for (std::size_t i = 0; i < choices; ++i) order[i] = i;
  std::mt19937_64 rng(0x5ca1ab1e5eedULL);
  for (std::size_t i = choices - 1; i > 0; --i) std::swap(order[i], order[rng() % (i + 1)]);
  return order[(seed % choices + choices - 1) % choices];  // seed 0: the last of the order
}

namespace {

// The key scans and the split: the map part is the key scans before the
// first one at or past the cut in time; the rest are evaluated (from `first`).
struct KeyScanSplit {
  std::vector<const carmen::LaserScan*> kept;
  std::size_t split = 0, map_end = 0, first = 0;
};

KeyScanSplit splitKeyScans(const carmen::CarmenLog& log, const CarmenFlagOptions& options) {
  KeyScanSplit k;
  k.kept = carmen::keyScans(log, options.scans);
  const std::vector<const carmen::LaserScan*>& kept = k.kept;
  std::size_t split = kept.size();
  if (options.map_fraction > 0) {
    const double cut = kept.front()->timestamp +
                       options.map_fraction * (kept.back()->timestamp - kept.front()->timestamp);
    split = 0;
    while (split < kept.size() && kept[split]->timestamp < cut) ++split;
    if (split == 0 || kept.size() - split < 2)
      throw Error(log.file + ": map_fraction " + std::to_string(options.map_fraction) +
                  " leaves no map part or fewer than two evaluated key scans");
  }
  // Which scans make the map, which are evaluated (from `first`).
  k.split = split;
  k.map_end = split == kept.size() ? kept.size() : split;
  k.first = 0;
  if (options.map_fraction > 0)
    k.first = split + seedStart(options.seed, std::max<std::size_t>(1, (kept.size() - split) / 2));
  return k;
}

// Detections in each kept scan (map part and evaluated), in the robot frame,
// those the stability check keeps (stable_edge_filter.h, at the odometry's
// latency `latency`).
std::vector<std::vector<VerticalEdge>> detectKeyScanEdges(const carmen::CarmenLog& log,
                                                          const KeyScanSplit& k,
                                                          const CarmenFlagOptions& options,
                                                          double latency) {
  StableEdgeFilter detector(log, options.scans.tag, options.edges, options.stable_edges, latency);
  std::vector<std::vector<VerticalEdge>> edges(k.kept.size());
  for (std::size_t i = 0; i < k.kept.size(); ++i) {
    if (i >= k.map_end && i < k.first) continue;  // neither map nor evaluated
    edges[i] = detector.detect(std::size_t(k.kept[i] - &log.scans[0]));
    for (VerticalEdge& e : edges[i]) {
      e.position = k.kept[i]->laser_offset.transformFrom(e.position);
      e.range = e.position.norm();
      e.bearing = std::atan2(e.position.y(), e.position.x());
      for (double& w : e.walls) w += k.kept[i]->laser_offset.theta;
    }
  }
  return edges;
}

// The landmarks as the corners of the walls merged from the map part's
// line segments; the same procedure on every key scan gives the detector's
// second labelled set.
std::vector<MapCorner> wallCornerLandmarks(const KeyScanSplit& k, const CarmenFlagOptions& options,
                                           CarmenFlag& out) {
  const auto segmentsOf = [&](std::size_t from, std::size_t to) {
    std::vector<WallSegment> segments;
    for (std::size_t i = from; i < to; ++i) {
      const carmen::LaserScan* s = k.kept[i];
      for (const LineSegment& l : extractLineSegments(rangeScanOf(*s), options.map_segments))
        segments.push_back({s->pose.transformFrom(s->laser_offset.transformFrom(l.a)),
                            s->pose.transformFrom(s->laser_offset.transformFrom(l.b))});
    }
    return segments;
  };
  std::vector<WallSegment> segments = segmentsOf(0, k.map_end);
  out.walls = mergeWalls(segments, options.landmarks.walls);
  std::vector<MapCorner> corners = wallCornerShapes(out.walls, options.landmarks.walls);
  out.clusters = out.walls.size();
  // The same procedure on every key scan: the detector's second labelled set.
  const std::vector<WallSegment> rest = segmentsOf(k.map_end, k.kept.size());
  segments.insert(segments.end(), rest.begin(), rest.end());
  out.log_walls = mergeWalls(segments, options.landmarks.walls);
  out.log_corners = wallCorners(out.log_walls, options.landmarks.walls);
  return corners;
}

// The landmarks as the clusters of the map part's detections in the world
// seen at least min_sightings times (their walls' directions not kept).
std::vector<MapCorner> clusteredEdgeLandmarks(const KeyScanSplit& k,
                                              const std::vector<std::vector<VerticalEdge>>& edges,
                                              const CarmenFlagOptions& options, CarmenFlag& out) {
  struct Cluster {
    Point2 sum = Point2::Zero();
    int n = 0;
    Point2 mean() const { return sum / double(n); }
  };
  std::vector<Cluster> clusters;
  for (std::size_t i = 0; i < k.map_end; ++i)
    for (const VerticalEdge& e : edges[i]) {
      const Point2 w = k.kept[i]->pose.transformFrom(e.position);
      std::size_t c = 0;
      while (c < clusters.size() &&
             (clusters[c].mean() - w).norm() > options.landmarks.cluster_radius)
        ++c;
      if (c == clusters.size()) clusters.emplace_back();
      clusters[c].sum += w;
      ++clusters[c].n;
    }
  std::vector<MapCorner> corners;
  for (const Cluster& c : clusters)
    if (c.n >= options.landmarks.min_sightings) corners.push_back({c.mean(), {}});
  out.clusters = clusters.size();
  return corners;
}

// The landmarks and their labels; labels draw from a stream of their own, so
// the odometry does not change with the count of landmarks.
void labelLandmarks(const std::vector<MapCorner>& corners, const CarmenFlagOptions& options,
                    CarmenFlag& out) {
  std::mt19937_64 label_rng(options.seed);
  std::normal_distribution<double> label_n01(0.0, 1.0);
  for (std::size_t k = 0; k < corners.size(); ++k) {
    out.landmarks.push_back(corners[k].position);
    const double dx = label_n01(label_rng), dy = label_n01(label_rng);
    out.labels.push_back({std::uint64_t(k),
                          corners[k].position + options.landmarks.label_sigma * Point2(dx, dy),
                          corners[k].walls});
  }
}

// The map part's odometry steps read at a latency, against the reference.
std::vector<OdometryStepSample> mapOdometrySamples(const carmen::CarmenLog& log,
                                                   const KeyScanSplit& k, double latency) {
  std::vector<OdometryStepSample> samples;
  Pose2 previous = logOdometryAt(log, *k.kept[0], latency);
  for (std::size_t i = 1; i < k.map_end; ++i) {
    const Pose2 now = logOdometryAt(log, *k.kept[i], latency);
    const Pose2 o = previous.between(now);
    samples.push_back({o, k.kept[i - 1]->pose.between(k.kept[i]->pose), std::hypot(o.x, o.y)});
    previous = now;
  }
  return samples;
}

// The latency: the one of a grid over [-max_latency, max_latency] whose
// steps disagree least with the reference (squared metres plus squared
// radians).
void calibrateOdometryLatency(const carmen::CarmenLog& log, const KeyScanSplit& k,
                              const CarmenFlagOptions& options, CarmenFlag& out) {
  double best = std::numeric_limits<double>::infinity();
  if (options.odometry.calibrate && options.odometry.max_latency > 0)
    for (int g = -20; g <= 20; ++g) {
      const double latency = options.odometry.max_latency * g / 20.0;
      double cost = 0;
      for (const OdometryStepSample& s : mapOdometrySamples(log, k, latency))
        cost += (s.odometry.t() - s.reference.t()).squaredNorm() +
                std::pow(wrapAngle(s.odometry.theta - s.reference.theta), 2);
      if (cost < best) best = cost, out.odometry.latency = latency;
    }
}

// The window scale (odometry_calibration.h) on the map part.
void calibrateOdometryScale(const KeyScanSplit& k, const std::vector<OdometryStepSample>& samples,
                            const std::vector<std::vector<VerticalEdge>>& edges,
                            const OdometryModel& model, const CarmenFlagOptions& options,
                            CarmenFlag& out) {
  Recording training;
  for (std::size_t i = 0; i < k.map_end; ++i) {
    RecordedStep s;
    s.truth = k.kept[i]->pose;
    if (i > 0) {
      s.odometry = samples[i - 1].odometry;
      s.distance = samples[i - 1].distance;
      s.odometry_sigma = model.sigma(s.odometry, options.odometry.min_distance);
    }
    s.detections.resize(edges[i].size());
    training.steps.push_back(std::move(s));
  }
  if (options.odometry.calibrate && training.steps.size() >= 2) {
    out.odometry.consistency = odometryConsistency(training, longestCoast(training));
    // The scale at the longest window, not the largest: a log's odometry
    // errors need not accumulate (the Radish logs' are mostly a jitter
    // of the odometry's clock against the laser's, which the longer
    // windows average out), and it is over long coasts that the gate
    // and the factors must match the drift.
    if (!out.odometry.consistency.empty())
      out.odometry.scale = std::max(1e-3, out.odometry.consistency.back().scale);
    if (options.odometry.fit_jitter) {
      out.odometry.jitter = odometryJitter(training);
      const std::size_t window = std::min(longestCoast(training), training.steps.size() - 1);
      out.odometry.scale = driftScale(training, window, out.odometry.jitter);
    }
  }
}

// The log's odometry at each used key scan (at the latency already
// calibrated, out.odometry.latency), its model fitted on the map part's steps (the stated model
// without calibration).
OdometryModel calibrateLogOdometry(const carmen::CarmenLog& log, const KeyScanSplit& k,
                                   const OdometryModel& stated,
                                   const std::vector<std::vector<VerticalEdge>>& edges,
                                   const CarmenFlagOptions& options, std::vector<Pose2>& odometry,
                                   CarmenFlag& out) {
  OdometryModel model = stated;
  for (std::size_t i = 0; i < k.kept.size(); ++i)
    if (i < k.map_end || i >= k.first)
      odometry[i] = logOdometryAt(log, *k.kept[i], out.odometry.latency);
  const std::vector<OdometryStepSample> samples = mapOdometrySamples(log, k, out.odometry.latency);
  if (options.odometry.calibrate) model = fitOdometryModel(samples, options.odometry.min_distance);
  calibrateOdometryScale(k, samples, edges, model, options, out);
  return model;
}

// A detection's source (grading only) is the landmark it lies near.
long landmarkNear(const Point2& w, const std::vector<Point2>& corners, double cluster_radius) {
  long best = -1;
  double best_d = cluster_radius;
  for (std::size_t k = 0; k < corners.size(); ++k)
    if ((corners[k] - w).norm() <= best_d) best_d = (corners[best = long(k)] - w).norm();
  return best;
}

// The evaluated key scans as the recording's steps: odometry (the log's, or
// the reference's with drawn noise from a stream of its own) and detections.
void recordEvaluatedSteps(const KeyScanSplit& k,
                          const std::vector<std::vector<VerticalEdge>>& edges,
                          const std::vector<Point2>& corners, const std::vector<Pose2>& odometry,
                          const OdometryModel& model, const CarmenFlagOptions& options,
                          CarmenFlag& out) {
  const bool log_odometry = options.odometry.source == CarmenFlagOptions::Odometry::kLog;
  std::mt19937_64 rng(options.seed ^ 0x0d0e7e70d0e7e7ULL);
  std::normal_distribution<double> n01(0.0, 1.0);
  const std::vector<const carmen::LaserScan*>& kept = k.kept;
  Recording& rec = out.recording;
  for (std::size_t i = k.first; i < kept.size(); ++i) {
    RecordedStep s;
    s.truth = kept[i]->pose;
    s.time = kept[i]->timestamp;
    if (i > k.first) {
      const Pose2 delta = kept[i - 1]->pose.between(kept[i]->pose);
      if (log_odometry) {
        s.odometry = odometry[i - 1].between(odometry[i]);
        s.distance = std::hypot(s.odometry.x, s.odometry.y);
      } else {
        s.distance = std::hypot(delta.x, delta.y);
        const Eigen::Vector3d drawn = odometrySigmas(
            options.odometry.world.x, options.odometry.world.y, options.odometry.world.theta,
            std::max(s.distance, options.odometry.min_distance));
        const double ex = n01(rng), ey = n01(rng), et = n01(rng);
        s.odometry = Pose2(delta.x + drawn[0] * ex, delta.y + drawn[1] * ey,
                           wrapAngle(delta.theta + drawn[2] * et));
      }
      s.odometry_sigma = model.sigma(s.odometry, options.odometry.min_distance);
    }
    for (std::size_t j = 0; j < edges[i].size(); ++j) {
      Detection d;
      d.range = edges[i][j].range;
      d.bearing = edges[i][j].bearing;
      d.range_sigma = options.stated_range_sigma;
      d.bearing_sigma = options.stated_bearing_sigma;
      d.walls = edges[i][j].walls;
      const long lm = landmarkNear(kept[i]->pose.transformFrom(edges[i][j].position), corners,
                                   options.landmarks.cluster_radius);
      d.source = lm >= 0 ? Source{Source::kCorner, std::uint64_t(lm)} : Source{Source::kNone, 0};
      if (options.exact_detections && lm >= 0) {
        const Point2 local = kept[i]->pose.transformTo(corners[std::size_t(lm)]);
        d.range = local.norm();
        d.bearing = std::atan2(local.y(), local.x());
      }
      s.detections.push_back(d);
      ++out.detections;
    }
    rec.steps.push_back(std::move(s));
  }
}

}  // namespace

CarmenFlag prepareCarmenFlag(const carmen::CarmenLog& log, const CarmenFlagOptions& options) {
  options.validate();
  if (options.landmarks.map_corners) options.landmarks.walls.validate();
  const KeyScanSplit k = splitKeyScans(log, options);
  const auto indexOf = [&](const carmen::LaserScan* s) { return std::size_t(s - &log.scans[0]); };
  CarmenFlag out;
  for (std::size_t i = 0; i < k.map_end; ++i) out.scans.map.push_back(indexOf(k.kept[i]));
  for (std::size_t i = k.first; i < k.kept.size(); ++i)
    out.scans.evaluated.push_back(indexOf(k.kept[i]));
  for (std::size_t i = k.split == k.kept.size() ? 0 : k.split; i < k.kept.size(); ++i)
    out.scans.held_out.push_back(indexOf(k.kept[i]));
  // The odometry's latency first: the stability check reads the odometry at it.
  if (options.odometry.source == CarmenFlagOptions::Odometry::kLog)
    calibrateOdometryLatency(log, k, options, out);
  out.stable_edges = options.stable_edges;
  const std::vector<std::vector<VerticalEdge>> edges =
      detectKeyScanEdges(log, k, options, out.odometry.latency);
  // The landmarks, from the map part alone.
  const std::vector<MapCorner> shapes = options.landmarks.map_corners
                                            ? wallCornerLandmarks(k, options, out)
                                            : clusteredEdgeLandmarks(k, edges, options, out);
  std::vector<Point2> corners;
  for (const MapCorner& c : shapes) corners.push_back(c.position);
  if (corners.empty())
    throw Error(log.file +
                (options.landmarks.map_corners
                     ? std::string(": the map's walls make no corner")
                     : ": no corner was seen " + std::to_string(options.landmarks.min_sightings) +
                           " times (min_sightings)") +
                ": no landmark to localize against");
  labelLandmarks(shapes, options, out);
  std::vector<Pose2> odometry(k.kept.size());
  OdometryModel model;
  model.per_metre = Eigen::Vector3d(options.odometry.stated.x, options.odometry.stated.y,
                                    options.odometry.stated.theta);
  if (options.odometry.source == CarmenFlagOptions::Odometry::kLog)
    model = calibrateLogOdometry(log, k, model, edges, options, odometry, out);
  out.odometry.model = model;
  Recording& rec = out.recording;
  rec.odom_sigma_x = model.per_metre[0];
  rec.odom_sigma_y = model.per_metre[1];
  rec.odom_sigma_theta = model.per_metre[2];
  recordEvaluatedSteps(k, edges, corners, odometry, model, options, out);
  return out;
}

}  // namespace hamal::flag
