// RangeBearingFactor: range and bearing from a Pose2 to a Point2 landmark
// (thesis sec. 2.2.3.2, eq. 2.34-2.37), e.g. a lidar's detection of a tree.
//
//   e = [ ||l - t|| - z_r ;  wrap(atan2(l_y - y, l_x - x) - th - z_phi) ]
//
// The thesis' eq. 2.35 writes atan2(y_a - y_l, x_a - x_l), the bearing from
// the landmark to the robot, which is off by pi from what a sensor on the
// robot measures; hamal uses the conventional bearing from the robot to the
// landmark, in the robot's frame, as above (and as g2o and GTSAM do). Its
// Jacobian is analytic (the thesis' eq. 2.37 follows its atan2 and a
// derivative of atan that does not hold; ours is d(atan2(dy,dx)) =
// (dx d(dy) - dy d(dx)) / r^2). The residual is singular at r = 0, where
// Evaluate fails.
//
// File line (a hamal tag, g2o has no 2D range-bearing edge):
//   EDGE_SE2_RANGE_BEARING pose landmark range bearing I11 I12 I22
// with the 2x2 information of (range, bearing) as an upper triangle.
#pragma once

#include <Eigen/Core>

#include "core/factor.h"
#include "core/information.h"
#include "core/mixture_component.h"
#include "core/registry.h"
#include "core/variable_prediction.h"

namespace hamal {

class RangeBearingFactor : public Factor, public VariablePrediction, public MixtureComponent {
 public:
  RangeBearingFactor(Key pose, Key landmark, double range, double bearing,
                     const Eigen::Matrix2d& information);

  std::string tag() const override { return "EDGE_SE2_RANGE_BEARING"; }
  // "pose landmark range bearing I11 I12 I22", 17 significant digits.
  void writeFields(std::ostream& os) const override;
  // The landmark from the pose: l = t + range (cos(th + bearing), sin(th + bearing)).
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;

  double range() const { return range_; }
  double bearing() const { return bearing_; }
  const Eigen::Matrix2d& information() const { return information_; }
  double logDetInformation() const override { return logDeterminant(information_); }

 private:
  double range_, bearing_;
  Eigen::Matrix2d information_;
};

// The file form: g2o EDGE_SE2_RANGE_BEARING "pose lm range bearing" +
// information I11 I12 I22 (a hamal tag).
FactorInfo rangeBearingFactorInfo();

}  // namespace hamal
