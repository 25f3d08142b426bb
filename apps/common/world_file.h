// WorldFile: the one text format of the simulated worlds, read once for FLAG's
// floor plans (thesis sec. 4.3.1, apps/flag/floor_plan.h) and MOSS' worlds
// (sec. 5.5, apps/moss/world.h). A file holds the records of either or both;
// each experiment takes the records it uses, and the others are read and
// checked like the rest (a file that describes a world for both experiments
// loads in both).
//
// One record per line, '#' starts a comment:
//   WORLD name                        the world's name
//   START x y theta                   where every MOSS run starts (at most one)
//   ROUTE x y                         MOSS' mapping-run waypoints, in order
//   WALL x1 y1 x2 y2                  a wall segment, metres (non-zero length)
//   CORNER id x y [label_x label_y]   a FLAG landmark, optionally labelled
//   OBJECT x y height [hides_id]      a static object's vertical edge
//   PERSON x1 y1 x2 y2 t0 speed       a person walking (speed > 0)
//   PATH x y                          FLAG's next waypoint
// A malformed record is an Error "file:line: reason"; what a world as a whole
// must hold (walls, a start, corners on walls, ...) each experiment checks
// on what it takes, naming the record's line (kept here with each record).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "core/pose2.h"

namespace hamal::apps {

struct WorldFile {
  struct Point {
    Point2 p;
    int line = 0;
  };
  struct Wall {
    Point2 a, b;
    int line = 0;
  };
  struct Corner {
    std::uint64_t id = 0;
    Point2 truth;
    bool has_label = false;
    Point2 label;
    int line = 0;
  };
  struct Object {
    Point2 position;
    double height = 0;
    std::int64_t hides = -1;  // the corner it stands in front of, or -1
    int line = 0;
  };
  struct Person {
    Point2 from, to;
    double t0 = 0, speed = 1;
    int line = 0;
  };

  std::string file;  // as named in messages
  int lines = 0;     // lines read
  std::string name;  // WORLD; empty without one
  bool has_start = false;
  Pose2 start;
  int start_line = 0;
  std::vector<Point> route, path;
  std::vector<Wall> walls;
  std::vector<Corner> corners;
  std::vector<Object> objects;
  std::vector<Person> people;
};

// Reads every record of `in`; throws Error "file:line: reason" for a bad one
// (and "file: cannot read ..." when the stream fails, e.g. a directory).
WorldFile parseWorldFile(std::istream& in, const std::string& file);
WorldFile parseWorldFile(const std::string& text, const std::string& file);

// The smallest wall length accepted, m.
constexpr double kMinWallLength = 1e-6;

}  // namespace hamal::apps
