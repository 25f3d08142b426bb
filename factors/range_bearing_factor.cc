// RangeBearingFactor: see range_bearing_factor.h (thesis eq. 2.34-2.37, with
// the bearing measured from the robot to the landmark).
#include "factors/range_bearing_factor.h"

#include <ceres/sized_cost_function.h>

#include <cmath>
#include <ostream>

#include "core/information.h"
#include "core/line_tokens.h"
#include "core/pose2.h"
#include "factors/full_precision.h"
#include "factors/whitening.h"

namespace hamal {

namespace {
class RangeBearingCost : public ceres::SizedCostFunction<2, 3, 2> {
 public:
  RangeBearingCost(double range, double bearing, const Eigen::Matrix2d& sqrt_info)
      : range_(range), bearing_(bearing), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    const double* pose = p[0];
    const double* l = p[1];
    const double dx = l[0] - pose[0], dy = l[1] - pose[1];
    const double r2 = dx * dx + dy * dy;
    const double r = std::sqrt(r2);
    // The bearing is undefined with the landmark on the robot.
    if (!(r > 0.0)) return false;
    const Eigen::Vector2d e(r - range_, wrapAngle(std::atan2(dy, dx) - pose[2] - bearing_));
    Eigen::Map<Eigen::Vector2d> res(residual);
    res = sqrt_info_ * e;
    if (!jacobians) return true;
    if (jacobians[0]) {
      Eigen::Matrix<double, 2, 3> jp;
      jp << -dx / r, -dy / r, 0.0,  //
          dy / r2, -dx / r2, -1.0;
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> j(jacobians[0]);
      j = sqrt_info_ * jp;
    }
    if (jacobians[1]) {
      Eigen::Matrix2d jl;
      jl << dx / r, dy / r,  //
          -dy / r2, dx / r2;
      Eigen::Map<Eigen::Matrix<double, 2, 2, Eigen::RowMajor>> j(jacobians[1]);
      j = sqrt_info_ * jl;
    }
    return true;
  }

 private:
  double range_, bearing_;
  Eigen::Matrix2d sqrt_info_;
};
FactorPtr parseRangeBearing(LineTokens& t) {
  const Key pose = X(t.keyIndex("pose")), landmark = L(t.keyIndex("landmark"));
  const double range = t.number("range"), bearing = t.angle("bearing");
  const Eigen::Matrix2d information = readInformation2(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<RangeBearingFactor>(pose, landmark, range, bearing, information);
}

}  // namespace

RangeBearingFactor::RangeBearingFactor(Key pose, Key landmark, double range, double bearing,
                                       const Eigen::Matrix2d& information)
    : Factor({pose, landmark}, std::make_unique<RangeBearingCost>(
                                   range, bearing, whitening(information, "RangeBearingFactor"))),
      range_(range),
      bearing_(bearing),
      information_(information) {}

void RangeBearingFactor::writeFields(std::ostream& os) const {
  FullPrecision full(os);
  os << keys()[0].index() << ' ' << keys()[1].index() << ' ' << range_ << ' ' << bearing_;
  writeUpperTriangle(os, information_);
}

bool RangeBearingFactor::predict(Key unknown, const Values& known, Values::Entry* guess) const {
  if (unknown != keys()[1] || !known.contains(keys()[0])) return false;
  const Pose2 pose = known.pose(keys()[0]);
  const double a = pose.theta + bearing_;
  *guess = {VariableType::kPoint2,
            {pose.x + range_ * std::cos(a), pose.y + range_ * std::sin(a), 0.0}};
  return true;
}

FactorInfo rangeBearingFactorInfo() {
  return {"g2o", "EDGE_SE2_RANGE_BEARING",
          "range and bearing (robot to landmark, robot frame) from a pose to a landmark: pose lm "
          "range bearing + information I11 I12 I22 (hamal tag)",
          parseRangeBearing};
}

}  // namespace hamal
