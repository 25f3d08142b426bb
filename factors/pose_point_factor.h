// PosePointFactor: a landmark's position observed in the robot's frame, a
// Pose2 x Point2 constraint with residual e = R(th)^T (l - t) - z (the point
// P of thesis fig. 2.3 projected into frame a, T_a^-1 P; g2o's EDGE_SE2_XY and
// the LANDMARK lines of victoria_park.txt). Whitened as U e, U^T U = Omega.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/factor.h"
#include "core/information.h"
#include "core/mixture_component.h"
#include "core/pose2.h"
#include "core/registry.h"
#include "core/variable_prediction.h"

namespace hamal {

class PosePointFactor : public Factor, public VariablePrediction, public MixtureComponent {
 public:
  // `measurement`: the landmark in pose's frame; `information`: its 2x2 SPD
  // information matrix.
  PosePointFactor(Key pose, Key landmark, const Point2& measurement,
                  const Eigen::Matrix2d& information);

  // Written as g2o's EDGE_SE2_XY "a b zx zy I11 I12 I22" with 17 significant
  // digits, also when read from a GTSAM LANDMARK line (covariance inverted).
  std::string tag() const override { return "EDGE_SE2_XY"; }
  void writeFields(std::ostream& os) const override;
  // The landmark from the pose (l = t + R z); a pose cannot be told from one
  // point, so predicting it returns false.
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;

  const Point2& measurement() const { return measurement_; }
  const Eigen::Matrix2d& information() const { return information_; }
  double logDetInformation() const override { return logDeterminant(information_); }

 private:
  Point2 measurement_;
  Eigen::Matrix2d information_;
};

// The file forms: g2o EDGE_SE2_XY "pose lm zx zy" + information I11 I12 I22,
// and GTSAM LANDMARK with the covariance c11 c12 c22.
std::vector<FactorInfo> posePointFactorInfos();

}  // namespace hamal
