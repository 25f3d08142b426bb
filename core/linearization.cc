// Linearization: see linearization.h.
#include "core/linearization.h"

#include <algorithm>
#include <cmath>

namespace hamal {

namespace {
// Whether n numbers are all finite, in one pass with no branch per number:
// 0 x v is 0 for a finite v and NaN for an infinite or NaN one, and a sum
// with a NaN in it is NaN. Eigen's allFinite branches on every entry.
bool allFinite(const double* v, Eigen::Index n) {
  double zero = 0;
  for (Eigen::Index i = 0; i < n; ++i) zero += 0.0 * v[i];
  return zero == 0;
}
}  // namespace

bool linearize(const Factor& factor, const double* const* parameters, Linearization* out) {
  const ceres::CostFunction& cost = *factor.costFunction();
  const int m = cost.num_residuals();
  const auto& sizes = cost.parameter_block_sizes();
  out->residual.resize(m);
  out->jacobians.resize(sizes.size());
  // The Jacobians' pointers on the stack for the usual few keys: a batch
  // linearises every factor, and a heap array per factor cost it a tenth
  // of the factor's own evaluation.
  constexpr std::size_t kFewKeys = 8;
  double* few[kFewKeys];
  std::vector<double*> many(sizes.size() > kFewKeys ? sizes.size() : 0);
  double** jac = sizes.size() > kFewKeys ? many.data() : few;
  for (std::size_t k = 0; k < sizes.size(); ++k) {
    auto& j = out->jacobians[k];
    // Eigen's resize checks the product for overflow with a division even
    // when the shape is the one the block already has (the usual case).
    if (j.rows() != m || j.cols() != sizes[k]) j.resize(m, sizes[k]);
    jac[k] = j.data();
  }
  if (!cost.Evaluate(parameters, out->residual.data(), jac)) return false;
  if (!allFinite(out->residual.data(), m)) return false;
  for (const auto& j : out->jacobians)
    if (!allFinite(j.data(), j.size())) return false;
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
