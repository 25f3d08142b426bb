// FloorPlan's text format and checks (thesis sec. 4.3.1; format in floor_plan.h).
#include "apps/flag/floor_plan.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <istream>
#include <limits>
#include <ostream>
#include <random>
#include <set>
#include <sstream>

#include "apps/common/world_file.h"
#include "core/error.h"
#include "core/text_file.h"

namespace hamal::flag {
namespace {

double cross(const Point2& a, const Point2& b) { return a.x() * b.y() - a.y() * b.x(); }

double distanceToSegment(const Point2& p, const Wall& w) {
  const Point2 d = w.b - w.a;
  const double len2 = d.squaredNorm();
  double t = len2 > 0 ? (p - w.a).dot(d) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return (w.a + t * d - p).norm();
}

// A corner must lie on a wall: a label may be off, the truth may not.
constexpr double kOnWallTolerance = 0.01;

}  // namespace

bool Person::at(double t, Point2* p) const {
  const double len = (to - from).norm();
  const double s = (t - t0) * speed;
  if (s < 0 || s > len) return false;
  *p = len > 0 ? Point2(from + (to - from) * (s / len)) : from;
  return true;
}

const Corner* FloorPlan::corner(std::uint64_t id) const {
  for (const Corner& c : corners)
    if (c.id == id) return &c;
  return nullptr;
}

double FloorPlan::pathLength() const {
  double len = 0;
  for (std::size_t i = 1; i < path.size(); ++i) len += (path[i] - path[i - 1]).norm();
  return len;
}

bool segmentBlocked(const Point2& p, const Point2& q, const Wall& w) {
  const Point2 r = q - p, s = w.b - w.a;
  const double denom = cross(r, s);
  if (std::abs(denom) < 1e-12) return false;   // parallel: a grazing ray is not blocked
  const double t = cross(w.a - p, s) / denom;  // along p-q
  const double u = cross(w.a - p, r) / denom;  // along the wall
  const double eps_t = 1e-6 / std::max(r.norm(), 1e-9);
  return t > eps_t && t < 1 - eps_t && u >= -1e-9 && u <= 1 + 1e-9;
}

void FloorPlan::validate(const std::string& source) const {
  const auto fail = [&](const std::string& reason) { throw Error(source + ": " + reason); };
  // The record's line when it was read from a file.
  const auto failAt = [&](const std::vector<int>& record_lines, std::size_t i,
                          const std::string& reason) {
    if (i < record_lines.size() && record_lines[i] > 0)
      throw Error(source + ":" + std::to_string(record_lines[i]) + ": " + reason);
    fail(reason);
  };
  if (walls.empty()) fail("the floor plan has no walls");
  if (corners.empty()) fail("the floor plan has no corners (landmarks)");
  std::set<std::uint64_t> ids;
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const Corner& c = corners[k];
    if (!ids.insert(c.id).second)
      failAt(lines.corners, k, "corner " + std::to_string(c.id) + " is defined twice");
    double nearest = std::numeric_limits<double>::infinity();
    for (const Wall& w : walls) nearest = std::min(nearest, distanceToSegment(c.truth, w));
    if (nearest > kOnWallTolerance) {
      std::ostringstream msg;
      msg << "corner " << c.id << " at (" << c.truth.x() << ", " << c.truth.y()
          << ") lies on no wall (nearest is " << nearest << " m away)";
      failAt(lines.corners, k, msg.str());
    }
  }
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const StaticObject& o = objects[k];
    if (o.hides >= 0 && !ids.count(static_cast<std::uint64_t>(o.hides)))
      failAt(lines.objects, k,
             "an object hides corner " + std::to_string(o.hides) + ", which does not exist");
  }
  if (path.size() < 2) fail("the path needs at least two waypoints");
  Point2 lo = walls[0].a, hi = walls[0].a;
  for (const Wall& w : walls) {
    lo = lo.cwiseMin(w.a).cwiseMin(w.b);
    hi = hi.cwiseMax(w.a).cwiseMax(w.b);
  }
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Point2& p = path[i];
    if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) {
      std::ostringstream msg;
      msg << "waypoint " << i << " at (" << p.x() << ", " << p.y()
          << ") leaves the world (the walls span (" << lo.x() << ", " << lo.y() << ")-(" << hi.x()
          << ", " << hi.y() << "))";
      failAt(lines.path, i, msg.str());
    }
    if (i == 0) continue;
    for (std::size_t k = 0; k < walls.size(); ++k) {
      const Wall& w = walls[k];
      // A leg that crosses a wall leaves the corridor; touching at an end is crossing too.
      const Point2 r = p - path[i - 1], s = w.b - w.a;
      const double denom = cross(r, s);
      if (std::abs(denom) < 1e-12) continue;
      const double t = cross(w.a - path[i - 1], s) / denom;
      const double u = cross(w.a - path[i - 1], r) / denom;
      if (t >= 0 && t <= 1 && u >= 0 && u <= 1) {
        std::ostringstream msg;
        msg << "the path from waypoint " << i - 1 << " to " << i << " goes through the wall ("
            << w.a.x() << ", " << w.a.y() << ")-(" << w.b.x() << ", " << w.b.y() << ")";
        if (k < lines.walls.size() && lines.walls[k] > 0) msg << " of line " << lines.walls[k];
        failAt(lines.path, i, msg.str());
      }
    }
  }
}

FloorPlan readFloorPlan(std::istream& in, const std::string& file, double label_sigma,
                        std::uint64_t seed) {
  // An option, not a line of the file: its message names no file.
  if (!(label_sigma >= 0) || !std::isfinite(label_sigma))
    throw Error("label sigma must be >= 0 and finite");
  const apps::WorldFile records = apps::parseWorldFile(in, file);
  FloorPlan plan;
  plan.name = file;
  std::vector<bool> labelled;
  for (const auto& w : records.walls) {
    plan.walls.push_back({w.a, w.b});
    plan.lines.walls.push_back(w.line);
  }
  for (const auto& c : records.corners) {
    plan.corners.push_back({c.id, c.truth, c.label});
    plan.lines.corners.push_back(c.line);
    labelled.push_back(c.has_label);
  }
  for (const auto& o : records.objects) {
    plan.objects.push_back({o.position, o.height, o.hides});
    plan.lines.objects.push_back(o.line);
  }
  for (const auto& p : records.people) plan.people.push_back({p.from, p.to, p.t0, p.speed});
  for (const auto& p : records.path) {
    plan.path.push_back(p.p);
    plan.lines.path.push_back(p.line);
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (std::size_t i = 0; i < plan.corners.size(); ++i) {
    if (labelled[i]) continue;
    const double dx = noise(rng), dy = noise(rng);
    plan.corners[i].label = plan.corners[i].truth + label_sigma * Point2(dx, dy);
  }
  plan.validate(file);
  return plan;
}

FloorPlan readFloorPlanFile(const std::string& path, double label_sigma, std::uint64_t seed) {
  std::istringstream in(readTextFile(path, "the floor plan"));
  return readFloorPlan(in, path, label_sigma, seed);
}

void writeFloorPlan(std::ostream& out, const FloorPlan& plan) {
  const auto flags = out.flags();
  const auto precision = out.precision();
  out << std::setprecision(17);
  out << "# hamal FLAG floor plan: " << plan.name << "\n";
  for (const Wall& w : plan.walls)
    out << "WALL " << w.a.x() << ' ' << w.a.y() << ' ' << w.b.x() << ' ' << w.b.y() << '\n';
  for (const Corner& c : plan.corners)
    out << "CORNER " << c.id << ' ' << c.truth.x() << ' ' << c.truth.y() << ' ' << c.label.x()
        << ' ' << c.label.y() << '\n';
  for (const StaticObject& o : plan.objects) {
    out << "OBJECT " << o.position.x() << ' ' << o.position.y() << ' ' << o.height;
    if (o.hides >= 0) out << ' ' << o.hides;
    out << '\n';
  }
  for (const Person& p : plan.people)
    out << "PERSON " << p.from.x() << ' ' << p.from.y() << ' ' << p.to.x() << ' ' << p.to.y() << ' '
        << p.t0 << ' ' << p.speed << '\n';
  for (const Point2& p : plan.path) out << "PATH " << p.x() << ' ' << p.y() << '\n';
  out.flags(flags);
  out.precision(precision);
}

}  // namespace hamal::flag
