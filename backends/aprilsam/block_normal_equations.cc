// BlockNormalEquations: see block_normal_equations.h (thesis eq. 3.5-3.7).
#include "backends/aprilsam/block_normal_equations.h"

#include <algorithm>

namespace hamal::aprilsam {

void BlockNormalEquations::clear(int num_positions) {
  for (int pos : touched_) row_of_[pos] = -1;
  touched_.clear();
  used_rows_ = 0;
  values_.clear();
  if (static_cast<int>(row_of_.size()) < num_positions) row_of_.resize(num_positions, -1);
}

BlockNormalEquations::Row& BlockNormalEquations::rowFor(int pos, int dim) {
  if (pos >= static_cast<int>(row_of_.size())) row_of_.resize(pos + 1, -1);
  if (row_of_[pos] < 0) {
    if (used_rows_ == static_cast<int>(rows_.size())) rows_.emplace_back();
    Row& r = rows_[used_rows_];
    r.dim = dim;
    std::fill(r.b, r.b + kMaxDim, 0.0);
    r.blocks.clear();
    row_of_[pos] = used_rows_++;
    touched_.push_back(pos);
  }
  return rows_[row_of_[pos]];
}

void BlockNormalEquations::add(const Linearization& lin, const int* pos, const int* dims) {
  const int nk = static_cast<int>(lin.jacobians.size());
  const int m = static_cast<int>(lin.residual.size());
  for (int a = 0; a < nk; ++a) {
    const auto& ja = lin.jacobians[a];  // m x da, row-major
    const int da = dims[a];
    Row& ra = rowFor(pos[a], da);
    for (int i = 0; i < da; ++i) {
      double s = 0;
      for (int t = 0; t < m; ++t) s += ja(t, i) * lin.residual[t];
      ra.b[i] -= s;
    }
    for (int c = 0; c < nk; ++c) {
      // Keep only the upper triangle in position order. A factor's keys are
      // distinct variables, so pos[c] == pos[a] only for c == a.
      if (pos[c] < pos[a] || (pos[c] == pos[a] && c != a)) continue;
      const auto& jc = lin.jacobians[c];
      const int dc = dims[c];
      const int offset = static_cast<int>(values_.size());
      values_.resize(values_.size() + da * dc);
      double* out = values_.data() + offset;
      for (int j = 0; j < dc; ++j)
        for (int i = 0; i < da; ++i) {
          double s = 0;
          for (int t = 0; t < m; ++t) s += ja(t, i) * jc(t, j);
          out[i + j * da] = s;
        }
      rows_[row_of_[pos[a]]].blocks.push_back({pos[c], offset});
    }
  }
}

void BlockNormalEquations::damp(double lambda, double floor) {
  for (int pos : touched_) {
    Row& r = rows_[row_of_[pos]];
    const int d = r.dim;
    // Sum the diagonal of every (pos, pos) block first: damping scales the
    // diagonal of the assembled A_ii, not of each factor's share.
    double diag[kMaxDim] = {};
    int first = -1;
    for (const Block& b : r.blocks)
      if (b.col == pos) {
        if (first < 0) first = b.offset;
        for (int i = 0; i < d; ++i) diag[i] += values_[b.offset + i * (d + 1)];
      }
    if (first < 0) {
      first = static_cast<int>(values_.size());
      values_.resize(values_.size() + d * d, 0.0);
      r.blocks.push_back({pos, first});
    }
    for (int i = 0; i < d; ++i) values_[first + i * (d + 1)] += lambda * std::max(diag[i], floor);
  }
}

}  // namespace hamal::aprilsam
