// residualCovariance: see residual_covariance.h (thesis eq. 3.7).
#include "backends/aprilsam/residual_covariance.h"

#include <algorithm>
#include <unordered_map>

#include "backends/aprilsam/dense_blocks.h"
#include "core/linearization.h"

namespace hamal::aprilsam {

bool residualCovariance(const LinearizedGraph& graph, const std::vector<const Factor*>& factors,
                        Eigen::MatrixXd* g) {
  if (graph.broken || graph.damped) return false;
  if (factors.empty()) {
    g->resize(0, 0);
    return true;
  }
  // Rows of J^T per position: B[p] is dim(p) x m, column-major. A factor
  // need not be held: its variables must be, and it is linearised at their
  // linearisation points.
  int m = 0;
  for (const Factor* factor : factors) {
    for (const Key& key : factor->keys())
      if (!graph.index.count(key)) return false;
    m += factor->residualDim();
  }
  std::unordered_map<int, std::vector<double>> b;
  Linearization lin;
  std::vector<const double*> params;
  int row = 0;
  for (const Factor* factor : factors) {
    params.clear();
    for (const Key& key : factor->keys())
      params.push_back(graph.lin[graph.index.at(key)].data.data());
    if (!linearize(*factor, params.data(), &lin)) return false;
    const int rows = factor->residualDim();
    for (std::size_t k = 0; k < factor->keys().size(); ++k) {
      const int v = graph.index.at(factor->keys()[k]);
      const int p = graph.pos_of[v];
      if (p < 0) continue;
      const int d = graph.dims[v];
      std::vector<double>& bp = b[p];
      if (bp.empty()) bp.assign(static_cast<std::size_t>(d) * m, 0.0);
      for (int r = 0; r < rows; ++r)
        for (int t = 0; t < d; ++t)
          bp[t + static_cast<std::size_t>(row + r) * d] += lin.jacobians[k](r, t);
    }
    row += rows;
  }
  // The reach: every position on the paths to the root, ascending.
  std::vector<int> reach;
  std::vector<char> seen(graph.chol.size(), 0);
  for (const auto& entry : b)
    for (int p = entry.first; p >= 0 && !seen[p]; p = graph.chol.parent(p)) {
      seen[p] = 1;
      reach.push_back(p);
    }
  std::sort(reach.begin(), reach.end());
  g->setZero(m, m);
  for (int p : reach) {
    const int d = graph.chol.dim(p);
    std::vector<double>& z = b[p];
    if (z.empty()) z.assign(static_cast<std::size_t>(d) * m, 0.0);
    const int nc = graph.chol.rowBlocks(p);
    const int* cols = graph.chol.rowInts(p);
    const int* offs = cols + nc;
    const double* vals = graph.chol.rowValues(p);
    solveUtX(vals + offs[0], z.data(), d, m);
    const Eigen::Map<const Eigen::MatrixXd> zp(z.data(), d, m);
    g->noalias() += zp.transpose() * zp;
    for (int k = 1; k < nc; ++k) {
      const int c = cols[k];
      const int dc = graph.chol.dim(c);
      std::vector<double>& bc = b[c];
      if (bc.empty()) bc.assign(static_cast<std::size_t>(dc) * m, 0.0);
      const Eigen::Map<const Eigen::MatrixXd> rpc(vals + offs[k], d, dc);
      Eigen::Map<Eigen::MatrixXd>(bc.data(), dc, m).noalias() -= rpc.transpose() * zp;
    }
    z.clear();
    z.shrink_to_fit();
  }
  return true;
}

}  // namespace hamal::aprilsam
