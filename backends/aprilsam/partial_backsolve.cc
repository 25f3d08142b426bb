// PartialBacksolve: see partial_backsolve.h (thesis sec. 3.4.2, fig. 3.7).
#include "backends/aprilsam/partial_backsolve.h"

#include <algorithm>
#include <cmath>

#include "backends/aprilsam/dense_blocks.h"

namespace hamal::aprilsam {

void PartialBacksolve::reset(int n) {
  dx_.assign(n, {});
  known_.assign(n, 0);
  queued_.assign(n, 0);
  changed_.clear();
}

void PartialBacksolve::append() {
  dx_.push_back({});
  known_.push_back(0);
  queued_.push_back(0);
}

// Recomputes dx_p; true when it moved by more than tol (or is new).
bool PartialBacksolve::solveRow(const IncrementalCholesky& factor, int p, double tol) {
  ++rows_solved_;
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
  // Top-down over a max-heap of positions: a row is solved after every row
  // it references (those sit at larger positions).
  heap_.clear();
  for (int p : factor.affected()) {
    queued_[p] = 1;
    heap_.push_back(p);
  }
  std::make_heap(heap_.begin(), heap_.end());
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end());
    const int p = heap_.back();
    heap_.pop_back();
    queued_[p] = 0;
    if (!solveRow(factor, p, tol)) continue;
    for (int r : factor.rowsReferencing(p)) {
      if (queued_[r]) continue;
      queued_[r] = 1;
      heap_.push_back(r);
      std::push_heap(heap_.begin(), heap_.end());
    }
  }
}

}  // namespace hamal::aprilsam
