// MapCorners: see map_corners.h (thesis sec. 4.4.2's labelled corners).
#include "apps/flag/map_corners.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace hamal::flag {

void MapCornerOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string(name) + " must be > 0");
  };
  positive(merge_angle, "wall merge angle");
  positive(merge_distance, "wall merge distance");
  positive(merge_gap, "wall merge gap");
  positive(min_wall_length, "min wall length");
  positive(corner_tolerance, "map corner tolerance");
  if (min_segments < 1) throw Error("min wall segments must be >= 1");
  if (!(min_corner_angle > 0 && min_corner_angle < max_corner_angle && max_corner_angle < M_PI))
    throw Error("map corner angles must satisfy 0 < min < max < 180 degrees");
}

namespace {

struct Wall {
  // Sums over the segments' ends for the total-least-squares line.
  Point2 sum = Point2::Zero();
  Eigen::Matrix2d outer = Eigen::Matrix2d::Zero();
  int ends = 0, segments = 0;
  Point2 centre = Point2::Zero(), direction = Point2::UnitX();
  double lo = 0, hi = 0;  // extent along direction from centre
  std::vector<Point2> points;

  void add(const WallSegment& s) {
    for (const Point2& p : {s.a, s.b}) {
      sum += p;
      outer += p * p.transpose();
      points.push_back(p);
      ++ends;
    }
    ++segments;
    centre = sum / ends;
    const Eigen::Matrix2d cov = outer / ends - centre * centre.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    direction = es.eigenvectors().col(1);
    lo = 1e300;
    hi = -1e300;
    for (const Point2& p : points) {
      const double t = (p - centre).dot(direction);
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
  }
  double distance(const Point2& p) const {
    const Point2 d = p - centre;
    return std::abs(d.x() * direction.y() - d.y() * direction.x());
  }
};

double lineAngle(const Point2& u, const Point2& v) {  // in [0, pi/2]
  const double c = std::abs(u.normalized().dot(v.normalized()));
  return std::acos(std::min(1.0, c));
}

}  // namespace

std::vector<MapWall> mergeWalls(const std::vector<WallSegment>& segments,
                                const MapCornerOptions& options) {
  options.validate();
  std::vector<Wall> walls;
  for (const WallSegment& s : segments) {
    const Point2 d = s.b - s.a;
    if (d.norm() <= 0) continue;
    Wall* joined = nullptr;
    for (Wall& w : walls) {
      if (lineAngle(d, w.direction) > options.merge_angle) continue;
      if (w.distance(s.a) > options.merge_distance || w.distance(s.b) > options.merge_distance)
        continue;
      const double ta = (s.a - w.centre).dot(w.direction), tb = (s.b - w.centre).dot(w.direction);
      if (std::max(ta, tb) < w.lo - options.merge_gap ||
          std::min(ta, tb) > w.hi + options.merge_gap)
        continue;
      joined = &w;
      break;
    }
    if (!joined) {
      walls.emplace_back();
      joined = &walls.back();
    }
    joined->add(s);
  }
  std::vector<MapWall> out;
  for (const Wall& w : walls) {
    if (w.segments < options.min_segments || w.hi - w.lo < options.min_wall_length) continue;
    out.push_back({w.centre + w.lo * w.direction, w.centre + w.hi * w.direction, w.segments});
  }
  return out;
}

std::vector<MapCorner> wallCornerShapes(const std::vector<MapWall>& walls,
                                        const MapCornerOptions& options) {
  options.validate();
  struct Corner {
    Point2 sum = Point2::Zero();
    int n = 0;
    std::vector<double> walls;
    Point2 mean() const { return sum / double(n); }
  };
  std::vector<Corner> corners;
  for (std::size_t i = 0; i < walls.size(); ++i)
    for (std::size_t j = i + 1; j < walls.size(); ++j) {
      const Point2 u = walls[i].b - walls[i].a, v = walls[j].b - walls[j].a;
      // Two lines meet at a and 180 - a degrees (a in [0, 90]): either in the window will do.
      const double between = lineAngle(u, v);
      if (between < std::min(options.min_corner_angle, M_PI - options.max_corner_angle)) continue;
      const double cross = u.x() * v.y() - u.y() * v.x();
      if (std::abs(cross) < 1e-12) continue;
      const Point2 w = walls[j].a - walls[i].a;
      const double t = (w.x() * v.y() - w.y() * v.x()) / cross;
      const Point2 p = walls[i].a + t * u;
      const auto nearEnd = [&](const MapWall& m) {
        return std::min((p - m.a).norm(), (p - m.b).norm()) <= options.corner_tolerance;
      };
      const auto onWall = [&](const MapWall& m) {
        const Point2 d = m.b - m.a;
        const double s = std::clamp(d.dot(p - m.a) / d.squaredNorm(), 0.0, 1.0);
        return (m.a + s * d - p).norm() <= options.corner_tolerance;
      };
      const bool ends_i = nearEnd(walls[i]), ends_j = nearEnd(walls[j]);
      if (!(ends_i && ends_j) &&
          !(options.junctions && ((ends_i && onWall(walls[j])) || (ends_j && onWall(walls[i])))))
        continue;
      std::size_t k = 0;
      while (k < corners.size() && (corners[k].mean() - p).norm() > options.corner_tolerance) ++k;
      if (k == corners.size()) corners.emplace_back();
      corners[k].sum += p;
      ++corners[k].n;
      // The ways each wall leaves p: towards an end it reaches past p.
      for (const MapWall* m : {&walls[i], &walls[j]}) {
        const Point2 d = (m->b - m->a).normalized();
        if ((m->b - p).dot(d) > options.corner_tolerance)
          corners[k].walls.push_back(std::atan2(d.y(), d.x()));
        if ((p - m->a).dot(d) > options.corner_tolerance)
          corners[k].walls.push_back(std::atan2(-d.y(), -d.x()));
      }
    }
  std::vector<MapCorner> out;
  for (const Corner& c : corners) out.push_back({c.mean(), c.walls});
  return out;
}

std::vector<Point2> wallCorners(const std::vector<MapWall>& walls,
                                const MapCornerOptions& options) {
  std::vector<Point2> out;
  for (const MapCorner& c : wallCornerShapes(walls, options)) out.push_back(c.position);
  return out;
}

}  // namespace hamal::flag
