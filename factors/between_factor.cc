// BetweenFactor: see between_factor.h (thesis eq. 2.28-2.32).
#include "factors/between_factor.h"

#include <ceres/sized_cost_function.h>

#include <Eigen/Geometry>
#include <map>
#include <ostream>
#include <typeinfo>

#include "core/information.h"
#include "core/line_tokens.h"
#include "factors/full_precision.h"
#include "factors/max_mixture_factor.h"
#include "factors/whitening.h"

namespace hamal {

namespace {

// Both residuals are a constant 3x3 matrix times the thesis' error: the
// measurement-frame one rotates the translation part by R(z_th)^T first. So
// one cost function serves both, with W = U (thesis) or U diag(R(z_th)^T, 1).
class BetweenCost : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  BetweenCost(const Pose2& z, const Eigen::Matrix3d& weight) : z_(z), weight_(weight) {}

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    const double* a = p[0];
    const double* b = p[1];
    const double c = std::cos(a[2]), s = std::sin(a[2]);
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    // eq. 2.28-2.30 minus the measurement.
    const Eigen::Vector3d e(c * dx + s * dy - z_.x, -s * dx + c * dy - z_.y,
                            wrapAngle(b[2] - a[2] - z_.theta));
    Eigen::Map<Eigen::Vector3d> r(residual);
    r = weight_ * e;
    if (!jacobians) return true;
    if (jacobians[0]) {
      // eq. 2.32, left block, sign flipped (e = F - z).
      Eigen::Matrix3d ja;
      ja << -c, -s, -s * dx + c * dy,  //
          s, -c, -c * dx - s * dy,     //
          0.0, 0.0, -1.0;
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[0]);
      j = weight_ * ja;
    }
    if (jacobians[1]) {
      Eigen::Matrix3d jb;
      jb << c, s, 0.0,  //
          -s, c, 0.0,   //
          0.0, 0.0, 1.0;
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> j(jacobians[1]);
      j = weight_ * jb;
    }
    return true;
  }

 private:
  Pose2 z_;
  Eigen::Matrix3d weight_;
};

Eigen::Matrix3d residualWeight(const Pose2& z, const Eigen::Matrix3d& information,
                               BetweenResidual residual) {
  const Eigen::Matrix3d u = whitening(information, "BetweenFactor");
  if (residual == BetweenResidual::kThesis) return u;
  Eigen::Matrix3d rotate = Eigen::Matrix3d::Identity();
  rotate.topLeftCorner<2, 2>() = z.R().transpose();
  return u * rotate;
}

FactorPtr parseBetween(LineTokens& t, MatrixLayout layout) {
  const Key a = X(t.keyIndex("pose a")), b = X(t.keyIndex("pose b"));
  const double dx = t.number("dx"), dy = t.number("dy"), dth = t.angle("dth");
  const Eigen::Matrix3d information = readInformation3(t, layout);
  t.expectEnd();
  return std::make_shared<BetweenFactor>(a, b, Pose2(dx, dy, dth), information);
}

FactorInfo betweenInfo(std::string format, std::string tag, MatrixLayout layout,
                       std::string description) {
  return {std::move(format), std::move(tag), std::move(description),
          [layout](LineTokens& t) { return parseBetween(t, layout); }};
}

}  // namespace

const char* betweenResidualName(BetweenResidual residual) {
  return residual == BetweenResidual::kThesis ? "thesis" : "measurement-frame";
}

BetweenFactor::BetweenFactor(Key a, Key b, const Pose2& measurement,
                             const Eigen::Matrix3d& information, BetweenResidual residual)
    : Factor({a, b}, std::make_unique<BetweenCost>(
                         measurement, residualWeight(measurement, information, residual))),
      measurement_(measurement),
      information_(information),
      residual_(residual) {}

void BetweenFactor::writeFields(std::ostream& os) const {
  FullPrecision full(os);
  os << keys()[0].index() << ' ' << keys()[1].index() << ' ' << measurement_.x << ' '
     << measurement_.y << ' ' << measurement_.theta;
  writeUpperTriangle(os, information_);
}

bool BetweenFactor::equals(const Factor& other, double tolerance) const {
  return Factor::equals(other, tolerance) &&
         static_cast<const BetweenFactor&>(other).residual_ == residual_;
}

bool BetweenFactor::predict(Key unknown, const Values& known, Values::Entry* guess) const {
  const Key a = keys()[0], b = keys()[1];
  Pose2 p;
  if (unknown == b && known.contains(a)) {
    p = known.pose(a).compose(measurement_);
  } else if (unknown == a && known.contains(b)) {
    p = known.pose(b).compose(measurement_.inverse());
  } else {
    return false;
  }
  *guess = {VariableType::kPose2, {p.x, p.y, p.theta}};
  return true;
}

namespace {

// A plain BetweenFactor with `residual`, or nullptr when `f` is another kind
// or has it already.
FactorPtr withResidual(const FactorPtr& f, BetweenResidual residual) {
  // Only plain BetweenFactors: a subclass (a plugin's factor) has its own
  // tag and fields, which a swap to the base class would lose on writing.
  if (typeid(*f) != typeid(BetweenFactor)) return nullptr;
  const auto* between = static_cast<const BetweenFactor*>(f.get());
  if (between->residual() == residual) return nullptr;
  auto swapped =
      std::make_shared<BetweenFactor>(between->keys()[0], between->keys()[1],
                                      between->measurement(), between->information(), residual);
  // Factor keeps its loss private: share it through an aliasing pointer
  // that keeps the old factor (its owner) alive.
  if (f->lossFunction())
    swapped->setLoss(std::shared_ptr<ceres::LossFunction>(f, f->lossFunction()));
  return swapped;
}

// The same mixture with its between components swapped (one swap per
// component factor, so a nominal + null pair stays one factor), or nullptr.
FactorPtr mixtureWithResidual(const MaxMixtureFactor& mix, const FactorPtr& f,
                              BetweenResidual residual) {
  std::vector<MaxMixtureFactor::Component> components = mix.components();
  std::map<const Factor*, FactorPtr> swapped;
  for (auto& c : components) {
    auto it = swapped.find(c.factor.get());
    if (it == swapped.end())
      it = swapped.emplace(c.factor.get(), withResidual(c.factor, residual)).first;
    if (it->second) c.factor = it->second;
  }
  bool any = false;
  for (const auto& kv : swapped) any |= kv.second != nullptr;
  if (!any) return nullptr;
  auto out = std::make_shared<MaxMixtureFactor>(std::move(components));
  if (f->lossFunction()) out->setLoss(std::shared_ptr<ceres::LossFunction>(f, f->lossFunction()));
  return out;
}

}  // namespace

std::optional<RelativePose> BetweenFactor::relativePose() const {
  if (residual_ == BetweenResidual::kThesis)
    return RelativePose{keys()[0], keys()[1], measurement_, information_};
  // The measurement-frame residual is the thesis' one with its translation
  // rotated by R(z_th)^T, so its information in a's frame is T Omega T^T.
  Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
  t.topLeftCorner<2, 2>() = Eigen::Rotation2Dd(measurement_.theta).toRotationMatrix();
  return RelativePose{keys()[0], keys()[1], measurement_, t * information_ * t.transpose()};
}

std::shared_ptr<Factor> BetweenFactor::relativePoseFactor(const RelativePose& r) const {
  return std::make_shared<BetweenFactor>(r.from, r.to, r.measurement, r.information);
}

int setBetweenResidual(Graph& graph, BetweenResidual residual) {
  int replaced = 0;
  for (FactorPtr& f : graph.factors) {
    if (const auto* mix = dynamic_cast<const MaxMixtureFactor*>(f.get())) {
      if (FactorPtr swapped = mixtureWithResidual(*mix, f, residual)) {
        f = std::move(swapped);
        ++replaced;
      }
      continue;
    }
    if (FactorPtr swapped = withResidual(f, residual)) {
      f = std::move(swapped);
      ++replaced;
    }
  }
  return replaced;
}

std::vector<FactorInfo> betweenFactorInfos() {
  return {
      betweenInfo("g2o", "EDGE_SE2", MatrixLayout::kG2oInformation,
                  "rigid-body constraint between poses a and b: a b dx dy dth + information, "
                  "upper triangle row-major (I11 I12 I13 I22 I23 I33)"),
      betweenInfo("toro", "EDGE2", MatrixLayout::kToroInformation,
                  "rigid-body constraint: a b dx dy dth + information in TORO order I11 I12 I22 "
                  "I33 I13 I23"),
      betweenInfo("gtsam", "EDGE2", MatrixLayout::kG2oCovariance,
                  "rigid-body constraint: a b dx dy dth + COVARIANCE c11 c12 c13 c22 c23 c33 "
                  "(w20000.txt)"),
      betweenInfo("gtsam", "ODOMETRY", MatrixLayout::kG2oCovariance,
                  "odometry between poses: a b dx dy dth + COVARIANCE c11 c12 c13 c22 c23 c33 "
                  "(victoria_park.txt)"),
  };
}

}  // namespace hamal
