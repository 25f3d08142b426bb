// IncrementalCholesky: AprilSAM's factor R (R^T R = A) and right-hand side y
// (R^T y = b), kept between steps in a fixed elimination order and updated
// only where new information lands (thesis sec. 3.4.1-3.4.2, eq. 3.8-3.19,
// figs. 3.5-3.7).
//
// R is block-sparse, one block row per variable (its dimension: 3 for Pose2,
// 2 for Point2), stored by rows in elimination order. The first off-diagonal
// block of a row names its parent in the elimination tree. Adding A_new, b_new
// on a set S of variables changes only the rows of aff = S and all of its
// elimination-tree ancestors: the other rows form a descendant-closed set,
// eliminating them first is a valid order, and what remains is eq. 3.14 with
// the trailing block replaced by the ancestor set (what figs. 3.5 and 3.6
// draw):
//     R~_aff^T R~_aff = R_aff^T R_aff + A_new              (eq. 3.14)
//     R~_aff^T y~_aff = R_aff^T y_aff + b_new              (eq. 3.19)
//
// This class is the face the rest of AprilSAM uses; each algorithm is its
// own file: R, y and their bookkeeping (cholesky_factor.h, its rows in
// factor_row_store.h), eq. 3.14 by a left-looking refactorisation of the
// affected rows, which is also the batch (left_looking_factorization.h), the
// same R~ by Householder reflections of the new factors' Jacobian rows
// (householder_rank_update.h, factor_update=rank), and the re-elimination
// of the top in a new order (top_reordering.h, reeliminate=top).
#pragma once

#include <cstddef>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/cholesky_factor.h"
#include "backends/aprilsam/factor_row_store.h"
#include "backends/aprilsam/householder_rank_update.h"
#include "backends/aprilsam/jacobian_rows.h"
#include "backends/aprilsam/left_looking_factorization.h"
#include "backends/aprilsam/top_reordering.h"

namespace hamal::aprilsam {

class IncrementalCholesky {
 public:
  // One block row of R (factor_row_store.h).
  using Row = FactorRow;
  using Outcome = FactorUpdateOutcome;

  // Empties R and y and sets the dimensions of positions 0..n-1 (a batch).
  void reset(const std::vector<int>& dims);
  // A new variable at the end of the order (appended between batches, as the
  // reference implementation does): an empty row, y = 0.
  void append(int dim);

  // Applies eq. 3.14 and 3.19 for the system `a_new` (positions must exist).
  // With `all`, every position is refactored (a batch after reset()). On a
  // failure (a diagonal block that is not positive definite) R and y are
  // left exactly as they were.
  Outcome update(const BlockNormalEquations& a_new, bool all);
  // The same update for A_new = W^T W, b_new = W^T e given as the rows of W
  // and e (householder_rank_update.h). flops is update()'s estimate for the
  // same rows (the thesis' cost model, so both paths lead to the same batch
  // decisions). On a failure R and y are left as they were.
  Outcome addRows(const JacobianRows& w) { return rank_.addRows(r_, aff_, w); }
  // The flops addRows(w) would report, from the structure alone (the
  // symbolic part of the update, no arithmetic, R untouched): what the
  // update policy needs to decide on a batch before paying for the update.
  double addRowsFlops(const JacobianRows& w) { return rank_.predictedFlops(r_, w); }

  // The rows an iSAM2-style re-elimination of the top must redo: those of
  // the positions in `path` (the variables of factors added since the last
  // re-elimination: eq. 3.14's S), of every row that references a position
  // in `relin`, and all their elimination-tree ancestors (top_reordering.h).
  // Ascending, closed under parent().
  std::vector<int> topOf(const std::vector<int>& path, const std::vector<int>& relin) const {
    return topOfFactor(r_, path, relin);
  }
  // Re-eliminates the rows `top` (as topOf returns them) in a new order, as
  // iSAM2 re-eliminates the top of its Bayes tree: the other rows keep their
  // numbers and their relative order and come first, then top's positions in
  // the order `order` (a permutation of top). `h` holds the factors' share
  // on the top variables at their new positions (top.size() positions from
  // size() - top.size() on): the whole J^T J of a factor on top variables
  // only, and the top blocks of one that also reaches a kept row, linearised
  // where that row was made. The kept rows' share, R_NT^T R_NT, is
  // subtracted as the top is factored (top_reordering.h).
  // new_pos[p] is the new position of old position p; affected() is the
  // top's new positions. On a failure (not positive definite at old
  // position failed_position) R is left renumbered without the top's rows:
  // the caller must start again with reset() (a batch).
  Outcome reorderTop(const std::vector<int>& top, const std::vector<int>& order,
                     const BlockNormalEquations& h, std::vector<int>* new_pos);

  // The rows the last successful update refactored, in increasing position.
  const std::vector<int>& affected() const { return aff_.positions; }

  int size() const { return r_.size(); }
  int dim(int p) const { return r_.dim(p); }
  Row row(int p) const { return r_.row(p); }
  // The same row as raw pointers, for the back-substitution's inner loop,
  // where building row()'s view cost a fifth of the loop: ncols blocks,
  // their columns at ints[0..ncols), offsets at ints[ncols..2 ncols).
  int rowBlocks(int p) const { return r_.ref(p).ncols; }
  const int* rowInts(int p) const { return r_.store().ints.data() + r_.ref(p).ints; }
  const double* rowValues(int p) const { return r_.store().vals.data() + r_.ref(p).vals; }
  int parent(int p) const { return r_.parent(p); }
  const double* y(int p) const { return r_.y(p); }
  // Calls f(r) for every row r whose structure references column q (each
  // once, in no particular order), for the partial back-substitution.
  // Structures only grow between resets, so no entry goes stale.
  template <class F>
  void forEachRowReferencing(int q, F&& f) const {
    r_.forEachRowReferencing(q, f);
  }

  // The numbers R holds, and the capacity of the pooled array that holds
  // them (with the rows an update replaced and compaction has not yet
  // dropped): the memory check of the scale study.
  std::size_t storedValues() const { return r_.storedValues(); }
  std::size_t valueCapacity() const { return r_.valueCapacity(); }

  long columnsTotal() const { return r_.columnsTotal(); }
  // Estimated flops of factoring all of R from scratch (choleskyFlops of every
  // scalar column count), kept up to date row by row.
  double totalFlops() const { return r_.totalFlops(); }

 private:
  CholeskyFactor r_;
  AffectedRows aff_;
  LeftLookingFactorization refactor_;
  HouseholderRankUpdate rank_;
};

}  // namespace hamal::aprilsam
