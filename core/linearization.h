// Linearization: one factor's whitened, robustified first-order model at the
// current estimate (thesis eq. 3.3-3.5): r(x0 + dx) ~ r0 + sum_k J_k dx_k.
// Normal-equation back-ends (cholesky, aprilsam) build A^T A and A^T b from
// these blocks; they call the factor's own ceres::CostFunction, so they see
// exactly what Ceres sees.
//
// A robust loss is applied as Ceres applies it (ceres::Corrector, the
// Triggs correction), so all back-ends minimise the same objective.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/factor.h"

namespace hamal {

struct Linearization {
  Eigen::VectorXd residual;  // r0, corrected for the loss
  // J_k, residualDim x dim(key k), one per key of the factor, corrected too.
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> jacobians;
  double cost = 0;  // rho(|r0|^2) (= |r0|^2 without a loss)
};

// `parameters[k]` points at key k's values. Returns false when the cost
// function's Evaluate fails or returns non-finite numbers.
bool linearize(const Factor& factor, const double* const* parameters, Linearization* out);

}  // namespace hamal
