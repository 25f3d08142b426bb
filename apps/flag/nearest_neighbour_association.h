// NearestNeighbourAssociation: a detection to the landmark nearest to where
// it projects, within a gate (thesis sec. 4.3.3: the max-mixtures are
// "bootstrapped with nearest-neighbor associations"; sec. 4.4.3.1: 50 cm).
//
// The gate may grow with the pose's uncertainty: given the covariance P of
// the projected point due to the pose (DeadReckoningUncertainty), the
// distance is Mahalanobis in S = P + (gate / gate_sigmas)^2 I and a landmark
// is within the gate when that distance is at most gate_sigmas. With P = 0
// this is exactly the thesis' fixed Euclidean gate; the gate never shrinks
// below it.
//
// With `reject_ambiguous`, a detection with two or more landmarks within its
// gate is left unassociated (ours: the unique-candidate rule of individual
// compatibility testing): where landmarks stand closer together than the
// gate is wide (trees in a park) nearest neighbour picks the wrong one of a
// pair about as often as the right one, and a measurement not made costs
// less than a wrong one.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/pose2.h"

namespace hamal::flag {

class NearestNeighbourAssociation {
 public:
  explicit NearestNeighbourAssociation(double gate, double gate_sigmas = 3.0,
                                       bool reject_ambiguous = false)
      : gate_(gate), gate_sigmas_(gate_sigmas), reject_ambiguous_(reject_ambiguous) {}
  // `landmarks[k]` is where landmark `ids[k]` is believed to be now.
  // Returns the index k of the nearest one within the gate of `point`, whose
  // covariance due to the pose is `pose_covariance` (zero: the fixed gate);
  // none when none is, or (reject_ambiguous) when more than one is, and then
  // `*ambiguous` (if given) is set.
  std::optional<std::size_t> associate(
      const Point2& point, const std::vector<Point2>& landmarks,
      const Eigen::Matrix2d& pose_covariance = Eigen::Matrix2d::Zero(),
      bool* ambiguous = nullptr) const;
  double gate() const { return gate_; }

 private:
  double gate_;
  double gate_sigmas_;
  bool reject_ambiguous_;
};

// Where a range-bearing detection from `pose` lies in the world.
Point2 project(const Pose2& pose, double range, double bearing);

}  // namespace hamal::flag
