// BlockNormalEquations: see block_normal_equations.h (thesis eq. 3.5-3.7).
#include "backends/aprilsam/block_normal_equations.h"

#include <algorithm>

#include "backends/aprilsam/dense_blocks.h"

namespace hamal::aprilsam {

void BlockNormalEquations::clear(int num_positions) {
  for (int pos : touched_) row_of_[pos] = -1;
  touched_.clear();
  used_rows_ = 0;
  used_values_ = 0;
  if (static_cast<int>(row_of_.size()) < num_positions) row_of_.resize(num_positions, -1);
}

BlockNormalEquations::Row& BlockNormalEquations::newRow(int pos, int dim) {
  if (pos >= static_cast<int>(row_of_.size())) row_of_.resize(pos + 1, -1);
  if (used_rows_ == static_cast<int>(rows_.size())) rows_.emplace_back();
  Row& r = rows_[used_rows_];
  r.dim = dim;
  std::fill(r.b, r.b + kMaxDim, 0.0);
  r.blocks.clear();
  row_of_[pos] = used_rows_++;
  touched_.push_back(pos);
  return r;
}

namespace {
// out (da x dc, column-major) = ja^T jc for row-major m x da and m x dc
// Jacobians; fixed sizes for the common 2/3 sides so the loops unroll.
template <int M, int A, int C>
void jtjFixed(const double* ja, const double* jc, double* out) {
  for (int j = 0; j < C; ++j)
    for (int i = 0; i < A; ++i) {
      double s = 0;
      for (int t = 0; t < M; ++t) s += ja[t * A + i] * jc[t * C + j];
      out[i + j * A] = s;
    }
}
// A pose's block (A = 3): entries 0 and 1 of each column in the two lanes
// of a vector (dense_blocks.h), entry 2 alone; each lane does jtjFixed's
// operations in its order, so the results are the same bits. A batch
// forms three such blocks per factor.
template <int M, int C>
void jtjPose(const double* ja, const double* jc, double* out) {
  Lanes2 a01[M];
  for (int t = 0; t < M; ++t) a01[t] = loadLanes2(ja + t * 3);
  for (int j = 0; j < C; ++j) {
    Lanes2 s01 = {0, 0};
    double s2 = 0;
    for (int t = 0; t < M; ++t) {
      const double c = jc[t * C + j];
      s01 += a01[t] * c;
      s2 += ja[t * 3 + 2] * c;
    }
    storeLanes2(out + j * 3, s01);
    out[2 + j * 3] = s2;
  }
}
// b -= sign ja^T r for a pose (da = 3) and a residual of 3, ja row-major
// (3 x 3): the generic loop's sums, entries 0 and 1 in two lanes, the same
// bits. A batch takes it twice per factor.
void subJtrPose(const double* ja, const double* r, double sign, double* b) {
  Lanes2 s01 = {0, 0};
  double s2 = 0;
  for (int t = 0; t < 3; ++t) {
    s01 += loadLanes2(ja + t * 3) * r[t];
    s2 += ja[t * 3 + 2] * r[t];
  }
  storeLanes2(b, loadLanes2(b) - sign * s01);
  b[2] -= sign * s2;
}
template <int M, int A>
bool jtjC(const double* ja, const double* jc, double* out, int dc) {
  if constexpr (A == 3) {
    if (dc == 3) return jtjPose<M, 3>(ja, jc, out), true;
    if (dc == 2) return jtjPose<M, 2>(ja, jc, out), true;
    return false;
  }
  if (dc == 3) return jtjFixed<M, A, 3>(ja, jc, out), true;
  if (dc == 2) return jtjFixed<M, A, 2>(ja, jc, out), true;
  return false;
}
template <int M>
bool jtjA(const double* ja, const double* jc, double* out, int da, int dc) {
  if (da == 3) return jtjC<M, 3>(ja, jc, out, dc);
  if (da == 2) return jtjC<M, 2>(ja, jc, out, dc);
  return false;
}
void jtj(const double* ja, const double* jc, double* out, int m, int da, int dc) {
  if (m == 3 && jtjA<3>(ja, jc, out, da, dc)) return;
  if (m == 2 && jtjA<2>(ja, jc, out, da, dc)) return;
  for (int j = 0; j < dc; ++j)
    for (int i = 0; i < da; ++i) {
      double s = 0;
      for (int t = 0; t < m; ++t) s += ja[t * da + i] * jc[t * dc + j];
      out[i + j * da] = s;
    }
}
}  // namespace

void BlockNormalEquations::add(const Linearization& lin, const int* pos, const int* dims,
                               double sign) {
  const int nk = static_cast<int>(lin.jacobians.size());
  const int m = static_cast<int>(lin.residual.size());
  const double* r = lin.residual.data();
  for (int a = 0; a < nk; ++a) {
    const double* ja = lin.jacobians[a].data();  // m x da, row-major
    const int da = dims[a];
    Row& ra = rowFor(pos[a], da);
    if (m == 3 && da == 3) {
      subJtrPose(ja, r, sign, ra.b);
    } else {
      for (int i = 0; i < da; ++i) {
        double s = 0;
        for (int t = 0; t < m; ++t) s += ja[t * da + i] * r[t];
        ra.b[i] -= sign * s;
      }
    }
    for (int c = 0; c < nk; ++c) {
      // Keep only the upper triangle in position order. A factor's keys are
      // distinct variables, so pos[c] == pos[a] only for c == a.
      if (pos[c] < pos[a] || (pos[c] == pos[a] && c != a)) continue;
      const int dc = dims[c];
      const int offset = newBlock(da * dc);
      jtj(ja, lin.jacobians[c].data(), values_.data() + offset, m, da, dc);
      if (sign != 1.0)
        for (int t = 0; t < da * dc; ++t) values_[offset + t] *= sign;
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
      first = newBlock(d * d);
      std::fill_n(values_.data() + first, d * d, 0.0);
      r.blocks.push_back({pos, first});
    }
    for (int i = 0; i < d; ++i) values_[first + i * (d + 1)] += lambda * std::max(diag[i], floor);
  }
}

}  // namespace hamal::aprilsam
