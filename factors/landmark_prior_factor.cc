// LandmarkPriorFactor: see landmark_prior_factor.h.
#include "factors/landmark_prior_factor.h"

#include <ceres/sized_cost_function.h>

#include <ostream>

#include "core/information.h"
#include "core/line_tokens.h"
#include "factors/full_precision.h"
#include "factors/whitening.h"

namespace hamal {

namespace {
class LandmarkPriorCost : public ceres::SizedCostFunction<2, 2> {
 public:
  LandmarkPriorCost(const Point2& z, const Eigen::Matrix2d& sqrt_info)
      : z_(z), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    Eigen::Map<Eigen::Vector2d> r(residual);
    r = sqrt_info_ * (Eigen::Vector2d(p[0][0], p[0][1]) - z_);
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 2, 2, Eigen::RowMajor>> j(jacobians[0]);
      j = sqrt_info_;
    }
    return true;
  }

 private:
  Point2 z_;
  Eigen::Matrix2d sqrt_info_;
};
FactorPtr parseLandmarkPrior(LineTokens& t) {
  const Key landmark = L(t.keyIndex("landmark"));
  const double x = t.number("x"), y = t.number("y");
  const Eigen::Matrix2d information = readInformation2(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<LandmarkPriorFactor>(landmark, Point2(x, y), information);
}

}  // namespace

LandmarkPriorFactor::LandmarkPriorFactor(Key landmark, const Point2& prior,
                                         const Eigen::Matrix2d& information)
    : Factor({landmark}, std::make_unique<LandmarkPriorCost>(
                             prior, whitening(information, "LandmarkPriorFactor"))),
      prior_(prior),
      information_(information) {}

void LandmarkPriorFactor::writeFields(std::ostream& os) const {
  FullPrecision full(os);
  os << keys()[0].index() << ' ' << prior_.x() << ' ' << prior_.y();
  writeUpperTriangle(os, information_);
}

bool LandmarkPriorFactor::predict(Key unknown, const Values&, Values::Entry* guess) const {
  if (unknown != keys()[0]) return false;
  *guess = {VariableType::kPoint2, {prior_.x(), prior_.y(), 0.0}};
  return true;
}

FactorInfo landmarkPriorFactorInfo() {
  return {"g2o", "EDGE_XY_PRIOR", "prior on a landmark position: id x y + information I11 I12 I22",
          parseLandmarkPrior};
}

}  // namespace hamal
