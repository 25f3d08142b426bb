// The simulated robot and detector (simulator.h; thesis sec. 4.3.2, 4.4.2).
#include "apps/flag/simulator.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include "apps/flag/corner_visibility.h"
#include "core/error.h"

namespace hamal::flag {

void SimulatorOptions::validate() const {
  const auto got = [](double v) {
    std::ostringstream os;
    os << v;
    return os.str();
  };
  const auto positive = [&](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw Error(std::string(name) + " must be > 0 and finite, got " + got(v));
  };
  const auto nonnegative = [&](double v, const char* name) {
    if (!(v >= 0) || !std::isfinite(v))
      throw Error(std::string(name) + " must be >= 0 and finite, got " + got(v));
  };
  positive(step, "step");
  positive(speed, "speed");
  positive(sensor_range, "sensor range");
  nonnegative(noise.odom_sigma_x, "world odometry sigma x");
  nonnegative(noise.odom_sigma_y, "world odometry sigma y");
  nonnegative(noise.odom_sigma_theta, "world odometry sigma theta");
  nonnegative(noise.range_sigma, "world range sigma");
  nonnegative(noise.bearing_sigma, "world bearing sigma");
  nonnegative(min_height, "minimum height");
  // What the factors assume; zero would be infinite information.
  positive(stated.odom_sigma_x, "odometry sigma x");
  positive(stated.odom_sigma_y, "odometry sigma y");
  positive(stated.odom_sigma_theta, "odometry sigma theta");
  positive(stated.range_sigma, "range sigma");
  positive(stated.bearing_sigma, "bearing sigma");
  positive(match_radius, "match radius");
  scanner.validate();
  edges.validate();
}

Eigen::Vector3d odometrySigmas(double ox, double oy, double otheta, double d) {
  const double s = std::sqrt(std::max(d, 0.0));
  return {ox * s, oy * s, otheta * s};
}

std::vector<Pose2> samplePath(const std::vector<Point2>& path, double step) {
  std::vector<Pose2> poses;
  if (path.size() < 2) return poses;
  double carried = 0;  // distance along the current leg where the next pose falls
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Point2 a = path[i - 1], b = path[i];
    const double len = (b - a).norm();
    if (len == 0) continue;
    const double heading = std::atan2(b.y() - a.y(), b.x() - a.x());
    double s = carried;
    for (; s < len - 1e-9; s += step) {
      const Point2 p = a + (b - a) * (s / len);
      poses.emplace_back(p.x(), p.y(), heading);
    }
    carried = s - len;
  }
  const Point2 end = path.back(), before = path[path.size() - 2];
  poses.emplace_back(end.x(), end.y(), std::atan2(end.y() - before.y(), end.x() - before.x()));
  return poses;
}

std::vector<Detection> detect(const FloorPlan& plan, const Pose2& pose, double time,
                              const SimulatorOptions& options) {
  std::vector<Detection> out;
  const Point2 t = pose.t();
  const auto add = [&](const Point2& p, Source source, bool occludable) {
    const Point2 d = p - t;
    const double r = d.norm();
    if (r > options.sensor_range || r < 1e-3) return;
    if (occludable)
      for (const Wall& w : plan.walls)
        if (segmentBlocked(t, p, w)) return;
    Detection det;
    det.range = r;
    det.bearing = wrapAngle(std::atan2(d.y(), d.x()) - pose.theta);
    det.range_sigma = options.stated.range_sigma;
    det.bearing_sigma = options.stated.bearing_sigma;
    det.source = source;
    out.push_back(det);
  };
  for (const Corner& c : plan.corners) {
    bool hidden = false;
    for (const StaticObject& o : plan.objects)
      if (o.hides == static_cast<std::int64_t>(c.id) && o.height >= options.min_height)
        hidden = true;
    if (!hidden) add(c.truth, {Source::kCorner, c.id}, true);
  }
  for (std::size_t i = 0; i < plan.objects.size(); ++i)
    if (plan.objects[i].height >= options.min_height)
      add(plan.objects[i].position, {Source::kObject, i}, true);
  for (std::size_t i = 0; i < plan.people.size(); ++i) {
    Point2 p;
    if (plan.people[i].at(time, &p)) add(p, {Source::kPerson, i}, true);
  }
  return out;
}

std::vector<Detection> detectInScan(const FloorPlan& plan, const Pose2& pose, double time,
                                    const SimulatorOptions& options, std::mt19937_64* rng) {
  RangeScannerOptions scanner = options.scanner;
  scanner.max_range = options.sensor_range;
  VerticalEdgeDetectorOptions edges = options.edges;
  edges.min_height = options.min_height;
  const RangeScan scan = castRangeScan(plan, pose, time, scanner, rng);
  std::vector<Detection> out;
  for (const VerticalEdge& e : detectVerticalEdges(scan, edges)) {
    Detection d;
    d.range = e.range;
    d.bearing = e.bearing;
    d.range_sigma = options.stated.range_sigma;
    d.bearing_sigma = options.stated.bearing_sigma;
    d.source = sourceOf(plan, pose.transformFrom(e.position), time, scanner, options.match_radius);
    out.push_back(d);
  }
  return out;
}

Recording simulate(const FloorPlan& plan, const SimulatorOptions& options) {
  options.validate();
  std::mt19937_64 rng(options.seed);
  // Detections draw from a stream of their own, so both detectors see the same odometry.
  std::mt19937_64 detection_rng(options.seed ^ 0x5ca9e5ca9e5ca9e5ULL);
  // One distribution per engine: a distribution keeps the second draw of a pair.
  std::normal_distribution<double> n01(0.0, 1.0), detection_n01(0.0, 1.0);
  Recording rec;
  rec.odom_sigma_x = options.stated.odom_sigma_x;
  rec.odom_sigma_y = options.stated.odom_sigma_y;
  rec.odom_sigma_theta = options.stated.odom_sigma_theta;
  const std::vector<Pose2> truth = samplePath(plan.path, options.step);
  double time = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    RecordedStep s;
    s.truth = truth[i];
    if (i > 0) {
      const Pose2 delta = truth[i - 1].between(truth[i]);
      s.distance = std::hypot(delta.x, delta.y);
      time += s.distance / options.speed;
      const Eigen::Vector3d sig =
          odometrySigmas(options.noise.odom_sigma_x, options.noise.odom_sigma_y,
                         options.noise.odom_sigma_theta, s.distance);
      const double ex = n01(rng), ey = n01(rng), et = n01(rng);
      s.odometry =
          Pose2(delta.x + sig[0] * ex, delta.y + sig[1] * ey, wrapAngle(delta.theta + sig[2] * et));
    }
    s.time = time;
    if (options.detector == SimulatorOptions::kScan) {
      s.detections = detectInScan(plan, s.truth, time, options, &detection_rng);
    } else {
      s.detections = detect(plan, s.truth, time, options);
      for (Detection& d : s.detections) {
        const double er = detection_n01(detection_rng), eb = detection_n01(detection_rng);
        d.range += options.noise.range_sigma * er;
        d.bearing = wrapAngle(d.bearing + options.noise.bearing_sigma * eb);
      }
      // After the draws, so that the arm keeps the oracle's noise (paired).
      if (options.detector == SimulatorOptions::kOracleInView) {
        RangeScannerOptions scanner = options.scanner;
        scanner.max_range = options.sensor_range;
        const std::vector<std::uint64_t> in_view =
            visibleCorners(plan, s.truth, time, scanner, options.edges.segments.min_length,
                           options.edges.corners.min_stub_length)
                .in_view;
        std::vector<Detection> kept;
        for (const Detection& d : s.detections)
          if (d.source.kind != Source::kCorner ||
              std::find(in_view.begin(), in_view.end(), d.source.id) != in_view.end())
            kept.push_back(d);
        s.detections = std::move(kept);
      }
    }
    rec.steps.push_back(std::move(s));
  }
  return rec;
}

}  // namespace hamal::flag
