// PositionFactor: a GPS-like measurement of a pose's position in the global
// frame (thesis sec. 2.2.3.3, eq. 2.39-2.41): e = t - z, two residuals,
// Jacobian [I 0] before whitening (eq. 2.41 plus the zero theta column; the
// thesis writes r = z - F, the same chi2).
//
// File line (a hamal tag): EDGE_SE2_POSITION id x y I11 I12 I22.
#pragma once

#include <Eigen/Core>

#include "core/factor.h"
#include "core/information.h"
#include "core/mixture_component.h"
#include "core/pose2.h"
#include "core/registry.h"
#include "core/variable_prediction.h"

namespace hamal {

class PositionFactor : public Factor, public VariablePrediction, public MixtureComponent {
 public:
  PositionFactor(Key pose, const Point2& position, const Eigen::Matrix2d& information);

  std::string tag() const override { return "EDGE_SE2_POSITION"; }
  // "id x y I11 I12 I22", 17 significant digits.
  void writeFields(std::ostream& os) const override;
  // A pose at the measured position with theta 0: the heading is unknown.
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;

  const Point2& measurement() const { return position_; }
  const Eigen::Matrix2d& information() const { return information_; }
  double logDetInformation() const override { return logDeterminant(information_); }

 private:
  Point2 position_;
  Eigen::Matrix2d information_;
};

// The file form: g2o EDGE_SE2_POSITION "id x y" + information I11 I12 I22 (a
// hamal tag).
FactorInfo positionFactorInfo();

}  // namespace hamal
