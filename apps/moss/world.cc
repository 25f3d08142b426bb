// World: see world.h (thesis sec. 5.5, fig. 5.5).
#include "apps/moss/world.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "apps/common/builtin_name.h"
#include "apps/common/world_file.h"
#include "core/error.h"
#include "core/text_file.h"

namespace hamal::moss {

namespace {

// CORRIDOR: a 2 m hallway along x from 0 to 10, ending in a 2 m wide cross
// hallway (x in [10, 12], y in [-3, 3]): the T. 12 x 6 m overall.
const char* kCorridor =
    R"(# CORRIDOR (thesis sec. 5.5.1): a hallway with a T-shaped intersection at one end
WORLD corridor
START 0.8 0 0
ROUTE 11 0
ROUTE 11 2.2
ROUTE 11 -2.2
WALL 0 -1 0 1
WALL 0 1 10 1
WALL 0 -1 10 -1
WALL 10 1 10 3
WALL 10 -1 10 -3
WALL 10 3 12 3
WALL 10 -3 12 -3
WALL 12 -3 12 3
)";

// SQUARE: a 12 m square with four L-shaped interior walls, one per quadrant,
// turned alike so that their local views alias, and a ring path around them.
const char* kSquare =
    R"(# SQUARE (thesis sec. 5.5.2): a square with 12 m sides and L-shaped interior walls
WORLD square
START 1.5 1.5 0
ROUTE 10.5 1.5
ROUTE 10.5 10.5
ROUTE 1.5 10.5
ROUTE 1.5 1.5
ROUTE 6 1.5
ROUTE 6 10.5
WALL 0 0 12 0
WALL 12 0 12 12
WALL 12 12 0 12
WALL 0 12 0 0
WALL 3 3 5 3
WALL 3 3 3 5
WALL 7 3 9 3
WALL 9 3 9 5
WALL 9 9 7 9
WALL 9 9 9 7
WALL 3 9 5 9
WALL 3 9 3 7
)";

// The route validation step, on a parsed world: each START / ROUTE point
// inside the walls' bounding box and clear of every wall by the robot's
// radius, each straight leg of the mapping run (START, then the waypoints in
// order) clear of every wall by that radius. A point outside the world or a
// leg that cannot be driven would end the mapping run short of its route.
struct PlacedPoint {
  Point2 p;
  int line;
  const char* what;
};

std::string at(const std::string& file_name, const PlacedPoint& p) {
  std::ostringstream os;
  os << file_name << ":" << p.line << ": " << p.what << " (" << p.p.x() << ", " << p.p.y() << ")";
  return os.str();
}

std::string wallText(const Segment& wall) {
  std::ostringstream os;
  os << "(" << wall.a.x() << ", " << wall.a.y() << ")-(" << wall.b.x() << ", " << wall.b.y() << ")";
  return os.str();
}

void checkRoute(const World& w, const std::vector<PlacedPoint>& points,
                const std::string& file_name) {
  for (const PlacedPoint& p : points) {
    const double d = distanceToSegments(p.p, w.walls);
    if (d < kRobotRadius) {
      std::ostringstream os;
      os << at(file_name, p) << " is inside a wall (" << d << " m from one, the robot's radius is "
         << kRobotRadius << " m)";
      throw Error(os.str());
    }
  }
  std::vector<PlacedPoint> legs;  // START first, then the waypoints in order
  for (const PlacedPoint& p : points)
    if (p.what == std::string("START"))
      legs.insert(legs.begin(), p);
    else
      legs.push_back(p);
  for (std::size_t i = 1; i < legs.size(); ++i) {
    const Point2 from = legs[i - 1].p, to = legs[i].p;
    const double length = (to - from).norm();
    if (length == 0) continue;
    const Point2 dir = (to - from) / length;
    const Segment leg{from, to};
    for (const Segment& wall : w.walls) {
      std::ostringstream os;
      os << file_name << ":" << legs[i].line << ": the route from (" << from.x() << ", " << from.y()
         << ") to " << legs[i].what << " (" << to.x() << ", " << to.y() << ")";
      if (castRay(from, dir, {&wall}, length) < length)
        throw Error(os.str() + " goes through the wall " + wallText(wall));
      // Not crossing it, the leg comes closest to the wall at one of the
      // four ends (its own ends are clear already).
      const double d = std::min(distanceToSegment(wall.a, leg), distanceToSegment(wall.b, leg));
      if (d < kRobotRadius) {
        os << " passes " << d << " m from the end of the wall " << wallText(wall)
           << ", closer than the robot's radius (" << kRobotRadius << " m)";
        throw Error(os.str());
      }
    }
  }
  // Last: in a closed world a point outside has a leg through a wall, the
  // more telling message.
  const Point2 lo = w.min(), hi = w.max();
  for (const PlacedPoint& p : points)
    if ((p.p.array() <= lo.array()).any() || (p.p.array() >= hi.array()).any()) {
      std::ostringstream os;
      os << at(file_name, p) << " is outside the world (its walls span (" << lo.x() << ", "
         << lo.y() << ")-(" << hi.x() << ", " << hi.y() << "))";
      throw Error(os.str());
    }
}

}  // namespace

Point2 World::min() const {
  Point2 m(1e300, 1e300);
  for (const Segment& s : walls) m = m.cwiseMin(s.a).cwiseMin(s.b);
  return m;
}
Point2 World::max() const {
  Point2 m(-1e300, -1e300);
  for (const Segment& s : walls) m = m.cwiseMax(s.a).cwiseMax(s.b);
  return m;
}

World parseWorld(const std::string& text, const std::string& file_name) {
  const apps::WorldFile records = apps::parseWorldFile(text, file_name);
  World w;
  w.name = records.name;
  w.start = records.start;
  const bool has_start = records.has_start;
  const int number = records.lines;
  std::vector<PlacedPoint> points;
  if (has_start) points.push_back({w.start.t(), records.start_line, "START"});
  for (const auto& r : records.route) {
    w.route.push_back(r.p);
    points.push_back({r.p, r.line, "ROUTE waypoint"});
  }
  std::sort(points.begin(), points.end(), [](const PlacedPoint& a, const PlacedPoint& b) {
    return a.line < b.line;
  });  // file order
  for (const auto& wall : records.walls) w.walls.push_back({wall.a, wall.b});
  const auto whole = [&](const std::string& reason) {
    throw Error(file_name + ":" + std::to_string(number) + ": " + reason);
  };
  if (w.walls.empty()) whole("no WALL line");
  if (!has_start) whole("no START line");
  if (w.route.empty()) whole("no ROUTE line");
  if (w.name.empty()) w.name = file_name;
  checkRoute(w, points, file_name);
  return w;
}

World readWorld(const std::string& path) {
  return parseWorld(readTextFile(path, "the world file"), path);
}

std::vector<std::string> builtinWorldNames() { return {"corridor", "square"}; }

std::string builtinWorldText(const std::string& name) {
  const std::string canonical = apps::builtinName(name, builtinWorldNames());
  if (canonical == "corridor") return kCorridor;
  if (canonical == "square") return kSquare;
  return "";
}

World loadWorld(const std::string& name_or_path) {
  const std::string text = builtinWorldText(name_or_path);
  if (!text.empty()) return parseWorld(text, apps::lowerCase(name_or_path));
  return readWorld(name_or_path);
}

std::string describeWorld(const World& w) {
  std::ostringstream os;
  const Point2 lo = w.min(), hi = w.max();
  os << w.name << ": " << w.walls.size() << " walls, " << (hi - lo).x() << " x " << (hi - lo).y()
     << " m, mapping route of " << w.route.size() << " waypoints";
  return os.str();
}

double distanceToSegment(const Point2& p, const Segment& s) {
  const Point2 d = s.b - s.a;
  const double len2 = d.squaredNorm();
  const double u = std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0);
  return (s.a + u * d - p).norm();
}

double distanceToSegments(const Point2& p, const std::vector<Segment>& segments) {
  double best = 1e300;
  for (const Segment& s : segments) best = std::min(best, distanceToSegment(p, s));
  return best;
}

double castRay(const Point2& o, const Point2& dir, const std::vector<const Segment*>& segments,
               double max_range) {
  double best = max_range;
  for (const Segment* s : segments) {
    // o + t dir = a + u (b - a), t >= 0, u in [0, 1].
    const Point2 e = s->b - s->a;
    const double den = dir.x() * e.y() - dir.y() * e.x();
    if (std::abs(den) < 1e-12) continue;
    const Point2 w = s->a - o;
    const double t = (w.x() * e.y() - w.y() * e.x()) / den;
    const double u = (w.x() * dir.y() - w.y() * dir.x()) / den;
    if (t >= 0.0 && t < best && u >= 0.0 && u <= 1.0) best = t;
  }
  return best;
}

std::vector<Segment> boxSegments(const Point2& c, double side) {
  const double h = side / 2;
  const Point2 p0 = c + Point2(-h, -h), p1 = c + Point2(h, -h), p2 = c + Point2(h, h),
               p3 = c + Point2(-h, h);
  return {{p0, p1}, {p1, p2}, {p2, p3}, {p3, p0}};
}

}  // namespace hamal::moss
