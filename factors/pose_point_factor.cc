// PosePointFactor: see pose_point_factor.h.
#include "factors/pose_point_factor.h"

#include <ceres/sized_cost_function.h>

#include <ostream>

#include "core/information.h"
#include "core/line_tokens.h"
#include "factors/full_precision.h"
#include "factors/whitening.h"

namespace hamal {

namespace {
class PosePointCost : public ceres::SizedCostFunction<2, 3, 2> {
 public:
  PosePointCost(const Point2& z, const Eigen::Matrix2d& sqrt_info) : z_(z), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    const double* pose = p[0];
    const double* l = p[1];
    const double c = std::cos(pose[2]), s = std::sin(pose[2]);
    const double dx = l[0] - pose[0], dy = l[1] - pose[1];
    const Eigen::Vector2d e(c * dx + s * dy - z_.x(), -s * dx + c * dy - z_.y());
    Eigen::Map<Eigen::Vector2d> r(residual);
    r = sqrt_info_ * e;
    if (!jacobians) return true;
    if (jacobians[0]) {
      Eigen::Matrix<double, 2, 3> jp;
      jp << -c, -s, -s * dx + c * dy,  //
          s, -c, -c * dx - s * dy;
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> j(jacobians[0]);
      j = sqrt_info_ * jp;
    }
    if (jacobians[1]) {
      Eigen::Matrix2d jl;
      jl << c, s,  //
          -s, c;
      Eigen::Map<Eigen::Matrix<double, 2, 2, Eigen::RowMajor>> j(jacobians[1]);
      j = sqrt_info_ * jl;
    }
    return true;
  }

 private:
  Point2 z_;
  Eigen::Matrix2d sqrt_info_;
};
FactorPtr parsePosePoint(LineTokens& t, MatrixLayout layout) {
  const Key pose = X(t.keyIndex("pose")), landmark = L(t.keyIndex("landmark"));
  const double zx = t.number("zx"), zy = t.number("zy");
  const Eigen::Matrix2d information = readInformation2(t, layout);
  t.expectEnd();
  return std::make_shared<PosePointFactor>(pose, landmark, Point2(zx, zy), information);
}

}  // namespace

PosePointFactor::PosePointFactor(Key pose, Key landmark, const Point2& measurement,
                                 const Eigen::Matrix2d& information)
    : Factor({pose, landmark}, std::make_unique<PosePointCost>(
                                   measurement, whitening(information, "PosePointFactor"))),
      measurement_(measurement),
      information_(information) {}

void PosePointFactor::writeFields(std::ostream& os) const {
  FullPrecision full(os);
  os << keys()[0].index() << ' ' << keys()[1].index() << ' ' << measurement_.x() << ' '
     << measurement_.y();
  writeUpperTriangle(os, information_);
}

bool PosePointFactor::predict(Key unknown, const Values& known, Values::Entry* guess) const {
  if (unknown != keys()[1] || !known.contains(keys()[0])) return false;
  const Point2 l = known.pose(keys()[0]).transformFrom(measurement_);
  *guess = {VariableType::kPoint2, {l.x(), l.y(), 0.0}};
  return true;
}

std::vector<FactorInfo> posePointFactorInfos() {
  return {
      {"g2o", "EDGE_SE2_XY",
       "landmark position seen in the pose's frame: pose lm zx zy + information I11 I12 I22",
       [](LineTokens& t) { return parsePosePoint(t, MatrixLayout::kG2oInformation); }},
      {"gtsam", "LANDMARK",
       "landmark position seen in the pose's frame: pose lm zx zy + COVARIANCE c11 c12 c22 "
       "(victoria_park.txt)",
       [](LineTokens& t) { return parsePosePoint(t, MatrixLayout::kG2oCovariance); }},
  };
}

}  // namespace hamal
