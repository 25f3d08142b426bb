// MapCorners: the corners of a real log's map, extracted from its wall
// segments, as a person labelling a floor plan would mark them (thesis sec.
// 4.4.2 labels corners on a plan); FLAG's landmarks on a real log, made
// independently of the corner detector FLAG localizes with.
//
// 1. Wall segments: every scan's line segments (split-and-merge,
//    vertical_edge_detector.h's step 2) placed in the world through the
//    scan's reference pose: the reference point cloud's walls, piece by piece.
// 2. Walls: a segment joins the first wall whose direction is within
//    `merge_angle`, whose line passes within `merge_distance` of both of the
//    segment's ends, and whose extent it overlaps or comes within `merge_gap`
//    of; the wall's line is refitted (total least squares over its segments'
//    ends) and its extent grows. A wall seen in at least `min_segments` scans
//    and `min_wall_length` long is kept.
// 3. Corners: two kept walls whose lines meet at an angle within
//    [min_corner_angle, max_corner_angle] at a point within
//    `corner_tolerance` of an end of each (an L, convex or concave), or of
//    an end of one and the other wall's extent (`junctions`: a T, whose stem
//    makes a concave corner either side with the wall running on; a wall's
//    thickness puts the two within the detector's hit radius of the point).
//    Corners closer than `corner_tolerance` to each other are one, at their
//    mean. A corner keeps the directions its walls leave it in (a wall
//    reaching past it by more than `corner_tolerance` on a side leaves it
//    that way; a T's running wall both ways): its shape and orientation, the
//    descriptor association compares a detection's walls with.
#pragma once
#include <vector>

#include "core/pose2.h"

namespace hamal::flag {

struct MapCornerOptions {
  double merge_angle = 5 * 3.14159265358979323846 / 180;  // rad
  double merge_distance = 0.10;                           // m
  double merge_gap = 0.30;                                // m
  int min_segments = 6;
  double min_wall_length = 0.5;                                  // m
  double min_corner_angle = 45 * 3.14159265358979323846 / 180;   // rad
  double max_corner_angle = 135 * 3.14159265358979323846 / 180;  // rad
  double corner_tolerance = 0.15;                                // m
  // A wall ending at another's side (a T, a wall's face meeting a wall that
  // runs on) makes a corner too: the concave corner either side of it.
  bool junctions = true;
  void validate() const;  // throws hamal::Error naming the option
};

struct WallSegment {
  Point2 a, b;  // world frame
};

struct MapWall {
  Point2 a, b;  // the extent's ends on the fitted line
  int segments = 0;
};

// Step 2: the kept walls.
std::vector<MapWall> mergeWalls(const std::vector<WallSegment>& segments,
                                const MapCornerOptions& options);
struct MapCorner {
  Point2 position;
  std::vector<double> walls;  // the directions its walls leave it in (world, rad)
};

// Step 3: the corners of `walls`, with their walls' directions, or their
// positions alone.
std::vector<MapCorner> wallCornerShapes(const std::vector<MapWall>& walls,
                                        const MapCornerOptions& options);
std::vector<Point2> wallCorners(const std::vector<MapWall>& walls, const MapCornerOptions& options);

}  // namespace hamal::flag
