// FloorPlan: the prior map FLAG localizes in (thesis sec. 4.3.1): the walls
// of a floor plan, its corners (the landmarks) with the positions a person
// labelled them at, and, for simulation, the clutter and the robot's path.
//
// The labelled position is what FLAG knows; the true corner is what the
// simulated robot sees. Labels are the corners moved by a Gaussian of
// `label_sigma` (thesis sec. 4.4.2: a hand labelling of a 0.1 m/pixel image,
// 10 cm) unless the file gives them.
//
// Text format: the world file of apps/common/world_file.h (one format for
// FLAG's and MOSS' worlds). A floor plan takes its records
//   WALL x1 y1 x2 y2                  a wall segment (occludes the sensor)
//   CORNER id x y [label_x label_y]   a landmark: true position, optional label
//   OBJECT x y height [hides_id]      a static object's vertical edge; one
//                                     under the detector's minimum height is
//                                     discarded by it; with hides_id it stands
//                                     in front of that corner, which the
//                                     robot then does not see (fig. 4.9)
//   PERSON x1 y1 x2 y2 t0 speed       a person walking from (x1,y1) to
//                                     (x2,y2) from time t0 on (fig. 4.7)
//   PATH x y                          the robot's next waypoint
// (MOSS' WORLD, START and ROUTE are read and not used).
// Bad input throws hamal::Error naming the file, line and reason; a plan
// with no corners, a corner on no wall or a path that leaves the world
// (outside the walls' bounding box or through a wall) is refused by
// validate(), naming the line of the record at fault where the plan was read
// from a file.
#pragma once
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/pose2.h"

namespace hamal::flag {

struct Wall {
  Point2 a, b;
};

struct Corner {
  std::uint64_t id = 0;
  Point2 truth;  // where the robot sees it
  Point2 label;  // where the floor plan says it is
};

struct StaticObject {
  Point2 position;
  double height = 0;
  std::int64_t hides = -1;  // id of the corner it stands in front of, or -1
};

struct Person {
  Point2 from, to;
  double t0 = 0, speed = 1;
  // Where the person is at time t, or false when not walking then.
  bool at(double t, Point2* p) const;
};

struct FloorPlan {
  std::string name;
  std::vector<Wall> walls;
  std::vector<Corner> corners;
  std::vector<StaticObject> objects;
  std::vector<Person> people;
  std::vector<Point2> path;
  // The line each record was read from (readFloorPlan), parallel to the
  // vectors above, for validate()'s messages; empty for a built plan.
  struct Lines {
    std::vector<int> walls, corners, objects, path;
  } lines;

  const Corner* corner(std::uint64_t id) const;
  // Throws hamal::Error "<source>:<line>: <reason>" for a plan FLAG cannot
  // use ("<source>: <reason>" where no one line is at fault).
  void validate(const std::string& source) const;
  // Total length of the path, metres.
  double pathLength() const;
};

// Reads the text format; corners without a label get truth + N(0, label_sigma^2 I)
// from `seed`. Validates the result.
FloorPlan readFloorPlan(std::istream& in, const std::string& file, double label_sigma,
                        std::uint64_t seed);
FloorPlan readFloorPlanFile(const std::string& path, double label_sigma, std::uint64_t seed);
// Writes the text format with every label, so a reader gets the same plan.
void writeFloorPlan(std::ostream& out, const FloorPlan& plan);

// True when the open segment p-q crosses wall w (touching at q, the corner
// being looked at, does not count).
bool segmentBlocked(const Point2& p, const Point2& q, const Wall& w);

}  // namespace hamal::flag
