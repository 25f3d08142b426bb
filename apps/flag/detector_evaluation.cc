// The vertical-edge detector against a map's visible corners (detector_evaluation.h).
#include "apps/flag/detector_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <tuple>

#include "apps/flag/stable_edge_filter.h"
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
  if (wall_returns < 0) throw Error("detector evaluation wall_returns must be >= 0");
  positive(wall_extent, "detector evaluation wall extent");
  if (!(min_wall_angle > 0 && min_wall_angle <= M_PI / 2))
    throw Error("detector evaluation min_wall_angle must be in (0, 90] degrees");
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
  // `in_view` the map's walls as they stand at the corner being judged.
  std::vector<MapWall> in_view;
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
    bool reached = false, through = false;
    for (long b = std::max(0L, beam - 1); b <= std::min(n - 1, beam + 1); ++b) {
      const std::size_t i = std::size_t(scan.angular_step > 0 ? b : n - 1 - b);
      const bool r = scan.hit(i) && scan.ranges[i] >= local.norm() - options.occlusion_margin;
      reached = reached || r;
      through = through || (r && b == std::min(beam, n - 1));
    }
    if (!reached) return false;
    // The beam at its bearing passed where a map wall may be drawn (a
    // wall's extent past its corner, a wall mapped twice a little apart):
    // the map hides nothing the scan saw through.
    if (through) return true;
    for (const MapWall& w : in_view)
      if (hides(w, sensor.t(), p, options.occlusion_margin)) return false;
    return true;
  };
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const Point2& c = corners[k];
    // A wall ending at the corner ends there: its extent past the corner is
    // its segments' ends scattering (map_corners.h), not wall, and would
    // hide the corner's other wall near it from a side that sees both.
    in_view = walls;
    for (MapWall& w : in_view) {
      const Point2 d = w.b - w.a;
      const double s = d.dot(c - w.a) / d.squaredNorm();
      if ((w.a - c).norm() <= options.wall_end_radius && s > 0 && s < 1)
        w.a += s * d;
      else if ((w.b - c).norm() <= options.wall_end_radius && s > 0 && s < 1)
        w.b = w.a + s * d;
    }
    if (!seen(c)) continue;
    // Its walls: the map walls with an end near it, each seen `arm` along,
    // and a wall passing it (a junction's), seen either way; two walls
    // seen count only when they meet at an angle (a thin wall's two faces,
    // or one face in two pieces, are one wall).
    std::vector<Point2> seen_walls;
    // How far along a wall through c along u the beams reach `wall_returns`
    // of it past arm / 2: a wall seen at a small angle to the beams holds
    // few returns in wall_extent, and the returns asked of it are sought as
    // far as that many beams meet it. The beams' spacing grows along such a
    // wall, so the reach is where the ray that many steps on meets the
    // wall's line, not that many of the spacings at c (those fall short of
    // the last return: a wall seen, unlabelled); a ray that never meets it
    // leaves the whole wall to search.
    const double step = std::abs(scan.angular_step);
    const auto reach = [&](const Point2& u) {
      const Point2 from = sensor.transformTo(c + 0.5 * options.arm * u);
      const Point2 ahead = sensor.transformTo(c + (0.5 * options.arm + 1e-3) * u) - from;
      const double turn = cross(from, ahead) >= 0 ? 1.0 : -1.0;  // the bearing's way along u
      const double b = std::atan2(from.y(), from.x()) + turn * options.wall_returns * step;
      const Point2 ray(std::cos(b), std::sin(b));
      const Point2 v = sensor.R().transpose() * u;  // u in the sensor frame
      const double denom = cross(ray, v);
      if (std::abs(denom) < 1e-12) return std::numeric_limits<double>::infinity();
      // from + v t on the ray: cross(ray, from + v t) = 0.
      const double t = -cross(ray, from) / denom;
      if (!(t > 0) || ray.dot(from + v * t) <= 0) return std::numeric_limits<double>::infinity();
      return 0.5 * options.arm + t;
    };
    // The ways the corner's walls that end at it leave it: a return counts
    // for a wall unless it lies ahead along another of them, at
    // min_wall_angle or more from it (closer ones are the same wall's faces
    // or pieces), and nearer that one's line. Within `on_wall` of a wall's
    // line lie the other wall's returns too where the two meet at an oblique
    // angle or the map's line passes a few centimetres off: a corner whose
    // second wall the scan does not hold would be labelled on its first
    // wall's returns. Only walls ending at the corner claim returns: a wall
    // passing it (a junction's) is asked along the directions to its ends,
    // which swing off its line where it passes a little off the corner, and
    // its line would claim the very returns those directions need.
    std::vector<Point2> ending;
    for (const MapWall& w : walls) {
      if ((w.a - c).norm() <= options.wall_end_radius) ending.push_back((w.b - w.a).normalized());
      if ((w.b - c).norm() <= options.wall_end_radius) ending.push_back((w.a - w.b).normalized());
    }
    const auto nearerAnother = [&](const Point2& u, const Point2& p) {
      for (const Point2& v : ending)
        if (std::abs(cross(u, v)) >= std::sin(options.min_wall_angle) && p.dot(v) > 0 &&
            std::abs(cross(v, p)) < std::abs(cross(u, p)))
          return true;
      return false;
    };
    const auto shows = [&](const Point2& along) {
      const Point2 u = along.normalized();
      const double length = std::min(std::max(options.wall_extent, reach(u)), along.norm());
      if (!seen(c + u * std::min(options.arm, along.norm()))) return false;
      if (options.wall_returns == 0) return true;
      int returns = 0;
      for (std::size_t b = 0; b < scan.ranges.size(); ++b) {
        if (!scan.hit(b)) continue;
        const Point2 p = sensor.transformFrom(scan.point(b)) - c;
        const double t = p.dot(u);
        returns += t >= 0.5 * options.arm && t <= length &&
                   std::abs(cross(u, p)) <= options.on_wall && !nearerAnother(u, p);
      }
      return returns >= options.wall_returns;
    };
    for (const MapWall& w : walls) {
      const bool at_a = (w.a - c).norm() <= options.wall_end_radius;
      const bool at_b = (w.b - c).norm() <= options.wall_end_radius;
      if (at_a || at_b) {
        const Point2 along = at_a ? Point2(w.b - w.a) : Point2(w.a - w.b);
        if (shows(along)) seen_walls.push_back(along.normalized());
        continue;
      }
      const Point2 d = w.b - w.a;
      const double s = std::clamp(d.dot(c - w.a) / d.squaredNorm(), 0.0, 1.0);
      if ((w.a + s * d - c).norm() > options.wall_end_radius) continue;
      if (shows(w.a - c) || shows(w.b - c)) seen_walls.push_back(d.normalized());
    }
    int walls_seen = seen_walls.empty() ? 0 : 1;
    for (std::size_t a = 0; a < seen_walls.size(); ++a)
      for (std::size_t b = a + 1; b < seen_walls.size(); ++b)
        if (std::abs(cross(seen_walls[a], seen_walls[b])) >= std::sin(options.min_wall_angle))
          walls_seen = 2;
    if (walls_seen >= options.walls_seen) out.push_back(k);
  }
  return out;
}

namespace {

// The detections matched to labels (closest pairs first, each side once):
// per detection the label's position in `labels`, or -1.
std::vector<long> matchScan(const std::vector<VerticalEdge>& detections, const Pose2& sensor,
                            const std::vector<Point2>& corners,
                            const std::vector<std::size_t>& labels,
                            const DetectorEvaluationOptions& options) {
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const Point2 w = sensor.transformFrom(detections[i].position);
    for (std::size_t j = 0; j < labels.size(); ++j) {
      const double d = (corners.at(labels[j]) - w).norm();
      if (d <= options.radius) pairs.emplace_back(d, i, j);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<long> match(detections.size(), -1);
  std::vector<char> used_l(labels.size(), 0);
  for (const auto& [d, i, j] : pairs) {
    if (match[i] >= 0 || used_l[j]) continue;
    match[i] = long(j);
    used_l[j] = 1;
  }
  return match;
}

// The corner each label is, as its first label's position in `labels`:
// labels closer than `radius` to each other (directly or through others) are
// one. A detection within the radius of either finds it, and the detector
// reports one corner where the map's walls, mapped twice a little apart or
// with a thin wall's two faces, made two; asking for both would count the
// one corner twice as found or missed.
std::vector<std::size_t> labelCorners(const std::vector<Point2>& corners,
                                      const std::vector<std::size_t>& labels,
                                      const DetectorEvaluationOptions& options) {
  std::vector<std::size_t> of(labels.size());
  for (std::size_t j = 0; j < labels.size(); ++j) {
    of[j] = j;
    for (std::size_t i = 0; i < j; ++i)
      if ((corners.at(labels[i]) - corners.at(labels[j])).norm() < options.radius) {
        // The two corners j is now in are one, under the first label of either.
        const std::size_t from = std::max(of[i], of[j]), to = std::min(of[i], of[j]);
        for (std::size_t k = 0; k <= j; ++k)
          if (of[k] == from) of[k] = to;
      }
  }
  return of;
}

// The detections the labels can judge: within max_range of the sensor, as
// the labels are; one farther is neither right nor wrong.
std::vector<VerticalEdge> withinLabelRange(const std::vector<VerticalEdge>& detections,
                                           const DetectorEvaluationOptions& options) {
  std::vector<VerticalEdge> out;
  for (const VerticalEdge& e : detections)
    if (e.position.norm() <= options.max_range) out.push_back(e);
  return out;
}

// The detector as FLAG ran it on the log: with the stability check cf's
// recording passed (stable_edge_filter.h), at the odometry's latency.
StableEdgeFilter logDetector(const carmen::CarmenLog& log, const CarmenFlag& cf,
                             const VerticalEdgeDetectorOptions& edges) {
  if (cf.scans.held_out.empty()) throw Error(log.file + ": no held-out key scan to judge");
  return StableEdgeFilter(log, log.scans.at(cf.scans.held_out.front()).tag, edges, cf.stable_edges,
                          cf.odometry.latency);
}

double distanceToWall(const MapWall& w, const Point2& p) {
  const Point2 u = w.b - w.a;
  const double t = std::clamp(u.dot(p - w.a) / std::max(u.squaredNorm(), 1e-12), 0.0, 1.0);
  return (w.a + t * u - p).norm();
}

}  // namespace

DetectorScore scoreScan(const std::vector<VerticalEdge>& detections, const Pose2& sensor,
                        const std::vector<Point2>& corners, const std::vector<std::size_t>& labels,
                        const DetectorEvaluationOptions& options) {
  options.validate();
  DetectorScore s;
  s.scans = 1;
  const std::vector<VerticalEdge> graded = withinLabelRange(detections, options);
  s.detections = graded.size();
  const std::vector<std::size_t> corner = labelCorners(corners, labels, options);
  std::vector<char> found(labels.size(), 0);
  for (long m : matchScan(graded, sensor, corners, labels, options))
    if (m >= 0) {
      ++s.true_positives;
      found[corner[std::size_t(m)]] = 1;
    }
  for (std::size_t j = 0; j < labels.size(); ++j) {
    s.labels += corner[j] == j;
    s.matched_labels += found[j];
  }
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
      if (distanceToWall(w, p) <= options.on_wall) {
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
  StableEdgeFilter detector = logDetector(log, cf, edges);
  for (std::size_t i : cf.scans.held_out) {
    const carmen::LaserScan& k = log.scans.at(i);
    const RangeScan scan = rangeScanOf(k);
    const Pose2 sensor = k.pose.compose(k.laser_offset);
    const std::vector<std::size_t> labels =
        visibleMapCorners(corners, walls, sensor, scan, options);
    const DetectorScore one = scoreScan(detector.detect(i), sensor, corners, labels, options);
    total += one;
    if (mapped && mapCoverage(scan, sensor, walls, options) >= options.mapped_share) *mapped += one;
  }
  return total;
}

void dumpDetectorErrors(const carmen::CarmenLog& log, const CarmenFlag& cf,
                        const VerticalEdgeDetectorOptions& edges,
                        const DetectorEvaluationOptions& options, bool whole_log,
                        std::ostream& out) {
  options.validate();
  const std::vector<MapWall>& walls = whole_log ? cf.log_walls : cf.walls;
  const std::vector<Point2>& corners = whole_log ? cf.log_corners : cf.landmarks;
  if (walls.empty())
    throw Error(log.file + ": the detector is judged against a map's walls (map_corners)");
  constexpr double kDeg = M_PI / 180;
  out << "scan,kind,x,y,range,angle_deg,convex,wall_a,wall_b,fit_rms,along_beam_deg,"
         "outer_a,outer_b,to_wall,to_corner,cause\n";
  const auto nearest = [](const std::vector<Point2>& ps, const Point2& p) {
    double d = 1e9;
    for (const Point2& q : ps) d = std::min(d, (q - p).norm());
    return d;
  };
  StableEdgeFilter detector = logDetector(log, cf, edges);
  for (std::size_t i : cf.scans.held_out) {
    const carmen::LaserScan& k = log.scans.at(i);
    const RangeScan scan = rangeScanOf(k);
    const Pose2 sensor = k.pose.compose(k.laser_offset);
    const std::vector<std::size_t> labels =
        visibleMapCorners(corners, walls, sensor, scan, options);
    const std::vector<VerticalEdge> found = withinLabelRange(detector.detect(i), options);
    const std::vector<long> match = matchScan(found, sensor, corners, labels, options);
    const long n = long(scan.ranges.size());
    // What lies past a wall's outer end `beam`, one beam further `dir`.
    const auto outer = [&](std::size_t beam, long dir) -> std::string {
      for (long b = long(beam) + dir; std::abs(b - long(beam)) <= 2; b += dir) {
        if (b < 0 || b >= n) return "fov";
        if (!scan.hit(std::size_t(b))) return "no_return";
      }
      const std::size_t next = std::size_t(long(beam) + dir);
      const double jump = scan.ranges[next] - scan.ranges[beam];
      const double gap = (scan.point(next) - scan.point(beam)).norm();
      if (gap < 0.3) return "joined";
      return jump < 0 ? "nearer" : "farther";
    };
    for (std::size_t d = 0; d < found.size(); ++d) {
      const VerticalEdge& e = found[d];
      const Point2 w = sensor.transformFrom(e.position);
      double to_wall = 1e9;
      for (const MapWall& m : cf.log_walls) to_wall = std::min(to_wall, distanceToWall(m, w));
      const double to_corner = nearest(cf.log_corners, w);
      // The walls' directions against the beam at their far ends.
      double along = 90;
      for (std::size_t b : {e.first_beam, e.last_beam}) {
        const Point2 leg = scan.point(b) - e.position;
        if (leg.norm() < 1e-9) continue;
        const double c = std::abs(leg.normalized().dot(scan.point(b).normalized()));
        along = std::min(along, std::acos(std::min(1.0, c)) / kDeg);
      }
      const std::string oa = outer(e.first_beam, scan.angular_step > 0 ? -1 : 1);
      const std::string ob = outer(e.last_beam, scan.angular_step > 0 ? 1 : -1);
      std::string cause;
      if (match[d] >= 0)
        cause = "-";
      else if (nearest(corners, w) <= options.radius)
        cause = "unlabelled_corner";
      else if (to_corner <= options.radius)
        cause = "unmapped_corner";
      else if (to_wall > options.on_wall)
        cause = "clutter";
      else if (oa == "no_return" || ob == "no_return")
        cause = "no_return";
      else if (oa == "nearer" || oa == "farther" || ob == "nearer" || ob == "farther")
        cause = "jump_edge";
      else if (along < 15)
        cause = "along_beam";
      else if (std::min(e.legs[0], e.legs[1]) < 0.5)
        cause = "short_wall";
      else
        cause = "no_map_corner";
      out << i << ',' << (match[d] >= 0 ? "tp" : "fp") << ',' << w.x() << ',' << w.y() << ','
          << e.range << ',' << e.angle / kDeg << ',' << e.convex << ',' << e.legs[0] << ','
          << e.legs[1] << ',' << e.fit_rms << ',' << along << ',' << oa << ',' << ob << ','
          << to_wall << ',' << to_corner << ',' << cause << '\n';
    }
    const std::vector<std::size_t> corner = labelCorners(corners, labels, options);
    std::vector<char> hit(labels.size(), 0);
    for (long m : match)
      if (m >= 0) hit[corner[std::size_t(m)]] = 1;
    for (std::size_t j = 0; j < labels.size(); ++j) {
      if (corner[j] != j || hit[j]) continue;
      const Point2& c = corners[labels[j]];
      double closest = 1e9;
      for (const VerticalEdge& e : found)
        closest = std::min(closest, (sensor.transformFrom(e.position) - c).norm());
      out << i << ",fn," << c.x() << ',' << c.y() << ',' << sensor.transformTo(c).norm()
          << ",,,,,,,,,0," << closest << ','
          << (closest <= 2 * options.radius ? "displaced" : "missed") << '\n';
    }
  }
}

}  // namespace hamal::flag
