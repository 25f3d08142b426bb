// DynamicCovarianceScaling: the closed-form switchable constraint of
// Agarwal, Tipaldi, Spinello, Stachniss, Burgard, "Robust Map Optimization
// using Dynamic Covariance Scaling", ICRA 2013, as a Ceres loss on a factor's
// chi2 term s = |r|^2.
//
// DCS scales a loop closure's information by s_ij^2 with
//   s_ij = min(1, 2 Phi / (Phi + s)),
// the optimal switch variable of Suenderhauf's switchable constraints in
// closed form. As a loss, that is the rho whose derivative is that weight,
//   rho(s) = s                           for s <= Phi,
//   rho(s) = 3 Phi - 4 Phi^2 / (Phi + s) for s >  Phi,
// rho'(s) = s_ij^2, rho''(s) = -8 Phi^2 / (Phi + s)^3 beyond Phi: a redescending
// loss bounded by 3 Phi, so a factor far off the estimate pulls less and less.
// Every hamal back-end applies it as Ceres does (core/linearization.h).
// Phi = 1 is the paper's default.
#pragma once

#include <ceres/loss_function.h>

namespace hamal::robust {

class DynamicCovarianceScaling : public ceres::LossFunction {
 public:
  // Throws hamal::Error unless phi is finite and > 0.
  explicit DynamicCovarianceScaling(double phi);
  void Evaluate(double s, double rho[3]) const override;
  double phi() const { return phi_; }
  // s_ij^2 at chi2 term s: the factor's weight.
  double weight(double s) const;

 private:
  double phi_;
};

}  // namespace hamal::robust
