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

Eigen::Matrix3d updateWithRangeBearing(const Eigen::Matrix3d& covariance, const Pose2& pose,
                                       const Point2& landmark, double landmark_sigma,
                                       double range_sigma, double bearing_sigma) {
  const Point2 d = landmark - pose.t();
  const double q = d.squaredNorm();
  if (!(q > 1e-12)) return covariance;  // a landmark at the pose says nothing of it
  const double r = std::sqrt(q);
  // d(range, bearing)/d(x, y, theta) and d(range, bearing)/d(landmark).
  Eigen::Matrix<double, 2, 3> H;
  H << -d.x() / r, -d.y() / r, 0, d.y() / q, -d.x() / q, -1;
  Eigen::Matrix2d Hl;
  Hl << d.x() / r, d.y() / r, -d.y() / q, d.x() / q;
  Eigen::Matrix2d R =
      Eigen::Vector2d(range_sigma * range_sigma, bearing_sigma * bearing_sigma).asDiagonal();
  R += landmark_sigma * landmark_sigma * Hl * Hl.transpose();
  const Eigen::Matrix2d S = H * covariance * H.transpose() + R;
  const Eigen::Matrix<double, 3, 2> K = covariance * H.transpose() * S.inverse();
  const Eigen::Matrix3d P = (Eigen::Matrix3d::Identity() - K * H) * covariance;
  return 0.5 * (P + P.transpose());
}

}  // namespace hamal::flag
