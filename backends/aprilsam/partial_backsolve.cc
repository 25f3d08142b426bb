// PartialBacksolve: see partial_backsolve.h (thesis sec. 3.4.2, fig. 3.7).
#include "backends/aprilsam/partial_backsolve.h"

#include <algorithm>
#include <cmath>

#include "backends/aprilsam/dense_blocks.h"

namespace hamal::aprilsam {

namespace {
int words(int n) { return (n + 63) / 64; }
}  // namespace

void PartialBacksolve::reset(int n) {
  dx_.assign(n, {});
  known_.assign(n, 0);
  queued_.assign(words(n), 0);
  changed_.clear();
}

void PartialBacksolve::append() {
  dx_.push_back({});
  known_.push_back(0);
  queued_.resize(words(static_cast<int>(dx_.size())), 0);
}

void PartialBacksolve::permute(const std::vector<int>& new_pos) {
  std::vector<std::array<double, kMaxDim>> dx(dx_.size());
  std::vector<char> known(known_.size());
  for (std::size_t p = 0; p < new_pos.size(); ++p) {
    dx[new_pos[p]] = dx_[p];
    known[new_pos[p]] = known_[p];
  }
  dx_.swap(dx);
  known_.swap(known);
}

// Recomputes dx_p; true when it moved by more than tol (or is new). The row's
// dimension D is fixed so the small loops unroll; the arithmetic (and so the
// rounding) is the generic loop's, operation for operation.
template <int D>
inline bool PartialBacksolve::solveRowFixed(const IncrementalCholesky& factor, int p, double tol) {
  double s[D];
  const double* y = factor.y(p);
  for (int t = 0; t < D; ++t) s[t] = y[t];
  const int nc = factor.rowBlocks(p);
  const int* cols = factor.rowInts(p);
  const int* offs = cols + nc;
  const double* vals = factor.rowValues(p);
  if constexpr (D == 3) {
    // A pose's row: s[0] and s[1] in two vector lanes (subAxPose), the same
    // bits as subAxFixed's.
    Lanes2 s01 = {s[0], s[1]};
    double s2 = s[2];
    for (int k = 1; k < nc; ++k) {
      const int q = cols[k];
      subAxPose(s01, s2, vals + offs[k], dx_[q].data(), factor.dim(q));
    }
    s[0] = s01[0];
    s[1] = s01[1];
    s[2] = s2;
  } else {
    for (int k = 1; k < nc; ++k) {
      const int q = cols[k];
      const double* r = vals + offs[k];
      const double* x = dx_[q].data();
      const int dq = factor.dim(q);
      if (dq == 3)
        detail::subAxFixed<D, 3>(s, r, x);
      else if (dq == 2)
        detail::subAxFixed<D, 2>(s, r, x);
      else
        subAx(s, r, x, D, dq);
    }
  }
  solveUx(vals, s, D);
  double* dx = dx_[p].data();
  double diff = 0;
  bool differs = !known_[p];
  for (int t = 0; t < D; ++t) {
    const double delta = std::fabs(s[t] - dx[t]);
    if (s[t] != dx[t]) differs = true;
    diff = std::max(diff, delta);
    dx[t] = s[t];
  }
  if (differs) changed_.push_back(p);
  const bool fresh = !known_[p];
  known_[p] = 1;
  return fresh || (tol > 0 ? diff > tol : differs);
}

// The dimension dispatch stays inline in the solve loops (a call per row
// costs as much as the row's products); other dimensions come here.
inline bool PartialBacksolve::solveRow(const IncrementalCholesky& factor, int p, double tol) {
  ++rows_solved_;
  const int d = factor.dim(p);
  if (d == 3) return solveRowFixed<3>(factor, p, tol);
  if (d == 2) return solveRowFixed<2>(factor, p, tol);
  return solveRowGeneric(factor, p, tol);
}

bool PartialBacksolve::solveRowGeneric(const IncrementalCholesky& factor, int p, double tol) {
  const int d = factor.dim(p);
  const auto& row = factor.row(p);
  double s[kMaxDim];
  const double* y = factor.y(p);
  for (int t = 0; t < d; ++t) s[t] = y[t];
  for (std::size_t k = 1; k < row.cols.size(); ++k) {
    const int q = row.cols[k];
    subAx(s, row.vals.data() + row.offs[k], dx_[q].data(), d, factor.dim(q));
  }
  solveUx(row.vals.data(), s, d);
  double diff = 0;
  bool differs = !known_[p];
  for (int t = 0; t < d; ++t) {
    const double delta = std::fabs(s[t] - dx_[p][t]);
    if (s[t] != dx_[p][t]) differs = true;
    diff = std::max(diff, delta);
    dx_[p][t] = s[t];
  }
  if (differs) changed_.push_back(p);
  const bool fresh = !known_[p];
  known_[p] = 1;
  return fresh || (tol > 0 ? diff > tol : differs);
}

void PartialBacksolve::solve(const IncrementalCholesky& factor, bool full, double tol) {
  changed_.clear();
  if (full) {
    for (int p = factor.size() - 1; p >= 0; --p) solveRow(factor, p, tol);
    return;
  }
  // Top-down: a row is solved after every row it references (those sit at
  // larger positions), so the highest queued position goes first.
  const std::vector<int>& aff = factor.affected();
  if (aff.empty()) return;
  // `waiting` counts the queued rows, so the scan stops at the last one
  // instead of walking the bitset down to position 0 at every step.
  long waiting = 0;
  auto enqueue = [&](int r) {
    std::uint64_t& word = queued_[r >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (r & 63);
    waiting += (word & bit) == 0;
    word |= bit;
  };
  for (int p : aff) enqueue(p);
  for (int w = aff.back() >> 6; waiting > 0;) {
    const std::uint64_t word = queued_[w];
    if (word == 0) {
      --w;
      continue;
    }
    const int b = 63 - __builtin_clzll(word);
    queued_[w] = word & ~(std::uint64_t{1} << b);
    --waiting;
    const int p = w * 64 + b;
    if (!solveRow(factor, p, tol)) continue;
    factor.forEachRowReferencing(p, enqueue);
  }
}

}  // namespace hamal::aprilsam
