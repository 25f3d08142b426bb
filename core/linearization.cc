// Linearization: see linearization.h.
#include "core/linearization.h"

#include <algorithm>
#include <cmath>

namespace hamal {

bool linearize(const Factor& factor, const double* const* parameters, Linearization* out) {
  const ceres::CostFunction& cost = *factor.costFunction();
  const int m = cost.num_residuals();
  const auto& sizes = cost.parameter_block_sizes();
  out->residual.resize(m);
  out->jacobians.resize(sizes.size());
  std::vector<double*> jac(sizes.size());
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    out->jacobians[k].resize(m, sizes[k]);
    jac[k] = out->jacobians[k].data();
  }
  if (!cost.Evaluate(parameters, out->residual.data(), jac.data())) return false;
  if (!out->residual.allFinite()) return false;
  for (const auto& j : out->jacobians)
    if (!j.allFinite()) return false;
  const double sq = out->residual.squaredNorm();
  if (!std::isfinite(sq)) return false;  // each residual finite, their square not
  out->cost = sq;
  if (const ceres::LossFunction* loss = factor.lossFunction()) {
    // The Triggs correction, as ceres::internal::Corrector applies it: the
    // corrected system's Gauss-Newton step equals the robust problem's.
    double rho[3];
    loss->Evaluate(sq, rho);
    out->cost = rho[0];
    const double sqrt_rho1 = std::sqrt(std::max(rho[1], 0.0));
    double scaling = sqrt_rho1, alpha_sq_norm = 0.0;
    if (sq > 0.0 && rho[2] > 0.0 && rho[1] > 0.0) {
      const double d = 1.0 + 2.0 * sq * rho[2] / rho[1];
      const double alpha = 1.0 - std::sqrt(d);
      scaling = sqrt_rho1 / (1.0 - alpha);
      alpha_sq_norm = alpha / sq;
    }
    for (auto& j : out->jacobians) {
      if (alpha_sq_norm != 0.0) {
        const Eigen::RowVectorXd rtj = out->residual.transpose() * j;
        j -= alpha_sq_norm * out->residual * rtj;
      }
      j *= sqrt_rho1;
    }
    out->residual *= scaling;
  }
  return true;
}

}  // namespace hamal
