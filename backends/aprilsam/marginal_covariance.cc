// marginalCovariance: see marginal_covariance.h (thesis eq. 3.7).
#include "backends/aprilsam/marginal_covariance.h"

#include "backends/aprilsam/residual_covariance.h"

namespace hamal::aprilsam {

Eigen::MatrixXd marginalCovariance(const VariableTable& vars, const EliminationOrder& order,
                                   const IncrementalCholesky& chol, const std::vector<Key>& keys) {
  // Where each variable's block lands in the result, and its position in R
  // (-1: fixed, no column).
  std::vector<int> starts, places;
  int size = 0, m = 0;
  for (Key key : keys) {
    const int v = vars.at(key);
    starts.push_back(order.posOf(v));
    places.push_back(size);
    size += vars.dim(v);
    if (order.posOf(v) >= 0) m += vars.dim(v);
  }
  std::vector<int> reach, col_of;
  const int n = pathsToRoot(chol, starts, &reach, &col_of);
  // Y = E^T over the reach's columns, one row per asked scalar column.
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(m, n);
  std::vector<int> row_place;  // row of Y -> its row in the result
  for (std::size_t k = 0; k < keys.size(); ++k) {
    if (starts[k] < 0) continue;
    for (int t = 0; t < chol.dim(starts[k]); ++t) {
      y(static_cast<int>(row_place.size()), col_of[starts[k]] + t) = 1;
      row_place.push_back(places[k] + t);
    }
  }
  solveOnReach(chol, reach, col_of, &y);
  Eigen::MatrixXd inner = Eigen::MatrixXd::Zero(m, m);
  inner.selfadjointView<Eigen::Lower>().rankUpdate(y);
  inner = inner.selfadjointView<Eigen::Lower>();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(size, size);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) out(row_place[i], row_place[j]) = inner(i, j);
  return out;
}

}  // namespace hamal::aprilsam
