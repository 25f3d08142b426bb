// Nearest-neighbour association within a gate (nearest_neighbour_association.h).
#include "apps/flag/nearest_neighbour_association.h"

#include <cmath>

namespace hamal::flag {

std::optional<std::size_t> NearestNeighbourAssociation::associate(
    const Point2& point, const std::vector<Point2>& landmarks) const {
  std::optional<std::size_t> best;
  double best_d2 = gate_ * gate_;
  for (std::size_t k = 0; k < landmarks.size(); ++k) {
    const double d2 = (landmarks[k] - point).squaredNorm();
    if (d2 <= best_d2) {
      best_d2 = d2;
      best = k;
    }
  }
  return best;
}

Point2 project(const Pose2& pose, double range, double bearing) {
  return pose.transformFrom(Point2(range * std::cos(bearing), range * std::sin(bearing)));
}

}  // namespace hamal::flag
