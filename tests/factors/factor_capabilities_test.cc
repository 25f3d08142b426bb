// The capabilities a factor kind opts into besides Factor (core/factor.h):
// which of the built-in kinds has which, and what a caller is told about a
// factor without one (no prediction, no relative pose, NaN log-determinant,
// no modes), so that a back-end or initialiser never needs a factor's class.
#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "core/key.h"
#include "core/mixture_component.h"
#include "core/multi_modal.h"
#include "core/relative_pose_measurement.h"
#include "core/variable_prediction.h"
#include "factors/between_factor.h"
#include "factors/l2g_factor.h"
#include "factors/landmark_prior_factor.h"
#include "factors/max_mixture_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/position_factor.h"
#include "factors/prior_factor.h"
#include "factors/range_bearing_factor.h"

namespace hamal {
namespace {

// What a factor says it can do, one letter per capability: P(redicts),
// R(elative pose), M(odes), C(omponent of a mixture), '-' when it cannot.
std::string capabilities(const Factor& f) {
  std::string s;
  s += dynamic_cast<const VariablePrediction*>(&f) ? 'P' : '-';
  s += asRelativePoseMeasurement(f) ? 'R' : '-';
  s += asMultiModal(f) ? 'M' : '-';
  s += dynamic_cast<const MixtureComponent*>(&f) ? 'C' : '-';
  return s;
}

// r = b - a, a factor kind that opts into nothing.
class DifferenceCost : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  bool Evaluate(double const* const* p, double* r, double** jacobians) const override {
    for (int i = 0; i < 3; ++i) r[i] = p[1][i] - p[0][i];
    if (jacobians)
      for (int k = 0; k < 2; ++k)
        if (jacobians[k])
          for (int i = 0; i < 9; ++i) jacobians[k][i] = (i % 4 == 0) ? (k == 0 ? -1.0 : 1.0) : 0.0;
    return true;
  }
};

class PlainFactor : public Factor {
 public:
  PlainFactor() : Factor({X(0), X(1)}, std::make_unique<DifferenceCost>()) {}
  std::string tag() const override { return "PLAIN"; }
  void writeFields(std::ostream&) const override {}
};

TEST(FactorCapabilities, EachBuiltInKindOptsIntoWhatItCanDo) {
  const Eigen::Matrix3d i3 = Eigen::Matrix3d::Identity();
  const Eigen::Matrix2d i2 = Eigen::Matrix2d::Identity();
  const auto between = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), i3);
  EXPECT_EQ(capabilities(*between), "PR-C");
  EXPECT_EQ(capabilities(PriorFactor(X(0), Pose2(), i3)), "P--C");
  EXPECT_EQ(capabilities(PositionFactor(X(0), Point2(1, 2), i2)), "P--C");
  EXPECT_EQ(capabilities(LandmarkPriorFactor(L(0), Point2(1, 2), i2)), "P--C");
  EXPECT_EQ(capabilities(PosePointFactor(X(0), L(0), Point2(1, 2), i2)), "P--C");
  EXPECT_EQ(capabilities(RangeBearingFactor(X(0), L(0), 2.0, 0.5, i2)), "P--C");
  EXPECT_EQ(capabilities(L2GFactor(X(0), 3, Pose2(), Pose2(1, 0, 0), i3)), "P--C");
  // A max-mixture has modes and predicts as its nominal, but measures no
  // single relative pose (LAGO must not read it as an edge) and is never a
  // component itself.
  EXPECT_EQ(capabilities(*MaxMixtureFactor::withNullHypothesis(between, 0.1, 1e-6)), "P-M-");
  EXPECT_EQ(capabilities(PlainFactor()), "----");
}

TEST(FactorCapabilities, AFactorWithoutOneIsToldSoWithoutItsClass) {
  const PlainFactor plain;
  Values known;
  known.insert(X(0), Pose2(1, 2, 0.3));
  Values::Entry guess;
  EXPECT_FALSE(predictVariable(plain, X(1), known, &guess));
  EXPECT_FALSE(relativePoseOf(plain).has_value());
  EXPECT_TRUE(std::isnan(logDetInformationOf(plain)));

  Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  info(2, 2) = 4;
  const BetweenFactor between(X(0), X(1), Pose2(1, 0, 0.5), info);
  ASSERT_TRUE(predictVariable(between, X(1), known, &guess));
  EXPECT_NEAR(guess.data[0], 1 + std::cos(0.3), 1e-12);
  const auto rel = relativePoseOf(between);
  ASSERT_TRUE(rel.has_value());
  EXPECT_EQ(rel->from, X(0));
  EXPECT_EQ(rel->to, X(1));
  EXPECT_NEAR(logDetInformationOf(between), std::log(4.0), 1e-12);
}

}  // namespace
}  // namespace hamal
