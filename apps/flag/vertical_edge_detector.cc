// Corners of a 2.5D range scan by split-and-merge (vertical_edge_detector.h;
// thesis sec. 4.3.2).
#include "apps/flag/vertical_edge_detector.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace hamal::flag {
namespace {

constexpr double kPi = 3.14159265358979323846;

double cross(const Point2& a, const Point2& b) { return a.x() * b.y() - a.y() * b.x(); }

struct Line {
  Point2 c, u;  // a point and the unit direction
  double distance(const Point2& p) const { return std::abs(cross(u, p - c)); }
  Point2 project(const Point2& p) const { return c + u * u.dot(p - c); }
};

// Total least squares through pts[lo..hi].
Line fitLine(const std::vector<Point2>& pts, std::size_t lo, std::size_t hi) {
  Point2 c = Point2::Zero();
  for (std::size_t k = lo; k <= hi; ++k) c += pts[k];
  c /= double(hi - lo + 1);
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t k = lo; k <= hi; ++k) {
    const Point2 d = pts[k] - c;
    sxx += d.x() * d.x();
    sxy += d.x() * d.y();
    syy += d.y() * d.y();
  }
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);
  return {c, Point2(std::cos(angle), std::sin(angle))};
}

double maxResidual(const Line& l, const std::vector<Point2>& pts, std::size_t lo, std::size_t hi) {
  double m = 0;
  for (std::size_t k = lo; k <= hi; ++k) m = std::max(m, l.distance(pts[k]));
  return m;
}

// Iterative end-point fit: [lo, hi] pieces sharing their break points.
void split(const std::vector<Point2>& pts, std::size_t lo, std::size_t hi, double tolerance,
           std::vector<std::pair<std::size_t, std::size_t>>* out) {
  if (hi - lo < 2) {
    out->push_back({lo, hi});
    return;
  }
  const Point2 a = pts[lo], d = pts[hi] - pts[lo];
  const double len = d.norm();
  std::size_t worst = lo;
  double worst_d = -1;
  for (std::size_t k = lo + 1; k < hi; ++k) {
    const double dist = len > 1e-12 ? std::abs(cross(d, pts[k] - a)) / len : (pts[k] - a).norm();
    if (dist > worst_d) {
      worst_d = dist;
      worst = k;
    }
  }
  if (worst_d <= tolerance) {
    out->push_back({lo, hi});
    return;
  }
  split(pts, lo, worst, tolerance, out);
  split(pts, worst, hi, tolerance, out);
}

struct Piece {
  std::size_t lo, hi;  // indices into the run's points
  Line line;
  Point2 a, b;
  double rms = 0;  // the points' RMS distance from the line
  bool kept = false;
};

// The pieces of one run after split and merge.
std::vector<Piece> splitAndMerge(const std::vector<Point2>& pts,
                                 const VerticalEdgeDetectorOptions& o) {
  std::vector<std::pair<std::size_t, std::size_t>> ranges;
  split(pts, 0, pts.size() - 1, o.segments.fit_tolerance, &ranges);
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i + 1 < ranges.size(); ++i) {
      const std::size_t lo = ranges[i].first, hi = ranges[i + 1].second;
      if (maxResidual(fitLine(pts, lo, hi), pts, lo, hi) <= o.segments.fit_tolerance) {
        ranges[i].second = hi;
        ranges.erase(ranges.begin() + long(i) + 1);
        merged = true;
      }
    }
  }
  std::vector<Piece> pieces;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    Piece p;
    p.lo = ranges[i].first;
    p.hi = ranges[i].second;
    // A break point shared with a neighbour may belong to either wall: fit without it.
    std::size_t flo = p.lo + (i > 0 ? 1 : 0), fhi = p.hi - (i + 1 < ranges.size() ? 1 : 0);
    if (fhi < flo + 1) flo = p.lo, fhi = p.hi;
    p.line = fitLine(pts, flo, fhi);
    double sq = 0;
    for (std::size_t k = flo; k <= fhi; ++k) sq += std::pow(p.line.distance(pts[k]), 2);
    p.rms = std::sqrt(sq / double(fhi - flo + 1));
    p.a = p.line.project(pts[p.lo]);
    p.b = p.line.project(pts[p.hi]);
    // Orient the direction in scan order.
    if (p.line.u.dot(p.b - p.a) < 0) p.line.u = -p.line.u;
    const int count = int(p.hi - p.lo + 1);
    p.kept = count >= o.segments.min_points && (p.b - p.a).norm() >= o.segments.min_length;
    pieces.push_back(p);
  }
  return pieces;
}

bool fullCircle(const RangeScan& scan) {
  return std::abs(scan.angular_step) * double(scan.ranges.size()) >= 2 * kPi - 1e-6;
}

// Step 1: beams i and j return from one surface (no breakpoint between them).
bool joined(const RangeScan& scan, const VerticalEdgeDetectorOptions& o, std::size_t i,
            std::size_t j) {
  if (!scan.hit(i) || !scan.hit(j)) return false;
  const double step = std::abs(scan.angular_step);
  const double reach = std::sin(step) / std::sin(std::max(o.breakpoints.lambda - step, 1e-6));
  const double dmax =
      std::min(scan.ranges[i], scan.ranges[j]) * reach + 3 * o.breakpoints.range_sigma;
  return (scan.point(i) - scan.point(j)).norm() <= dmax;
}

// Runs of consecutive returns between breakpoints, as beam indices, the
// scan taken as a circle when it covers 360 degrees.
std::vector<std::vector<std::size_t>> runs(const RangeScan& scan,
                                           const VerticalEdgeDetectorOptions& o) {
  const std::size_t n = scan.ranges.size();
  std::vector<std::vector<std::size_t>> out;
  if (n == 0) return out;
  const bool circle = fullCircle(scan);
  const auto joined = [&](std::size_t i, std::size_t j) { return flag::joined(scan, o, i, j); };
  // Start after a breakpoint, so no run is cut by where the beams start.
  std::size_t start = 0;
  if (circle) {
    for (std::size_t i = 0; i < n; ++i)
      if (!joined((i + n - 1) % n, i)) {
        start = i;
        break;
      }
  }
  std::vector<std::size_t> run;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (start + k) % n;
    if (!scan.hit(i)) {
      if (!run.empty()) out.push_back(std::move(run));
      run.clear();
      continue;
    }
    if (!run.empty() && !joined(run.back(), i)) {
      out.push_back(std::move(run));
      run.clear();
    }
    run.push_back(i);
  }
  if (!run.empty()) out.push_back(std::move(run));
  return out;
}

Point2 unit(double bearing) { return Point2(std::cos(bearing), std::sin(bearing)); }

// An edge at x (sensor frame), its height the lowest of the run's returns
// lo..hi within `reach` of it (step 5).
VerticalEdge edgeAt(const Point2& x, const RangeScan& scan, const std::vector<std::size_t>& run,
                    const std::vector<Point2>& pts, std::size_t lo, std::size_t hi, double reach) {
  VerticalEdge e;
  e.position = x;
  e.range = x.norm();
  e.bearing = std::atan2(x.y(), x.x());
  e.height = 1e9;
  for (std::size_t k = lo; k <= hi; ++k)
    if ((pts[k] - x).norm() <= reach) e.height = std::min(e.height, scan.height(run[k]));
  return e;
}

// How far along the ray at `bearing` it meets the line, if ahead of the sensor.
bool rayMeets(const Line& l, double bearing, double* t) {
  const double denom = cross(l.u, unit(bearing));
  if (std::abs(denom) < 1e-12) return false;
  *t = cross(l.u, l.c) / denom;
  return *t > 0;
}

// The beam after `beam` (`forward`: in scan order, else before it), the
// scan taken as a circle when it covers 360 degrees; the beams' count past
// the field of view's edge.
std::size_t beamPast(const RangeScan& scan, std::size_t beam, bool forward) {
  const std::size_t n = scan.ranges.size();
  if (forward) return beam + 1 < n ? beam + 1 : (fullCircle(scan) ? 0 : n);
  return beam > 0 ? beam - 1 : (fullCircle(scan) ? n - 1 : n);
}

// Step 4: the silhouette edge at piece p's end (`forward`: its end in scan
// order, else its start), which is its run's end, if the beam past it
// returns beyond p's line.
void silhouette(const RangeScan& scan, const std::vector<std::size_t>& run,
                const std::vector<Point2>& pts, const Piece& p, bool forward,
                const VerticalEdgeDetectorOptions& o, std::vector<VerticalEdge>* out) {
  if (!p.kept || (p.b - p.a).norm() < o.silhouettes.min_length) return;
  const std::size_t n = scan.ranges.size(), last = forward ? run[p.hi] : run[p.lo];
  const std::size_t next = beamPast(scan, last, forward);
  // The field of view's edge (nothing is known past it), or a closed room.
  if (next == n || joined(scan, o, last, next)) return;
  double on_line;
  if (!rayMeets(p.line, scan.bearing(next), &on_line)) return;  // the wall recedes out of sight
  const double beyond = scan.hit(next) ? scan.ranges[next] : scan.max_range;
  if (beyond < on_line + o.silhouettes.margin) return;
  // Seen at a grazing angle the beams fall far apart on the wall, and the
  // end is known no better than their spacing.
  const Point2 end = p.line.project(pts[forward ? p.hi : p.lo]);
  if ((on_line * unit(scan.bearing(next)) - end).norm() > o.silhouettes.max_spacing) return;
  const double half_way = scan.bearing(last) + (forward ? 0.5 : -0.5) * scan.angular_step;
  double t;
  const Point2 x = rayMeets(p.line, half_way, &t) ? Point2(t * unit(half_way)) : end;
  const double reach = o.corners.tolerance + 2 * x.norm() * std::abs(scan.angular_step);
  VerticalEdge e = edgeAt(x, scan, run, pts, p.lo, p.hi, reach);
  e.convex = e.silhouette = true;
  e.first_beam = run[p.lo];
  e.last_beam = run[p.hi];
  e.legs[1] = (p.b - p.a).norm();
  e.fit_rms = p.rms;
  // The wall leaves its end back along itself.
  const Point2 back = forward ? Point2(-p.line.u) : p.line.u;
  e.walls = {std::atan2(back.y(), back.x())};
  if (e.height >= o.min_height) out->push_back(e);
}

// Whether piece k's outer end (`forward`: its end in scan order, else its
// start) is where its surface ends in the open: the run goes on into a piece
// turned from it by a corner's least angle or more (the surface turns
// again), or the run ends there and the beam past it returns from more than
// the silhouette margin beyond k's line (nothing stands in front: the
// surface stops). A surface cut by something nearer, at a no-return beam,
// at the field of view's edge or where the next beam cannot meet its line
// may go on unseen.
bool endsInTheOpen(const RangeScan& scan, const std::vector<std::size_t>& run,
                   const std::vector<Piece>& pieces, std::size_t k, bool forward,
                   const VerticalEdgeDetectorOptions& o) {
  const Piece& s = pieces[k];
  if (forward ? k + 1 < pieces.size() : k > 0) {
    const Piece& t = pieces[forward ? k + 1 : k - 1];
    const double c = std::abs(s.line.u.dot(t.line.u));
    return std::acos(std::min(1.0, c)) >= o.corners.min_angle;
  }
  const std::size_t next = beamPast(scan, forward ? run[s.hi] : run[s.lo], forward);
  if (next == scan.ranges.size() || !scan.hit(next)) return false;
  double on_line;
  if (!rayMeets(s.line, scan.bearing(next), &on_line)) return false;
  return scan.ranges[next] > on_line + o.silhouettes.margin;
}

}  // namespace

void VerticalEdgeDetectorOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string(name) + " must be > 0");
  };
  positive(segments.fit_tolerance, "fit_tolerance");
  positive(segments.min_length, "min_segment_length");
  positive(corners.tolerance, "corner_tolerance");
  if (segments.min_points < 3) throw Error("min_segment_points must be >= 3");
  if (corners.min_stub_points < 3 || corners.min_stub_points > segments.min_points)
    throw Error("min_stub_points must be >= 3 and <= min_segment_points");
  if (!(corners.min_stub_length > 0 && corners.min_stub_length <= segments.min_length))
    throw Error("min_stub_length must be > 0 and <= min_segment_length");
  if (!(breakpoints.lambda > 0 && breakpoints.lambda < kPi / 2))
    throw Error("breakpoint_lambda must be in (0, 90) degrees");
  if (!(breakpoints.range_sigma >= 0) || !std::isfinite(breakpoints.range_sigma))
    throw Error("detector range_sigma must be >= 0");
  if (!(corners.min_angle > 0 && corners.min_angle < corners.max_angle && corners.max_angle < kPi))
    throw Error("corner angles must satisfy 0 < min_corner_angle < max_corner_angle < 180 degrees");
  if (!(min_height >= 0) || !std::isfinite(min_height)) throw Error("min_height must be >= 0");
  if (!(corners.min_long_wall >= 0) || !std::isfinite(corners.min_long_wall))
    throw Error("min_long_wall must be >= 0");
  if (!(corners.max_fit_rms >= 0) || !std::isfinite(corners.max_fit_rms))
    throw Error("max_fit_rms must be >= 0");
  if (!(corners.min_open_wall >= 0) || !std::isfinite(corners.min_open_wall))
    throw Error("min_open_wall must be >= 0");
  positive(silhouettes.margin, "silhouette_margin");
  positive(silhouettes.max_spacing, "max_silhouette_spacing");
  if (!(silhouettes.min_length >= segments.min_length) || !std::isfinite(silhouettes.min_length))
    throw Error("min_silhouette_length must be >= min_segment_length");
}

VerticalEdgeDetectorOptions realLogDetectorOptions() {
  VerticalEdgeDetectorOptions o;
  o.breakpoints.lambda = 10 * kPi / 180;
  o.corners.min_stub_points = o.segments.min_points;
  o.corners.min_stub_length = o.segments.min_length;
  o.silhouettes.enabled = false;
  o.corners.min_angle = 75 * kPi / 180;
  o.corners.max_angle = 105 * kPi / 180;
  o.corners.min_long_wall = 0.8;
  o.corners.max_fit_rms = 0.025;
  o.corners.min_open_wall = 0.5;
  return o;
}

std::vector<LineSegment> extractLineSegments(const RangeScan& scan,
                                             const VerticalEdgeDetectorOptions& options) {
  options.validate();
  std::vector<LineSegment> out;
  for (const auto& run : runs(scan, options)) {
    if (run.size() < 2) continue;
    std::vector<Point2> pts;
    for (std::size_t i : run) pts.push_back(scan.point(i));
    for (const Piece& p : splitAndMerge(pts, options))
      if (p.kept) out.push_back({p.a, p.b, run[p.lo], run[p.hi]});
  }
  return out;
}

std::vector<VerticalEdge> detectVerticalEdges(const RangeScan& scan,
                                              const VerticalEdgeDetectorOptions& options) {
  options.validate();
  if (scan.heights.size() != scan.ranges.size() && !scan.heights.empty())
    throw Error("a scan's heights must be one per beam");
  std::vector<VerticalEdge> out;
  const double step = std::abs(scan.angular_step);
  for (const auto& run : runs(scan, options)) {
    if (run.size() < 2) continue;
    std::vector<Point2> pts;
    for (std::size_t i : run) pts.push_back(scan.point(i));
    const std::vector<Piece> pieces = splitAndMerge(pts, options);
    // The corner where p (earlier in the scan) meets q, if they make one.
    const auto corner = [&](std::size_t pi, std::size_t qi) {
      const Piece& p = pieces[pi];
      const Piece& q = pieces[qi];
      const double turn = std::abs(std::atan2(cross(p.line.u, q.line.u), p.line.u.dot(q.line.u)));
      if (turn < options.corners.min_angle || turn > options.corners.max_angle) return false;
      if (std::max((p.b - p.a).norm(), (q.b - q.a).norm()) < options.corners.min_long_wall)
        return false;
      if (options.corners.max_fit_rms > 0 && std::max(p.rms, q.rms) > options.corners.max_fit_rms)
        return false;
      // A short wall that ends in the open is a door jamb's, a recess's or
      // a pillar's face: the edge is real, but no wall of a plan's corner.
      const auto open = [&](std::size_t k, bool forward) {
        const Piece& w = pieces[k];
        return (w.b - w.a).norm() < options.corners.min_open_wall &&
               endsInTheOpen(scan, run, pieces, k, forward, options);
      };
      if (open(pi, false) || open(qi, true)) return false;
      const double denom = cross(p.line.u, q.line.u);
      const Point2 x = p.line.c + p.line.u * (cross(q.line.c - p.line.c, q.line.u) / denom);
      const double r = x.norm();
      const double reach = options.corners.tolerance + 2 * r * step;
      if ((x - p.b).norm() > reach || (x - q.a).norm() > reach) return false;
      VerticalEdge e = edgeAt(x, scan, run, pts, p.lo, q.hi, reach);
      e.angle = turn;
      e.first_beam = run[p.lo];
      e.last_beam = run[q.hi];
      e.legs[0] = (p.b - p.a).norm();
      e.legs[1] = (q.b - q.a).norm();
      e.fit_rms = std::max(p.rms, q.rms);
      // p (oriented in scan order) ends at the corner, q starts there.
      e.walls = {std::atan2(-p.line.u.y(), -p.line.u.x()), std::atan2(q.line.u.y(), q.line.u.x())};
      // Convex when the corner lies on the sensor's side of a short chord
      // across it (a long one may pass behind the sensor).
      const double arm = 0.5 * std::min((p.b - p.a).norm(), (q.b - q.a).norm());
      const Point2 u = x - p.line.u * arm, w = x + q.line.u * arm;
      const double sensor_side = cross(w - u, Point2(-u));
      const double corner_side = cross(w - u, x - u);
      e.convex = sensor_side * corner_side > 0;
      if (e.height < options.min_height) return true;  // furniture: the ends are taken all the same
      out.push_back(e);
      return true;
    };
    // Each kept piece with the next kept one of the run.
    std::vector<char> end_taken(pieces.size(), 0), start_taken(pieces.size(), 0);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      if (!pieces[i].kept) continue;
      std::size_t j = i + 1;
      while (j < pieces.size() && !pieces[j].kept) ++j;
      if (j == pieces.size()) break;
      if (corner(i, j)) end_taken[i] = start_taken[j] = 1;
    }
    // A kept wall whose end made no corner, with the stub of a wall adjoining it.
    const auto stub = [&](const Piece& p) {
      return !p.kept && int(p.hi - p.lo + 1) >= options.corners.min_stub_points &&
             (p.b - p.a).norm() >= options.corners.min_stub_length;
    };
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      if (!pieces[i].kept) continue;
      if (!end_taken[i] && i + 1 < pieces.size() && stub(pieces[i + 1])) corner(i, i + 1);
      if (!start_taken[i] && i > 0 && stub(pieces[i - 1])) corner(i - 1, i);
    }
    if (options.silhouettes.enabled) {
      silhouette(scan, run, pts, pieces.front(), false, options, &out);
      silhouette(scan, run, pts, pieces.back(), true, options, &out);
    }
  }
  return out;
}

}  // namespace hamal::flag
