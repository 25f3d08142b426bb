// residualCovariance: G = J H^-1 J^T (core/factor_weights.h) from AprilSAM's
// R (thesis eq. 3.7, H = R^T R): Z = R^-T J^T by forward substitution over
// the elimination-tree paths from the factors' variables to the root (the
// rows an update of those factors would refactor), G = Z^T Z. What robust
// estimators such as graduated non-convexity read to anneal a few factors
// on the factorisation AprilSAM already has.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "backends/aprilsam/elimination_order.h"
#include "backends/aprilsam/incremental_cholesky.h"
#include "backends/aprilsam/variable_table.h"
#include "core/factor.h"

namespace hamal::aprilsam {

// R = `chol` of the variables `vars` in `order`, usable (the caller asks
// only when R is the undamped system). False for a factor on a variable
// `vars` does not hold (the factor itself need not be held); then `g` is
// untouched.
bool residualCovariance(const VariableTable& vars, const EliminationOrder& order,
                        const IncrementalCholesky& chol, const std::vector<const Factor*>& factors,
                        Eigen::MatrixXd* g);

// The forward substitution both covariances share: Y <- Y R_reach^-1, that
// is Z = R^-T Y^T for the rows of Y, on `reach` (ascending positions closed
// under the elimination tree's parent, as pathsToRoot returns it), position
// p's columns of Y starting at col_of[p].
void solveOnReach(const IncrementalCholesky& chol, const std::vector<int>& reach,
                  const std::vector<int>& col_of, Eigen::MatrixXd* y);
// The positions on the paths from `starts` to the root, ascending, and
// col_of (sized to R) giving each its first column in Y; the reach's
// scalar columns in all.
int pathsToRoot(const IncrementalCholesky& chol, const std::vector<int>& starts,
                std::vector<int>* reach, std::vector<int>* col_of);

}  // namespace hamal::aprilsam
