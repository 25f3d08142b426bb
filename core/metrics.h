// Metrics: how an estimate is graded, computed outside the back-ends so that
// no back-end grades itself (docs/PROTOCOL.md, "chi2").
//
// chi2 = sum over factors of |whitened residual|^2, without the robust loss
// and without a factor 1/2 (thesis eq. 2.9). With the between factor's
// default (thesis) residual this is exactly docs/PROTOCOL.md's chi2.
#pragma once

#include <vector>

#include "core/factor.h"
#include "core/values.h"

namespace hamal {

// Factors whose variables are missing from `values` are an error (hamal::Error).
double chi2(const std::vector<FactorPtr>& factors, const Values& values);

// The objective a back-end minimises, for its own convergence checks (not a
// grade): each factor's chi2 through its robust loss, rho(chi2) in Ceres'
// convention, and the chi2 itself for a factor without one. A robust solve
// may raise chi2 while it lowers this: an outlier let go.
double robustChi2(const Factor& factor, const Values& values);
double robustCost(const std::vector<FactorPtr>& factors, const Values& values);

struct TrajectoryError {
  double translation_rmse = 0;  // metres
  double rotation_rmse = 0;     // radians
  std::size_t poses = 0;        // poses compared
};

// Absolute trajectory error over the poses both hold. With `align`, the
// estimate is first moved by the rigid transform that best fits it to the
// truth (2D Horn/Umeyama, no scale), the usual ATE.
TrajectoryError absoluteTrajectoryError(const Values& estimate, const Values& truth,
                                        bool align = true);

}  // namespace hamal
