// PriorFactor: a Gaussian prior on a Pose2, e = [x - x0, y - y0, wrap(th - th0)]
// (the anchor the thesis protocol puts on the first pose, docs/PROTOCOL.md, "The thesis
// protocol";
// g2o's EDGE_SE2_PRIOR). Residual U e with U^T U = Omega; Jacobian U.
#pragma once

#include <Eigen/Core>

#include "core/factor.h"
#include "core/information.h"
#include "core/mixture_component.h"
#include "core/pose2.h"
#include "core/registry.h"
#include "core/variable_prediction.h"

namespace hamal {

class PriorFactor : public Factor, public VariablePrediction, public MixtureComponent {
 public:
  PriorFactor(Key key, const Pose2& prior, const Eigen::Matrix3d& information);

  std::string tag() const override { return "EDGE_SE2_PRIOR"; }
  void writeFields(std::ostream& os) const override;
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;

  const Pose2& measurement() const { return prior_; }
  const Eigen::Matrix3d& information() const { return information_; }
  double logDetInformation() const override { return logDeterminant(information_); }

 private:
  Pose2 prior_;
  Eigen::Matrix3d information_;
};

// The file form: g2o EDGE_SE2_PRIOR "id x y th" + information I11 I12 I13 I22
// I23 I33.
FactorInfo priorFactorInfo();

}  // namespace hamal
