// First-order propagation of odometry noise (dead_reckoning_uncertainty.h).
#include "apps/flag/dead_reckoning_uncertainty.h"

#include <Eigen/LU>
#include <cmath>

namespace hamal::flag {

Eigen::Matrix3d propagateOdometry(const Eigen::Matrix3d& covariance, const Pose2& from,
                                  const Pose2& odometry, const Eigen::Vector3d& sigma) {
  const double c = std::cos(from.theta), s = std::sin(from.theta);
  // d(compose)/d(from) and d(compose)/d(odometry), both in world coordinates.
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  F(0, 2) = -s * odometry.x - c * odometry.y;
  F(1, 2) = c * odometry.x - s * odometry.y;
  Eigen::Matrix3d G = Eigen::Matrix3d::Identity();
  G.topLeftCorner<2, 2>() = from.R();
  const Eigen::Matrix3d Q = sigma.cwiseProduct(sigma).asDiagonal();
  return F * covariance * F.transpose() + G * Q * G.transpose();
}

Eigen::Matrix2d projectedCovariance(const Eigen::Matrix3d& pose_covariance, const Pose2& pose,
                                    double range, double bearing) {
  const double a = pose.theta + bearing;
  Eigen::Matrix<double, 2, 3> J;
  J << 1, 0, -range * std::sin(a), 0, 1, range * std::cos(a);
  return J * pose_covariance * J.transpose();
}

PoseBelief updateWithRangeBearing(const PoseBelief& belief, const Point2& landmark,
                                  double landmark_sigma, double range, double bearing,
                                  double range_sigma, double bearing_sigma) {
  const Pose2& pose = belief.mean;
  const Point2 d = landmark - pose.t();
  const double q = d.squaredNorm();
  if (!(q > 1e-12)) return belief;  // a landmark at the pose says nothing of it
  const double r = std::sqrt(q);
  // d(range, bearing)/d(x, y, theta) and d(range, bearing)/d(landmark).
  Eigen::Matrix<double, 2, 3> H;
  H << -d.x() / r, -d.y() / r, 0, d.y() / q, -d.x() / q, -1;
  Eigen::Matrix2d Hl;
  Hl << d.x() / r, d.y() / r, -d.y() / q, d.x() / q;
  Eigen::Matrix2d R =
      Eigen::Vector2d(range_sigma * range_sigma, bearing_sigma * bearing_sigma).asDiagonal();
  R += landmark_sigma * landmark_sigma * Hl * Hl.transpose();
  const Eigen::Matrix3d& P = belief.covariance;
  const Eigen::Matrix2d S = H * P * H.transpose() + R;
  const Eigen::Matrix<double, 3, 2> K = P * H.transpose() * S.inverse();
  const Eigen::Vector2d innovation(range - r,
                                   wrapAngle(bearing - (std::atan2(d.y(), d.x()) - pose.theta)));
  const Eigen::Vector3d dx = K * innovation;
  PoseBelief out;
  out.mean = Pose2(pose.x + dx.x(), pose.y + dx.y(), wrapAngle(pose.theta + dx.z()));
  const Eigen::Matrix3d updated = (Eigen::Matrix3d::Identity() - K * H) * P;
  out.covariance = 0.5 * (updated + updated.transpose());
  if (!out.mean.t().allFinite() || !std::isfinite(out.mean.theta) || !out.covariance.allFinite())
    return belief;  // a degenerate update (S singular) leaves the belief as it was
  return out;
}

Eigen::Matrix3d updateWithRangeBearing(const Eigen::Matrix3d& covariance, const Pose2& pose,
                                       const Point2& landmark, double landmark_sigma,
                                       double range_sigma, double bearing_sigma) {
  // The covariance does not depend on the measured values: measure what is
  // predicted.
  const Point2 d = landmark - pose.t();
  const PoseBelief b = updateWithRangeBearing(
      PoseBelief{pose, covariance}, landmark, landmark_sigma, d.norm(),
      wrapAngle(std::atan2(d.y(), d.x()) - pose.theta), range_sigma, bearing_sigma);
  return b.covariance;
}

}  // namespace hamal::flag
