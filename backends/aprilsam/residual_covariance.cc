// residualCovariance: see residual_covariance.h (thesis eq. 3.7).
#include "backends/aprilsam/residual_covariance.h"

#include <algorithm>

#include "core/linearization.h"

namespace hamal::aprilsam {

bool residualCovariance(const VariableTable& vars, const EliminationOrder& order,
                        const IncrementalCholesky& chol, const std::vector<const Factor*>& factors,
                        Eigen::MatrixXd* g) {
  if (factors.empty()) {
    g->resize(0, 0);
    return true;
  }
  int m = 0;
  for (const Factor* factor : factors) {
    for (const Key& key : factor->keys())
      if (vars.find(key) < 0) return false;
    m += factor->residualDim();
  }
  // The reach: every position on the paths to the root, ascending, each
  // with its columns in Y = Z^T (m x the reach's dimensions), so that
  // G = Y Y^T is one product over the whole reach, not one per position.
  std::vector<int> starts;
  for (const Factor* factor : factors)
    for (const Key& key : factor->keys()) starts.push_back(order.posOf(vars.at(key)));
  std::vector<int> reach, col_of;
  const int n = pathsToRoot(chol, starts, &reach, &col_of);
  // J^T into the columns of the factors' variables. A factor need not be
  // held: its variables must be, and it is linearised at their
  // linearisation points.
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(m, n);
  Linearization lin;
  std::vector<const double*> params;
  int row = 0;
  for (const Factor* factor : factors) {
    params.clear();
    for (const Key& key : factor->keys()) params.push_back(vars.lin(vars.at(key)).data.data());
    if (!linearize(*factor, params.data(), &lin)) return false;
    const int rows = factor->residualDim();
    for (std::size_t k = 0; k < factor->keys().size(); ++k) {
      const int v = vars.at(factor->keys()[k]);
      const int p = order.posOf(v);
      if (p < 0) continue;
      y.block(row, col_of[p], rows, vars.dim(v)) += lin.jacobians[k];
    }
    row += rows;
  }
  solveOnReach(chol, reach, col_of, &y);
  g->setZero(m, m);
  g->selfadjointView<Eigen::Lower>().rankUpdate(y);
  *g = g->selfadjointView<Eigen::Lower>();
  return true;
}

int pathsToRoot(const IncrementalCholesky& chol, const std::vector<int>& starts,
                std::vector<int>* reach, std::vector<int>* col_of) {
  reach->clear();
  col_of->assign(chol.size(), -1);
  for (int start : starts)
    for (int p = start; p >= 0 && (*col_of)[p] < 0; p = chol.parent(p)) {
      (*col_of)[p] = 0;
      reach->push_back(p);
    }
  std::sort(reach->begin(), reach->end());
  int n = 0;
  for (int p : *reach) {
    (*col_of)[p] = n;
    n += chol.dim(p);
  }
  return n;
}

void solveOnReach(const IncrementalCholesky& chol, const std::vector<int>& reach,
                  const std::vector<int>& col_of, Eigen::MatrixXd* y) {
  // Forward substitution R^T Z = J^T, transposed: Y_p <- Y_p R_pp^-1, then
  // Y_c -= Y_p R_pc for the ancestors c that row p references.
  for (int p : reach) {
    const int d = chol.dim(p);
    const int nc = chol.rowBlocks(p);
    const int* cols = chol.rowInts(p);
    const int* offs = cols + nc;
    const double* vals = chol.rowValues(p);
    auto yp = y->middleCols(col_of[p], d);
    Eigen::Map<const Eigen::MatrixXd>(vals + offs[0], d, d)
        .triangularView<Eigen::Upper>()
        .solveInPlace<Eigen::OnTheRight>(yp);
    for (int k = 1; k < nc; ++k) {
      const int c = cols[k];
      const int dc = chol.dim(c);
      if (d == 3 && dc == 3) {  // pose to pose: fixed sizes, vectorised down Y's m rows
        y->middleCols<3>(col_of[c]).noalias() -=
            y->middleCols<3>(col_of[p]) * Eigen::Map<const Eigen::Matrix3d>(vals + offs[k]);
      } else {
        y->middleCols(col_of[c], dc).noalias() -=
            yp.lazyProduct(Eigen::Map<const Eigen::MatrixXd>(vals + offs[k], d, dc));
      }
    }
  }
}

}  // namespace hamal::aprilsam
