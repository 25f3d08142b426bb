// PriorFactor: see prior_factor.h.
#include "factors/prior_factor.h"

#include <ceres/sized_cost_function.h>

#include "core/information.h"
#include "core/line_tokens.h"
#include "factors/full_precision.h"
#include "factors/whitening.h"

namespace hamal {

namespace {
class PriorCost : public ceres::SizedCostFunction<3, 3> {
 public:
  PriorCost(const Pose2& prior, const Eigen::Matrix3d& sqrt_info)
      : prior_(prior), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    const Eigen::Vector3d e(p[0][0] - prior_.x, p[0][1] - prior_.y,
                            wrapAngle(p[0][2] - prior_.theta));
    Eigen::Map<Eigen::Vector3d> r(residual);
    r = sqrt_info_ * e;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[0]);
      j = sqrt_info_;
    }
    return true;
  }

 private:
  Pose2 prior_;
  Eigen::Matrix3d sqrt_info_;
};
FactorPtr parsePrior(LineTokens& t) {
  const Key k = X(t.keyIndex("pose"));
  const double x = t.number("x"), y = t.number("y"), th = t.angle("th");
  const Eigen::Matrix3d information = readInformation3(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<PriorFactor>(k, Pose2(x, y, th), information);
}

}  // namespace

PriorFactor::PriorFactor(Key key, const Pose2& prior, const Eigen::Matrix3d& information)
    : Factor({key}, std::make_unique<PriorCost>(prior, whitening(information, "PriorFactor"))),
      prior_(prior),
      information_(information) {}

void PriorFactor::writeFields(std::ostream& os) const {
  FullPrecision full(os);
  os << keys()[0].index() << ' ' << prior_.x << ' ' << prior_.y << ' ' << prior_.theta;
  writeUpperTriangle(os, information_);
}

bool PriorFactor::predict(Key unknown, const Values&, Values::Entry* guess) const {
  if (unknown != keys()[0]) return false;
  *guess = {VariableType::kPose2, {prior_.x, prior_.y, prior_.theta}};
  return true;
}

FactorInfo priorFactorInfo() {
  return {"g2o", "EDGE_SE2_PRIOR",
          "prior on a pose: id x y th + information I11 I12 I13 I22 I23 I33", parsePrior};
}

}  // namespace hamal
