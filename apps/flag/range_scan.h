// RangeScan: a 2.5D range scan (thesis sec. 4.3.2: the 3D point cloud
// projected into 2D with height information), and the simulated scanner that
// ray casts one in a floor plan: walls, static objects as boxes of their
// height and people walking as circles, one return per bearing, each with
// the height of the surface that returned it. FLAG's vertical-edge detector
// (vertical_edge_detector.h) reads these scans instead of the true corners.
//
// The scanner is a documented world, not a claim about one product: 360
// degrees every 0.5 degree, 10 m, range noise 1.5 cm (the order of a
// VLP-16's stated +-3 cm accuracy), walls 2.5 m tall, an object a square box
// 0.4 m on a side centred on its position, a person a 0.25 m circle 1.7 m
// tall. A beam that hits nothing returns max_range (no return).
#pragma once
#include <cmath>
#include <random>
#include <vector>

#include "apps/flag/floor_plan.h"

namespace hamal::flag {

struct RangeScan {
  double start_angle = 0;   // bearing of beam 0 in the sensor frame, rad
  double angular_step = 0;  // rad
  double max_range = 0;     // a range at or beyond this is no return
  std::vector<double> ranges;
  std::vector<double> heights;  // per beam, m; empty: every return is tall

  double bearing(std::size_t i) const { return start_angle + angular_step * double(i); }
  bool hit(std::size_t i) const {
    return ranges[i] > 0 && ranges[i] < max_range && std::isfinite(ranges[i]);
  }
  double height(std::size_t i) const { return heights.empty() ? 1e9 : heights[i]; }
  Point2 point(std::size_t i) const {
    return ranges[i] * Point2(std::cos(bearing(i)), std::sin(bearing(i)));
  }
};

struct RangeScannerOptions {
  double field_of_view = 2 * 3.14159265358979323846;  // rad
  double angular_step = 0.5 * 3.14159265358979323846 / 180;
  double max_range = 10.0;      // m
  double range_sigma = 0.015;   // m, the noise the world draws
  double wall_height = 2.5;     // m
  double object_side = 0.4;     // m
  double person_radius = 0.25;  // m
  double person_height = 1.7;   // m
  // Throws hamal::Error naming the option for a value out of range.
  void validate() const;
};

// The boxes that stand for the plan's static objects (their walls), for
// ray casting and for grading detections.
std::vector<Wall> objectBox(const StaticObject& object, double side);

// The scan from `pose` at `time`; range noise from `rng` (nullptr: exact).
RangeScan castRangeScan(const FloorPlan& plan, const Pose2& pose, double time,
                        const RangeScannerOptions& options, std::mt19937_64* rng);

// True when nothing of the scanner's world (walls, boxes, people at `time`)
// stands strictly between `from` and `to`.
bool lineOfSight(const FloorPlan& plan, const Point2& from, const Point2& to, double time,
                 const RangeScannerOptions& options);

}  // namespace hamal::flag
