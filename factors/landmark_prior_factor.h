// LandmarkPriorFactor: a Gaussian prior on a Point2 landmark, e = l - z
// (the landmark counterpart of the thesis' pose prior; g2o's EDGE_XY_PRIOR:
// "EDGE_XY_PRIOR id x y I11 I12 I22"). Residual U e, Jacobian U.
#pragma once

#include <Eigen/Core>

#include "core/factor.h"
#include "core/information.h"
#include "core/mixture_component.h"
#include "core/pose2.h"
#include "core/registry.h"
#include "core/variable_prediction.h"

namespace hamal {

class LandmarkPriorFactor : public Factor, public VariablePrediction, public MixtureComponent {
 public:
  LandmarkPriorFactor(Key landmark, const Point2& prior, const Eigen::Matrix2d& information);

  std::string tag() const override { return "EDGE_XY_PRIOR"; }
  // "id x y I11 I12 I22", 17 significant digits.
  void writeFields(std::ostream& os) const override;
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;

  const Point2& measurement() const { return prior_; }
  const Eigen::Matrix2d& information() const { return information_; }
  double logDetInformation() const override { return logDeterminant(information_); }

 private:
  Point2 prior_;
  Eigen::Matrix2d information_;
};

// The file form: g2o EDGE_XY_PRIOR "id x y" + information I11 I12 I22.
FactorInfo landmarkPriorFactorInfo();

}  // namespace hamal
