// DeadReckoningUncertainty: how uncertain the predicted pose is, as an
// extended Kalman filter's covariance beside the graph: odometry noise is
// propagated through Pose2::compose (first order), and each accepted
// range-bearing measurement shrinks it by the usual Kalman update (the
// landmark's label uncertainty counted as measurement noise). It is an
// approximation of the back-end's marginal that costs a few 3x3 products a
// step, and widens the nearest-neighbour gate where the robot has coasted
// (thesis sec. 4.3.3 associates within a fixed 50 cm; on long stretches
// without landmarks, or real odometry, the drift outgrows that).
// The same filter's mean, updated by the step's accepted measurements, is
// where FLAG starts each new pose (FlagOptions::odometry.corrected_guess).
#pragma once
#include <Eigen/Core>

#include "core/pose2.h"

namespace hamal::flag {

// The covariance (world frame, x y theta) of `from.compose(odometry)` given
// `covariance` of `from` and independent odometry noise of `sigma` (x, y,
// theta, in the odometry's own frame).
Eigen::Matrix3d propagateOdometry(const Eigen::Matrix3d& covariance, const Pose2& from,
                                  const Pose2& odometry, const Eigen::Vector3d& sigma);

// The covariance of a detection's world point at (range, bearing) from `pose`
// due to the pose's covariance alone.
Eigen::Matrix2d projectedCovariance(const Eigen::Matrix3d& pose_covariance, const Pose2& pose,
                                    double range, double bearing);

// The covariance after a range-bearing measurement from `pose` of a landmark
// at `landmark` (covariance landmark_sigma^2 I) with noise (range_sigma,
// bearing_sigma) is accepted: the Kalman update of `covariance`.
Eigen::Matrix3d updateWithRangeBearing(const Eigen::Matrix3d& covariance, const Pose2& pose,
                                       const Point2& landmark, double landmark_sigma,
                                       double range_sigma, double bearing_sigma);

// The same Kalman update for the mean too: `pose` moved by the gain times
// the innovation (range, bearing measured minus predicted from `pose`).
// FLAG starts a new pose there instead of at the odometry's prediction, so
// that a max-mixture is first evaluated where the pose's own measurements
// put it: evaluated at a prediction that has drifted, a right measurement
// looks like an outlier, its null hypothesis wins, and a null hypothesis
// pulls the estimate too little to ever switch back.
struct PoseBelief {
  Pose2 mean;
  Eigen::Matrix3d covariance;
};
PoseBelief updateWithRangeBearing(const PoseBelief& belief, const Point2& landmark,
                                  double landmark_sigma, double range, double bearing,
                                  double range_sigma, double bearing_sigma);

}  // namespace hamal::flag
