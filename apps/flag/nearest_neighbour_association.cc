// Nearest-neighbour association within a gate (nearest_neighbour_association.h).
#include "apps/flag/nearest_neighbour_association.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace hamal::flag {

std::optional<std::size_t> NearestNeighbourAssociation::associate(
    const Point2& point, const std::vector<Point2>& landmarks,
    const Eigen::Matrix2d& pose_covariance, bool* ambiguous) const {
  if (ambiguous) *ambiguous = false;
  const double floor_sigma = gate_ / gate_sigmas_;
  const Eigen::Matrix2d S =
      pose_covariance + floor_sigma * floor_sigma * Eigen::Matrix2d::Identity();
  const Eigen::LLT<Eigen::Matrix2d> llt(S);
  std::optional<std::size_t> best;
  const double gate_d2 = gate_sigmas_ * gate_sigmas_;
  double best_d2 = gate_d2;
  std::size_t within = 0;
  for (std::size_t k = 0; k < landmarks.size(); ++k) {
    const Point2 r = landmarks[k] - point;
    const double d2 = r.dot(llt.solve(r));
    if (d2 <= gate_d2) ++within;
    if (d2 <= best_d2) {
      best_d2 = d2;
      best = k;
    }
  }
  if (reject_ambiguous_ && within > 1) {
    if (ambiguous) *ambiguous = true;
    return std::nullopt;
  }
  return best;
}

Point2 project(const Pose2& pose, double range, double bearing) {
  return pose.transformFrom(Point2(range * std::cos(bearing), range * std::sin(bearing)));
}

}  // namespace hamal::flag
