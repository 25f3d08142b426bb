// Laser: see laser.h (thesis sec. 5.5).
#include "apps/moss/laser.h"

#include <cmath>

namespace hamal::moss {

Laser::Laser(LaserConfig config) : config_(config) {}

std::vector<double> Laser::ranges(const Pose2& pose, const std::vector<Segment>& walls,
                                  const std::vector<Segment>& obstacles) const {
  // Only segments that come within range can be hit: the cull keeps a beam's
  // cost to the few walls near the robot.
  std::vector<const Segment*> near;
  const Point2 o = pose.t();
  for (const auto* list : {&walls, &obstacles})
    for (const Segment& s : *list)
      if (distanceToSegment(o, s) < config_.max_range) near.push_back(&s);
  std::vector<double> out(config_.beams);
  const double step = 2.0 * M_PI / config_.beams;
  for (int i = 0; i < config_.beams; ++i) {
    const double a = pose.theta + i * step;
    out[i] = castRay(o, Point2(std::cos(a), std::sin(a)), near, config_.max_range);
  }
  return out;
}

Scan Laser::scan(const Pose2& pose, const std::vector<Segment>& walls,
                 const std::vector<Segment>& obstacles, std::mt19937_64* rng) const {
  const std::vector<double> r = ranges(pose, walls, obstacles);
  std::normal_distribution<double> noise(0.0, config_.sigma_range);
  Scan out;
  out.reserve(r.size());
  const double step = 2.0 * M_PI / config_.beams;
  for (int i = 0; i < config_.beams; ++i) {
    if (r[i] >= config_.max_range) continue;
    const double range = r[i] + (rng ? noise(*rng) : 0.0);
    const double a = i * step;
    out.emplace_back(range * std::cos(a), range * std::sin(a));
  }
  return out;
}

}  // namespace hamal::moss
