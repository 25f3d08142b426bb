// CauchyBetweenFactor: see cauchy_between_factor.h.
#include "cauchy_between_factor.h"

#include <ceres/loss_function.h>

#include <memory>
#include <ostream>

#include "core/error.h"
#include "core/information.h"
#include "core/line_tokens.h"
#include "factors/full_precision.h"

namespace hamal::example {

namespace {

std::shared_ptr<ceres::LossFunction> cauchyLoss(double scale) {
  if (!(scale > 0.0))
    throw Error("EDGE_SE2_CAUCHY: the Cauchy scale must be positive, got " + std::to_string(scale));
  return std::make_shared<ceres::CauchyLoss>(scale);
}

FactorPtr parseCauchyBetween(LineTokens& t) {
  const std::uint64_t a = t.keyIndex("pose a"), b = t.keyIndex("pose b");
  const double dx = t.number("dx"), dy = t.number("dy"), dth = t.angle("dth");
  const Eigen::Matrix3d information = readInformation3(t, MatrixLayout::kG2oInformation);
  const double scale = t.number("scale");
  t.expectEnd();
  if (!(scale > 0.0)) t.fail("scale " + std::to_string(scale) + " must be positive");
  return std::make_shared<CauchyBetweenFactor>(X(a), X(b), Pose2(dx, dy, dth), information, scale);
}

}  // namespace

CauchyBetweenFactor::CauchyBetweenFactor(Key a, Key b, const Pose2& measurement,
                                         const Eigen::Matrix3d& information, double scale)
    : BetweenFactor(a, b, measurement, information), scale_(scale) {
  setLoss(cauchyLoss(scale));
}

void CauchyBetweenFactor::writeFields(std::ostream& os) const {
  BetweenFactor::writeFields(os);
  FullPrecision full(os);  // the scale must round-trip like the other fields
  os << ' ' << scale_;
}

FactorInfo cauchyBetweenFactorInfo() {
  return {"g2o", "EDGE_SE2_CAUCHY",
          "rigid-body constraint with a Cauchy loss (example plugin): a b dx dy dth + information "
          "I11 I12 I13 I22 I23 I33 + Cauchy scale",
          &parseCauchyBetween};
}

}  // namespace hamal::example
