// The simulated 2.5D scanner (range_scan.h; thesis sec. 4.3.2).
#include "apps/flag/range_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace hamal::flag {
namespace {

double cross(const Point2& a, const Point2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Distance along the unit ray (o, d) to segment w, or infinity.
double raySegment(const Point2& o, const Point2& d, const Wall& w) {
  const Point2 s = w.b - w.a;
  const double denom = cross(d, s);
  if (std::abs(denom) < 1e-12) return std::numeric_limits<double>::infinity();
  const double t = cross(w.a - o, s) / denom;
  const double u = cross(w.a - o, d) / denom;
  if (t <= 1e-9 || u < -1e-12 || u > 1 + 1e-12) return std::numeric_limits<double>::infinity();
  return t;
}

// Distance along the unit ray to a circle the ray starts outside of, or infinity.
double rayCircle(const Point2& o, const Point2& d, const Point2& c, double radius) {
  const Point2 oc = o - c;
  const double b = oc.dot(d), cc = oc.squaredNorm() - radius * radius;
  if (cc <= 0) return std::numeric_limits<double>::infinity();  // inside: not seen
  const double disc = b * b - cc;
  if (disc < 0) return std::numeric_limits<double>::infinity();
  const double t = -b - std::sqrt(disc);
  return t > 0 ? t : std::numeric_limits<double>::infinity();
}

double distanceToSegment(const Point2& p, const Wall& w) {
  const Point2 d = w.b - w.a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - w.a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (w.a + t * d - p).norm();
}

// What a ray from `o` can hit within `reach` at `time`: walls and object
// boxes (with their heights) near enough, people walking then. Gathered once
// per scan, so each beam tests only what is in range.
struct Surfaces {
  std::vector<Wall> segments;
  std::vector<double> heights;
  std::vector<Point2> people;

  Surfaces(const FloorPlan& plan, const Point2& o, double reach, double time,
           const RangeScannerOptions& opt) {
    const auto add = [&](const Wall& w, double h) {
      if (distanceToSegment(o, w) <= reach) {
        segments.push_back(w);
        heights.push_back(h);
      }
    };
    for (const Wall& w : plan.walls) add(w, opt.wall_height);
    for (const StaticObject& obj : plan.objects)
      for (const Wall& w : objectBox(obj, opt.object_side)) add(w, obj.height);
    for (const Person& p : plan.people) {
      Point2 at;
      if (p.at(time, &at) && (at - o).norm() <= reach + opt.person_radius) people.push_back(at);
    }
  }

  // Nearest hit along the unit ray (o, d) and the height of what was hit.
  double cast(const Point2& o, const Point2& d, const RangeScannerOptions& opt,
              double* height) const {
    double best = std::numeric_limits<double>::infinity();
    *height = opt.wall_height;
    for (std::size_t k = 0; k < segments.size(); ++k) {
      const double t = raySegment(o, d, segments[k]);
      if (t < best) {
        best = t;
        *height = heights[k];
      }
    }
    for (const Point2& at : people) {
      const double t = rayCircle(o, d, at, opt.person_radius);
      if (t < best) {
        best = t;
        *height = opt.person_height;
      }
    }
    return best;
  }
};

}  // namespace

void RangeScannerOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string(name) + " must be > 0");
  };
  positive(field_of_view, "scanner field of view");
  positive(angular_step, "scanner angular step");
  positive(max_range, "scanner max range");
  positive(wall_height, "wall height");
  positive(object_side, "object side");
  positive(person_radius, "person radius");
  positive(person_height, "person height");
  if (!(range_sigma >= 0) || !std::isfinite(range_sigma))
    throw Error("scan range sigma must be >= 0");
  if (field_of_view > 2 * 3.14159265358979323846 + 1e-9)
    throw Error("scanner field of view must be at most 360 degrees");
  if (angular_step > field_of_view) throw Error("scanner angular step exceeds its field of view");
}

std::vector<Wall> objectBox(const StaticObject& object, double side) {
  const Point2 c = object.position;
  const double h = side / 2;
  const Point2 v[4] = {c + Point2(-h, -h), c + Point2(h, -h), c + Point2(h, h), c + Point2(-h, h)};
  return {{v[0], v[1]}, {v[1], v[2]}, {v[2], v[3]}, {v[3], v[0]}};
}

RangeScan castRangeScan(const FloorPlan& plan, const Pose2& pose, double time,
                        const RangeScannerOptions& options, std::mt19937_64* rng) {
  RangeScan scan;
  const bool full = options.field_of_view >= 2 * 3.14159265358979323846 - 1e-9;
  const std::size_t beams =
      static_cast<std::size_t>(std::floor(options.field_of_view / options.angular_step + 1e-9)) +
      (full ? 0 : 1);
  scan.angular_step = options.angular_step;
  scan.start_angle = full ? -3.14159265358979323846 : -options.field_of_view / 2;
  scan.max_range = options.max_range;
  scan.ranges.resize(beams);
  scan.heights.resize(beams);
  const Surfaces surfaces(plan, pose.t(), options.max_range, time, options);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (std::size_t i = 0; i < beams; ++i) {
    const double a = pose.theta + scan.bearing(i);
    const Point2 d(std::cos(a), std::sin(a));
    double height = 0;
    double r = surfaces.cast(pose.t(), d, options, &height);
    if (r >= options.max_range) {
      scan.ranges[i] = options.max_range;
      scan.heights[i] = 0;
      continue;
    }
    if (rng) r = std::max(0.0, r + options.range_sigma * n01(*rng));
    scan.ranges[i] = std::min(r, options.max_range);
    scan.heights[i] = height;
  }
  return scan;
}

bool lineOfSight(const FloorPlan& plan, const Point2& from, const Point2& to, double time,
                 const RangeScannerOptions& options) {
  const double len = (to - from).norm();
  if (len < 1e-9) return true;
  const Point2 d = (to - from) / len;
  double height = 0;
  const double t = Surfaces(plan, from, len, time, options).cast(from, d, options, &height);
  return t >= len - 1e-6;
}

}  // namespace hamal::flag
