// JacobianRows: see jacobian_rows.h (thesis eq. 3.5-3.7).
#include "backends/aprilsam/jacobian_rows.h"

#include <algorithm>
#include <numeric>

namespace hamal::aprilsam {

void JacobianRows::clear() {
  groups_.clear();
  values_.clear();
  total_rows_ = 0;
}

void JacobianRows::add(const Linearization& lin, const int* pos, const int* dims) {
  const int nk = static_cast<int>(lin.jacobians.size());
  const int m = static_cast<int>(lin.residual.size());
  // The blocks in increasing position: the factorisation walks them so.
  order_.resize(nk);
  std::iota(order_.begin(), order_.end(), 0);
  std::sort(order_.begin(), order_.end(), [&](int a, int b) { return pos[a] < pos[b]; });
  Group g;
  g.rows = m;
  for (int k : order_) {
    g.cols.push_back(pos[k]);
    g.dims.push_back(dims[k]);
    g.width += dims[k];
  }
  g.offset = static_cast<int>(values_.size());
  values_.resize(values_.size() + static_cast<std::size_t>(m) * (g.width + 1));
  double* out = values_.data() + g.offset;
  int col = 0;
  for (int k : order_) {
    const double* j = lin.jacobians[k].data();  // m x dims[k], row-major
    for (int c = 0; c < dims[k]; ++c, ++col)
      for (int r = 0; r < m; ++r) out[r + col * m] = j[r * dims[k] + c];
  }
  for (int r = 0; r < m; ++r) out[r + col * m] = -lin.residual[r];
  total_rows_ += m;
  groups_.push_back(std::move(g));
}

}  // namespace hamal::aprilsam
