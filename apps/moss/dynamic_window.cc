// DynamicWindow: see dynamic_window.h (Fox et al. 1997).
#include "apps/moss/dynamic_window.h"

#include <algorithm>
#include <cmath>

namespace hamal::moss {

namespace {

Pose2 arc(const Pose2& p, double v, double w, double t) {
  if (std::abs(w) < 1e-9)
    return {p.x + v * t * std::cos(p.theta), p.y + v * t * std::sin(p.theta), p.theta};
  const double th = p.theta + w * t;
  return {p.x + v / w * (std::sin(th) - std::sin(p.theta)),
          p.y - v / w * (std::cos(th) - std::cos(p.theta)), wrapAngle(th)};
}

}  // namespace

void DynamicWindow::advance(RobotState* s, double v, double w) const {
  s->pose = arc(s->pose, v, w, config_.dt);
  s->v = v;
  s->w = w;
}

void DynamicWindow::control(const RobotState& s, const Point2& goal,
                            const std::vector<Segment>& segments, double* v_out,
                            double* w_out) const {
  const DynamicWindowConfig& c = config_;
  // Only what the arcs can reach matters.
  const double reach = c.v_max * c.horizon + c.clearance_cap + kRobotRadius;
  std::vector<Segment> near;
  for (const Segment& seg : segments)
    if (distanceToSegment(s.pose.t(), seg) < reach) near.push_back(seg);
  const double v_lo = std::max(0.0, s.v - c.acc_v * c.dt);
  const double v_hi = std::min(c.v_max, s.v + c.acc_v * c.dt);
  const double w_lo = std::max(-c.w_max, s.w - c.acc_w * c.dt);
  const double w_hi = std::min(c.w_max, s.w + c.acc_w * c.dt);
  const int steps = static_cast<int>(std::round(c.horizon / c.dt));
  double best = -1e300, best_v = 0.0, best_w = 0.0;
  bool found = false;
  for (int i = 0; i < c.v_samples; ++i) {
    const double v = v_lo + (v_hi - v_lo) * i / std::max(1, c.v_samples - 1);
    for (int j = 0; j < c.w_samples; ++j) {
      const double w = w_lo + (w_hi - w_lo) * j / std::max(1, c.w_samples - 1);
      double clearance = c.clearance_cap;
      Pose2 p = s.pose;
      for (int k = 1; k <= steps && clearance > 0.0; ++k) {
        p = arc(s.pose, v, w, k * c.dt);
        for (const Segment& seg : near)
          clearance = std::min(clearance, distanceToSegment(p.t(), seg) - kRobotRadius);
      }
      // Admissible: the robot can brake to a stop before the obstacle.
      if (clearance <= 0.0 || v * v / (2.0 * c.acc_v) > clearance) continue;
      const Point2 to_goal = goal - p.t();
      const double angle = std::abs(wrapAngle(std::atan2(to_goal.y(), to_goal.x()) - p.theta));
      const double score = c.w_heading * (1.0 - angle / M_PI) +
                           c.w_clearance * clearance / c.clearance_cap + c.w_velocity * v / c.v_max;
      if (score > best) {
        best = score;
        best_v = v;
        best_w = w;
        found = true;
      }
    }
  }
  if (!found) {
    const Point2 to_goal = goal - s.pose.t();
    const double angle = wrapAngle(std::atan2(to_goal.y(), to_goal.x()) - s.pose.theta);
    best_v = 0.0;
    best_w = std::clamp(angle, -c.w_max, c.w_max);
  }
  *v_out = best_v;
  *w_out = best_w;
}

}  // namespace hamal::moss
