// NearMisses (backends/robust/near_misses.h): each rejected closure's test
// against the map, r^T (I + G)^-1 r / c2, and the false closures the
// rejected ones predict among the accepted, against hand-computed values,
// across the blocks the covariance is asked in.
#include "backends/robust/near_misses.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "core/error.h"
#include "core/key.h"
#include "factors/between_factor.h"

namespace hamal::robust {
namespace {

// Gives G = diag(g of each factor) (no correlation between factors), or
// refuses.
class FixedCovariance : public FactorWeights {
 public:
  std::map<const Factor*, double> g;
  bool gives = true;
  int asked = 0;
  void setFactorWeight(const Factor*, double) override {}
  std::map<const Factor*, double> weight;  // 1 where not set
  double factorWeight(const Factor* f) const override {
    const auto it = weight.find(f);
    return it == weight.end() ? 1 : it->second;
  }
  bool residualCovariance(const std::vector<const Factor*>& factors,
                          Eigen::MatrixXd* out) override {
    ++asked;
    if (!gives) return false;
    int rows = 0;
    for (const Factor* f : factors) rows += f->residualDim();
    *out = Eigen::MatrixXd::Zero(rows, rows);
    int o = 0;
    for (const Factor* f : factors) {
      const int d = f->residualDim();
      out->block(o, o, d, d).setIdentity();
      out->block(o, o, d, d) *= g.at(f);
      o += d;
    }
    return true;
  }
};

// A closure between x0 and x1 whose whitened residual at x0 = x1 = 0 is
// (dx, 0, 0) (unit information, so chi2 = dx^2).
std::shared_ptr<Factor> closure(double dx) {
  return std::make_shared<BetweenFactor>(X(0), X(1), Pose2(dx, 0, 0), Eigen::Matrix3d::Identity());
}

Values origin() {
  Values v;
  v.insert(X(0), Pose2(0, 0, 0));
  v.insert(X(1), Pose2(0, 0, 0));
  return v;
}

TEST(NearMisses, AClosuresWeightIsTheAcceptanceBallsShareOfItsOwn) {
  EXPECT_DOUBLE_EQ(nearMissWeight(4, 3), 1.0 / 8);
  EXPECT_DOUBLE_EQ(nearMissWeight(4, 2), 1.0 / 4);
  EXPECT_DOUBLE_EQ(nearMissWeight(100, 3), 1e-3);
  EXPECT_DOUBLE_EQ(nearMissWeight(1, 3), 1);    // on the edge
  EXPECT_DOUBLE_EQ(nearMissWeight(0.2, 3), 1);  // inside: a local minimum's
  EXPECT_DOUBLE_EQ(nearMissWeight(std::nan(""), 3), 1);
}

TEST(NearMisses, TheTestIsTheResidualAgainstTheMapsUncertaintyToo) {
  // chi2 = 36 against its own noise; the map's variance 2 makes S = 3, so
  // the test is 12, k = 12 / 3 = 4 at c2 = 3: weight 1/8.
  const auto f = closure(6);
  FixedCovariance w;
  w.g[f.get()] = 2;
  const std::optional<double> e = expectedFalseAcceptances(w, {f.get()}, {3}, origin());
  ASSERT_TRUE(e);
  EXPECT_NEAR(*e, 1.0 / 8, 1e-12);
  // A tight map (variance 0): k = 12, weight 12^-1.5.
  w.g[f.get()] = 0;
  EXPECT_NEAR(*expectedFalseAcceptances(w, {f.get()}, {3}, origin()), std::pow(12.0, -1.5), 1e-12);
}

TEST(NearMisses, TheSumRunsAcrossBlocks) {
  std::vector<std::shared_ptr<Factor>> keep;
  std::vector<const Factor*> rejected;
  std::vector<double> c2;
  FixedCovariance w;
  double expected = 0;
  for (std::size_t i = 0; i < 2 * kNearMissBlock + 5; ++i) {
    keep.push_back(closure(2 + 0.1 * static_cast<double>(i)));
    rejected.push_back(keep.back().get());
    c2.push_back(1);
    w.g[keep.back().get()] = 0.5 * static_cast<double>(i % 3);
    const double k = std::pow(2 + 0.1 * static_cast<double>(i), 2) / (1 + w.g[keep.back().get()]);
    expected += nearMissWeight(k, 3);
  }
  const std::optional<double> e = expectedFalseAcceptances(w, rejected, c2, origin());
  ASSERT_TRUE(e);
  EXPECT_NEAR(*e, expected, 1e-9);
  EXPECT_EQ(w.asked, 3);
}

TEST(NearMisses, NoCovarianceNoEstimate) {
  const auto f = closure(6);
  FixedCovariance w;
  w.gives = false;
  EXPECT_FALSE(expectedFalseAcceptances(w, {f.get()}, {3}, origin()));
  w.gives = true;
  w.g[f.get()] = 0;
  Values partial;
  partial.insert(X(0), Pose2(0, 0, 0));  // x1 missing: the factor does not evaluate
  EXPECT_FALSE(expectedFalseAcceptances(w, {f.get()}, {3}, partial));
  EXPECT_THROW(expectedFalseAcceptances(w, {f.get()}, {3, 4}, origin()), Error);
  EXPECT_DOUBLE_EQ(*expectedFalseAcceptances(w, {}, {}, origin()), 0);
}

TEST(NearMisses, AClosureHoldsADirectionAloneAboveTheBound) {
  const auto lone = closure(0), shared = closure(0), edge = closure(0);
  FixedCovariance w;
  w.g[lone.get()] = 0.9995;
  w.g[shared.get()] = 0.9;
  w.g[edge.get()] = kAloneLeverage;  // at the bound: not above it
  EXPECT_EQ(*closuresAlone(w, {lone.get(), shared.get(), edge.get()}), 1u);
  EXPECT_EQ(*closuresAlone(w, {}), 0u);
  // Not in H (weight 0): its G is a prediction, not a leverage.
  w.weight[lone.get()] = 0;
  EXPECT_EQ(*closuresAlone(w, {lone.get(), shared.get()}), 0u);
  w.weight.erase(lone.get());
  // Both halves of the evidence, and none without a covariance.
  const auto far = closure(60);  // k = 3600 / 1 / 3 at c2 = 3, no map variance
  w.g[far.get()] = 0;
  const std::optional<Refutation> r =
      refutation(w, {far.get()}, {3}, {lone.get(), shared.get()}, origin());
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->expected_false, std::pow(1200.0, -1.5), 1e-15);
  EXPECT_EQ(r->alone, 1u);
  w.gives = false;
  EXPECT_FALSE(refutation(w, {far.get()}, {3}, {lone.get()}, origin()));
}

}  // namespace
}  // namespace hamal::robust
