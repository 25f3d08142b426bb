// marginalCovariance: the joint covariance of chosen variables from
// AprilSAM's R (core/marginals.h; thesis eq. 3.7, H = R^T R): with E the unit
// columns of the variables' scalar columns, Sigma = E^T H^-1 E = Y Y^T for
// Y^T = R^-T E, a forward substitution over the elimination-tree paths from
// the variables to the root only (residual_covariance.h's reach), the
// entries iSAM2's marginalCovariance and SLAM++'s marginals recover from the
// factor, not the whole inverse.
//
// The system is R's: H at the variables' linearisation points (which lag
// the estimate between batches), with every factor at the weight R holds it
// with and dormant factors out, as iSAM2's covariance is that of its Bayes
// tree.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "backends/aprilsam/elimination_order.h"
#include "backends/aprilsam/incremental_cholesky.h"
#include "backends/aprilsam/variable_table.h"
#include "core/key.h"

namespace hamal::aprilsam {

// R = `chol` of the variables `vars` in `order`, usable (not broken, not
// damped); `keys` are held by `vars` and distinct (checkMarginalKeys). A
// fixed variable's rows and columns are 0.
Eigen::MatrixXd marginalCovariance(const VariableTable& vars, const EliminationOrder& order,
                                   const IncrementalCholesky& chol, const std::vector<Key>& keys);

}  // namespace hamal::aprilsam
