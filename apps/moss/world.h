// World: the simulated environments of thesis sec. 5.5 (fig. 5.5) as wall
// segments, with the route of the one mapping run, and the geometry queries
// the laser and the Dynamic Window planner need.
//
// File format: the world file of apps/common/world_file.h (one format for
// FLAG's and MOSS' worlds). A MOSS world takes its records
//   WORLD name
//   START x y theta          the pose every run starts from (known, sec. 5.5)
//   ROUTE x y                mapping-run waypoints, in driving order (>= 1)
//   WALL x1 y1 x2 y2         a wall segment, metres (>= 1, non-zero length)
// (FLAG's CORNER, OBJECT, PERSON and PATH are read and not used). A
// malformed line, a zero-length wall, a START / ROUTE point closer to a
// wall than the robot's radius or outside the walls' bounding box, or a
// straight leg of the route (START, then the waypoints in order) through a
// wall or closer than that radius to a wall's end is an error naming the
// file, line and reason.
#pragma once

#include <string>
#include <vector>

#include "core/pose2.h"

namespace hamal::moss {

constexpr double kRobotRadius = 0.2;  // m: a waypoint needs this clearance

struct Segment {
  Point2 a, b;
};

struct World {
  std::string name;
  Pose2 start;
  std::vector<Point2> route;
  std::vector<Segment> walls;
  // Bounding box of the walls.
  Point2 min() const;
  Point2 max() const;
};

// Reads and checks a world file (errors name file, line and reason).
World readWorld(const std::string& path);
World parseWorld(const std::string& text, const std::string& file_name);
// "corridor" (12 x 6 m hallway with a T at one end) or "square" (12 m sides,
// L-shaped interior walls); the text of their files, so they are the format.
// Names are matched without regard to case (apps/common/builtin_name.h): a
// built-in world is named in lower case, "" for another name.
std::vector<std::string> builtinWorldNames();
std::string builtinWorldText(const std::string& name);
// A built-in name, or else a path.
World loadWorld(const std::string& name_or_path);
std::string describeWorld(const World& world);

// Geometry on segments.
double distanceToSegment(const Point2& p, const Segment& s);
double distanceToSegments(const Point2& p, const std::vector<Segment>& segments);
// Distance along the ray from `origin` in direction `dir` (unit) to the first
// segment hit, or `max_range` when none is hit within it.
double castRay(const Point2& origin, const Point2& dir, const std::vector<const Segment*>& segments,
               double max_range);
// Square obstacle of side `side` centred at `c`, as four segments.
std::vector<Segment> boxSegments(const Point2& c, double side);

}  // namespace hamal::moss
