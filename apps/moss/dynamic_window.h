// DynamicWindow: the Dynamic Window approach to collision avoidance (Fox,
// Burgard & Thrun 1997), which drives the simulated robot of thesis sec. 5.5
// to its waypoints around static obstacles.
//
// Each control cycle searches the velocities (v, w) reachable within one
// cycle under the acceleration limits (the dynamic window), keeps the
// admissible ones (the robot can still stop before the nearest obstacle on
// the arc it would drive), and picks the one maximising Fox's objective
//   heading (alignment with the goal at the end of the arc)
//   + clearance (distance to the nearest obstacle on the arc, capped)
//   + velocity (forward speed),
// each normalised to [0, 1] and weighted.
#pragma once

#include <vector>

#include "apps/moss/world.h"

namespace hamal::moss {

struct DynamicWindowConfig {
  double v_max = 0.5, w_max = 1.5;    // m/s, rad/s
  double acc_v = 1.0, acc_w = 3.0;    // m/s^2, rad/s^2
  double dt = 0.1;                    // s, one control cycle
  double horizon = 1.5;               // s, how far an arc is simulated
  int v_samples = 6, w_samples = 15;  // grid over the window
  double w_heading = 1.0, w_clearance = 0.3, w_velocity = 0.2;
  double clearance_cap = 1.0;  // m
};

struct RobotState {
  Pose2 pose;
  double v = 0.0, w = 0.0;
};

class DynamicWindow {
 public:
  explicit DynamicWindow(DynamicWindowConfig config = {}) : config_(config) {}
  const DynamicWindowConfig& config() const { return config_; }
  // The (v, w) of the next cycle towards `goal`, avoiding `segments` (walls
  // and obstacles). No admissible arc: stop and turn in place towards the goal.
  void control(const RobotState& state, const Point2& goal, const std::vector<Segment>& segments,
               double* v, double* w) const;
  // Moves `state` one cycle with (v, w) (exact arc).
  void advance(RobotState* state, double v, double w) const;

 private:
  DynamicWindowConfig config_;
};

}  // namespace hamal::moss
