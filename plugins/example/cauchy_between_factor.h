// CauchyBetweenFactor: the example plugin's factor kind, g2o tag
// EDGE_SE2_CAUCHY: the rigid-body between of factors/between_factor.h (thesis
// sec. 2.2.3.1, eq. 2.28-2.32) minimised under a Cauchy loss, the robust
// kernel the thesis' loop-closure discussion (sec. 2.3) motivates.
//
// It shows the cheapest way to add a factor kind in a plugin: reuse a public
// factor's residual and Jacobians by deriving from it, and change only what
// differs: the loss, the tag, and the extra field on the line. chi2 (core/
// metrics.h) ignores the loss, so figures stay comparable with EDGE_SE2.
//
// Line: EDGE_SE2_CAUCHY a b dx dy dth I11 I12 I13 I22 I23 I33 scale
// `scale` is ceres::CauchyLoss's a: rho(s) = a^2 log(1 + s / a^2), with s the
// squared whitened residual, so residuals much larger than `scale` are
// down-weighted.
#pragma once

#include "core/registry.h"
#include "factors/between_factor.h"

namespace hamal::example {

class CauchyBetweenFactor : public BetweenFactor {
 public:
  // Throws hamal::Error unless scale > 0.
  CauchyBetweenFactor(Key a, Key b, const Pose2& measurement, const Eigen::Matrix3d& information,
                      double scale);

  std::string tag() const override { return "EDGE_SE2_CAUCHY"; }
  void writeFields(std::ostream& os) const override;

  double scale() const { return scale_; }

 private:
  double scale_;
};

// The registry entry: format "g2o", tag "EDGE_SE2_CAUCHY".
FactorInfo cauchyBetweenFactorInfo();

}  // namespace hamal::example
