// PartialBacksolve: dx from R dx = y, recomputing only what an incremental
// update can have changed (thesis sec. 3.4.2, fig. 3.7).
//
// Back-substitution runs from the root of the elimination tree down: dx_p
// depends on y_p, row p of R and the dx_q its row references. After an
// update, rows outside the refactored set keep R and y, so dx_p needs
// recomputing only when p was refactored or when some dx_q of its row
// changed. "Changed" means by more than `tol` (max-norm of the block); with
// tol = 0 every change counts and the result is bit for bit the full
// solve's. The full solve (AprilSAM-FullSolve, sec. 3.5.1) visits every row.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "backends/aprilsam/incremental_cholesky.h"

namespace hamal::aprilsam {

class PartialBacksolve {
 public:
  // Forgets every dx (after a reordering) and sizes for n positions.
  void reset(int n);
  // A new position at the end, with no dx yet.
  void append();
  // The order changed (IncrementalCholesky::reorderTop): position p's dx
  // moves to new_pos[p].
  void permute(const std::vector<int>& new_pos);

  // Solves for the rows `factor` refactored last (factor.affected()) and
  // whatever they change; with `full`, for every row.
  void solve(const IncrementalCholesky& factor, bool full, double tol);

  const double* dx(int p) const { return dx_[p].data(); }
  // Positions whose dx differs from before the last solve().
  const std::vector<int>& changed() const { return changed_; }
  long rowsSolved() const { return rows_solved_; }

 private:
  bool solveRow(const IncrementalCholesky& factor, int p, double tol);
  bool solveRowGeneric(const IncrementalCholesky& factor, int p, double tol);
  template <int D>
  bool solveRowFixed(const IncrementalCholesky& factor, int p, double tol);

  std::vector<std::array<double, kMaxDim>> dx_;
  std::vector<char> known_;  // dx_ holds a solved value
  // Rows waiting to be solved, one bit per position: every row queued while
  // row p is solved references p, so sits below it, and a scan from the top
  // word down pops them in the order a max-heap would, at a word per 64
  // positions instead of a heap operation per row.
  std::vector<std::uint64_t> queued_;
  std::vector<int> changed_;
  long rows_solved_ = 0;
};

}  // namespace hamal::aprilsam
