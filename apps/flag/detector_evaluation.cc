// The vertical-edge detector against a map's visible corners (detector_evaluation.h).
#include "apps/flag/detector_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <tuple>

#include "core/error.h"

namespace hamal::flag {
namespace {

double cross(const Point2& a, const Point2& b) { return a.x() * b.y() - a.y() * b.x(); }

// True when wall w crosses the segment from o to c farther than `margin` from c.
bool hides(const MapWall& w, const Point2& o, const Point2& c, double margin) {
  const Point2 r = c - o, s = w.b - w.a;
  const double denom = cross(r, s);
  if (std::abs(denom) < 1e-12) return false;
  const double t = cross(w.a - o, s) / denom, u = cross(w.a - o, r) / denom;
  return t > 0 && t * r.norm() < r.norm() - margin && u >= 0 && u <= 1;
}

}  // namespace

void DetectorEvaluationOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string(name) + " must be > 0");
  };
  positive(radius, "detector evaluation radius");
  positive(max_range, "detector evaluation max range");
  positive(arm, "detector evaluation arm");
  positive(on_wall, "detector evaluation on_wall");
  if (!(mapped_share >= 0 && mapped_share <= 1))
    throw Error("detector evaluation mapped_share must be in [0, 1]");
  positive(wall_end_radius, "detector evaluation wall end radius");
  if (walls_seen < 0 || walls_seen > 2)
    throw Error("detector evaluation walls_seen must be 0, 1 or 2");
  if (!(occlusion_margin >= 0) || !std::isfinite(occlusion_margin))
    throw Error("detector evaluation occlusion margin must be >= 0");
}

DetectorScore& DetectorScore::operator+=(const DetectorScore& o) {
  scans += o.scans;
  detections += o.detections;
  true_positives += o.true_positives;
  labels += o.labels;
  matched_labels += o.matched_labels;
  return *this;
}

std::vector<std::size_t> visibleMapCorners(const std::vector<Point2>& corners,
                                           const std::vector<MapWall>& walls, const Pose2& sensor,
                                           const RangeScan& scan,
                                           const DetectorEvaluationOptions& options) {
  options.validate();
  std::vector<std::size_t> out;
  if (scan.ranges.empty()) return out;
  const double range = std::min(options.max_range, scan.max_range);
  // The field of view, from the first beam's bearing to the last's.
  const double lo = std::min(scan.bearing(0), scan.bearing(scan.ranges.size() - 1));
  const double span = std::abs(scan.angular_step) * double(scan.ranges.size() - 1);
  const long n = long(scan.ranges.size());
  const auto seen = [&](const Point2& p) {
    const Point2 local = sensor.transformTo(p);
    if (local.norm() >= range) return false;
    double rel = std::atan2(local.y(), local.x()) - lo;
    rel -= 2 * M_PI * std::floor(rel / (2 * M_PI));
    if (rel > span) return false;
    // Something the map does not hold (a person, a cabinet, a closed door)
    // stands in front when none of the beams at the point's bearing and
    // its two neighbours returns from as far as the point.
    const long beam = std::lround(rel / std::abs(scan.angular_step));
    bool reached = false;
    for (long b = std::max(0L, beam - 1); b <= std::min(n - 1, beam + 1); ++b) {
      const std::size_t i = std::size_t(scan.angular_step > 0 ? b : n - 1 - b);
      reached =
          reached || (scan.hit(i) && scan.ranges[i] >= local.norm() - options.occlusion_margin);
    }
    if (!reached) return false;
    for (const MapWall& w : walls)
      if (hides(w, sensor.t(), p, options.occlusion_margin)) return false;
    return true;
  };
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const Point2& c = corners[k];
    if (!seen(c)) continue;
    // Its walls: the map walls with an end near it, each seen `arm` along.
    int walls_seen = 0;
    for (const MapWall& w : walls) {
      const bool at_a = (w.a - c).norm() <= options.wall_end_radius;
      if (!at_a && (w.b - c).norm() > options.wall_end_radius) continue;
      const Point2 along = at_a ? Point2(w.b - w.a) : Point2(w.a - w.b);
      walls_seen += seen(c + along.normalized() * std::min(options.arm, along.norm()));
    }
    if (walls_seen >= options.walls_seen) out.push_back(k);
  }
  return out;
}

DetectorScore scoreScan(const std::vector<VerticalEdge>& detections, const Pose2& sensor,
                        const std::vector<Point2>& corners, const std::vector<std::size_t>& labels,
                        const DetectorEvaluationOptions& options) {
  options.validate();
  DetectorScore s;
  s.scans = 1;
  s.detections = detections.size();
  s.labels = labels.size();
  // Every pair within the radius, matched closest first, each side once.
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const Point2 w = sensor.transformFrom(detections[i].position);
    for (std::size_t j = 0; j < labels.size(); ++j) {
      const double d = (corners.at(labels[j]) - w).norm();
      if (d <= options.radius) pairs.emplace_back(d, i, j);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<char> used_d(detections.size(), 0), used_l(labels.size(), 0);
  for (const auto& [d, i, j] : pairs) {
    if (used_d[i] || used_l[j]) continue;
    used_d[i] = used_l[j] = 1;
    ++s.true_positives;
  }
  s.matched_labels = s.true_positives;
  return s;
}

double mapCoverage(const RangeScan& scan, const Pose2& sensor, const std::vector<MapWall>& walls,
                   const DetectorEvaluationOptions& options) {
  options.validate();
  std::size_t returns = 0, on = 0;
  for (std::size_t b = 0; b < scan.ranges.size(); ++b) {
    if (!scan.hit(b) || scan.ranges[b] >= options.max_range) continue;
    ++returns;
    const Point2 p = sensor.transformFrom(scan.point(b));
    for (const MapWall& w : walls) {
      const Point2 u = w.b - w.a;
      const double t = std::clamp(u.dot(p - w.a) / std::max(u.squaredNorm(), 1e-12), 0.0, 1.0);
      if ((w.a + t * u - p).norm() <= options.on_wall) {
        ++on;
        break;
      }
    }
  }
  return returns ? double(on) / double(returns) : 0.0;
}

DetectorScore evaluateDetectorOnLog(const carmen::CarmenLog& log, const CarmenFlag& cf,
                                    const VerticalEdgeDetectorOptions& edges,
                                    const DetectorEvaluationOptions& options, DetectorScore* mapped,
                                    bool whole_log) {
  const std::vector<MapWall>& walls = whole_log ? cf.log_walls : cf.walls;
  const std::vector<Point2>& corners = whole_log ? cf.log_corners : cf.landmarks;
  if (walls.empty())
    throw Error(log.file + ": the detector is judged against a map's walls (map_corners)");
  DetectorScore total;
  for (std::size_t i : cf.held_out_scans) {
    const carmen::LaserScan& k = log.scans.at(i);
    const RangeScan scan = rangeScanOf(k);
    const Pose2 sensor = k.pose.compose(k.laser_offset);
    const std::vector<std::size_t> labels =
        visibleMapCorners(corners, walls, sensor, scan, options);
    const DetectorScore one =
        scoreScan(detectVerticalEdges(scan, edges), sensor, corners, labels, options);
    total += one;
    if (mapped && mapCoverage(scan, sensor, walls, options) >= options.mapped_share) *mapped += one;
  }
  return total;
}

}  // namespace hamal::flag
