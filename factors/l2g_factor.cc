// L2GFactor: see l2g_factor.h (thesis sec. 5.3.2, eq. 5.2).
#include "factors/l2g_factor.h"

#include <ceres/sized_cost_function.h>

#include <memory>
#include <ostream>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/line_tokens.h"
#include "factors/full_precision.h"

namespace hamal {

namespace {

// e is affine in a with a constant Jacobian: W = U diag(R(th_b)^T, 1).
class L2GCost : public ceres::SizedCostFunction<3, 3> {
 public:
  L2GCost(const Pose2& b, const Pose2& z, const Eigen::Matrix3d& u) : b_(b), z_(z), u_(u) {
    Eigen::Matrix3d rotate = Eigen::Matrix3d::Identity();
    rotate.topLeftCorner<2, 2>() = b.R().transpose();
    w_ = u_ * rotate;
  }

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    const double* a = p[0];
    const double c = std::cos(b_.theta), s = std::sin(b_.theta);
    const double dx = a[0] - b_.x, dy = a[1] - b_.y;
    const Eigen::Vector3d e(c * dx + s * dy - z_.x, -s * dx + c * dy - z_.y,
                            wrapAngle(a[2] - b_.theta - z_.theta));
    Eigen::Map<Eigen::Vector3d> r(residual);
    r = u_ * e;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[0]);
      j = w_;
    }
    return true;
  }

 private:
  Pose2 b_, z_;
  Eigen::Matrix3d u_, w_;
};

Eigen::Matrix3d checkedWhitening(const Eigen::Matrix3d& information) {
  if (!isSymmetricPositiveDefinite(information)) {
    std::ostringstream os;
    os << "L2GFactor: the information matrix is not symmetric positive definite: ["
       << information.format(Eigen::IOFormat(6, 0, ", ", "; ")) << "]";
    throw Error(os.str());
  }
  return sqrtInformation(information);
}

FactorPtr parseL2G(LineTokens& t) {
  const std::uint64_t a = t.keyIndex("pose a");
  const std::uint64_t b = t.id("map node b");
  const double bx = t.number("bx"), by = t.number("by"), bth = t.angle("bth");
  const double dx = t.number("dx"), dy = t.number("dy"), dth = t.angle("dth");
  const Eigen::Matrix3d information = readInformation3(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<L2GFactor>(X(a), b, Pose2(bx, by, bth), Pose2(dx, dy, dth), information);
}

}  // namespace

L2GFactor::L2GFactor(Key a, std::uint64_t map_node, const Pose2& map_pose, const Pose2& measurement,
                     const Eigen::Matrix3d& information)
    : Factor({a}, std::make_unique<L2GCost>(map_pose, measurement, checkedWhitening(information))),
      map_node_(map_node),
      map_pose_(map_pose),
      measurement_(measurement),
      information_(information) {}

void L2GFactor::writeFields(std::ostream& os) const {
  FullPrecision full(os);
  os << keys()[0].index() << ' ' << map_node_ << ' ' << map_pose_.x << ' ' << map_pose_.y << ' '
     << map_pose_.theta << ' ' << measurement_.x << ' ' << measurement_.y << ' '
     << measurement_.theta;
  writeUpperTriangle(os, information_);
}

bool L2GFactor::predict(Key unknown, const Values&, Values::Entry* guess) const {
  if (unknown != keys()[0]) return false;
  const Pose2 p = globalPose();
  *guess = {VariableType::kPose2, {p.x, p.y, p.theta}};
  return true;
}

FactorInfo l2gFactorInfo() {
  return {"g2o", "EDGE_SE2_L2G",
          "scan match of pose a against prior-map node b of known global pose (thesis eq. 5.2): "
          "a b bx by bth dx dy dth + information I11 I12 I13 I22 I23 I33 (hamal tag; b is not a "
          "variable)",
          parseL2G};
}

}  // namespace hamal
