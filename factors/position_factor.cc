// PositionFactor: see position_factor.h (thesis eq. 2.39-2.41).
#include "factors/position_factor.h"

#include <ceres/sized_cost_function.h>

#include <ostream>

#include "core/information.h"
#include "core/line_tokens.h"
#include "factors/full_precision.h"
#include "factors/whitening.h"

namespace hamal {

namespace {
class PositionCost : public ceres::SizedCostFunction<2, 3> {
 public:
  PositionCost(const Point2& z, const Eigen::Matrix2d& sqrt_info) : z_(z), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    Eigen::Map<Eigen::Vector2d> r(residual);
    r = sqrt_info_ * (Eigen::Vector2d(p[0][0], p[0][1]) - z_);
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> j(jacobians[0]);
      j.leftCols<2>() = sqrt_info_;
      j.col(2).setZero();
    }
    return true;
  }

 private:
  Point2 z_;
  Eigen::Matrix2d sqrt_info_;
};
FactorPtr parsePosition(LineTokens& t) {
  const Key pose = X(t.keyIndex("pose"));
  const double x = t.number("x"), y = t.number("y");
  const Eigen::Matrix2d information = readInformation2(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<PositionFactor>(pose, Point2(x, y), information);
}

}  // namespace

PositionFactor::PositionFactor(Key pose, const Point2& position, const Eigen::Matrix2d& information)
    : Factor({pose},
             std::make_unique<PositionCost>(position, whitening(information, "PositionFactor"))),
      position_(position),
      information_(information) {}

void PositionFactor::writeFields(std::ostream& os) const {
  FullPrecision full(os);
  os << keys()[0].index() << ' ' << position_.x() << ' ' << position_.y();
  writeUpperTriangle(os, information_);
}

bool PositionFactor::predict(Key unknown, const Values&, Values::Entry* guess) const {
  if (unknown != keys()[0]) return false;
  *guess = {VariableType::kPose2, {position_.x(), position_.y(), 0.0}};
  return true;
}

FactorInfo positionFactorInfo() {
  return {"g2o", "EDGE_SE2_POSITION",
          "GPS position of a pose in the global frame: id x y + information I11 I12 I22 (hamal "
          "tag)",
          parsePosition};
}

}  // namespace hamal
