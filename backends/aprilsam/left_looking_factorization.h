// LeftLookingFactorization: eq. 3.14 and 3.19 of the thesis (sec. 3.4.2,
// figs. 3.5-3.7), the refactoring of R's affected rows
//     R~_aff^T R~_aff = R_aff^T R_aff + A_new              (eq. 3.14)
//     R~_aff^T y~_aff = R_aff^T y_aff + b_new              (eq. 3.19)
// by a left-looking block Cholesky factorisation. The right side is never
// formed as a matrix: for each affected position p in order, the work row
// W_p gathers A_new's row p and the old rows' outer products on p, takes
// out what the rows already refactored eliminate, and is factored into the
// new row p and y~_p. Old and new rows wait in lists per column, each
// filed under the next column it contributes to. A batch factorisation is
// the same code with R empty and every variable affected, and the top
// re-elimination (top_reordering.h) the same with the kept rows below the
// top waiting as rows already refactored.
#pragma once

#include <array>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/cholesky_factor.h"

namespace hamal::aprilsam {

class LeftLookingFactorization {
 public:
  // The work space for n positions (reset) or one more (append).
  void resize(int n);
  void append();

  // Refactors aff.positions (collected and indexed) of r for the system
  // a_new and commits the new rows. `in_place`: a batch on an empty r,
  // writing R's rows directly. On a failure r and y are left as they were
  // (empty, for in_place) and aff is emptied.
  FactorUpdateOutcome factor(CholeskyFactor& r, AffectedRows& aff,
                             const BlockNormalEquations& a_new, bool in_place);
  // The same for the top of a re-elimination: r's positions from nn on
  // (emptied by CholeskyFactor::moveTopLast), from h, the factors' share on
  // them; the kept rows that reach the top take their share out of it
  // (R_NT^T R_NT, each untouched subtree's marginal on its separator) as
  // rows already refactored do.
  FactorUpdateOutcome factorTop(CholeskyFactor& r, AffectedRows& aff, const BlockNormalEquations& h,
                                int nn);

 private:
  // Rows waiting for the column they contribute to next: head[q] the first
  // row waiting at position q (-1: none), next[j] the row after j in its
  // list, ptr[j] the block of row j that column is.
  struct WaitingRows {
    std::vector<int> head, next, ptr;
  };
  // W_p's blocks, created zero on first use. slot[q] holds block q's
  // offset in vals (-1 when absent): the lookup is the factorisation's most
  // frequent cache miss, and this saves one dependent load. vals only
  // grows, its first size entries in use, so a new block costs a few
  // stores, not a vector resize.
  struct WorkRow {
    std::vector<int> slot;   // position -> offset in vals
    std::vector<int> cols;   // the blocks' positions, in creation order
    std::vector<int> order;  // cols sorted (factorRow)
    std::vector<double> vals;
    int size = 0;
  };

  // factor()'s steps, in its order: c = R_aff^T y_aff + b_new (eq. 3.19);
  // the old rows filed by the column they contribute to first; then for
  // each affected position p, W_p gathered from a_new, the old rows and the
  // rows already refactored (addWaitingRows), and factored into the new row
  // p and y~_p (factorRow, false when W_pp is not positive definite).
  void formRightHandSide(const CholeskyFactor& r, const BlockNormalEquations& a_new);
  void fileOldRows(bool in_place);
  // `pos_of[j]` is the position of waiting row j (for its dimension).
  template <typename RefOf>
  void addWaitingRows(int p, double sign, const FactorRowStore& store, RefOf ref_of,
                      const int* pos_of, WaitingRows& lists);
  bool factorRow(int i, const double* diag_scale, FactorRowStore& store, RowRef* nr);
  double* wblock(int p, int q) __attribute__((always_inline)) {
    int off = w_.slot[q];
    if (__builtin_expect(off < 0, 0)) off = newWBlock(p, q);
    return w_.vals.data() + off;
  }
  int newWBlock(int p, int q);
  // Back to the state between updates after a failure.
  void forgetAfterFailure(CholeskyFactor& r, bool in_place);

  // The factor and affected rows of the update under way (set by factor()):
  // the hot loops index them as they would their own arrays.
  const int* dims_ = nullptr;
  const RowRef* refs_ = nullptr;
  const int* aff_ = nullptr;
  int* local_ = nullptr;
  std::array<double, kMaxDim>* c_ = nullptr;
  int m_ = 0;

  WaitingRows old_;  // R's old rows of aff
  WaitingRows new_;  // the rows already refactored
  // factorTop: the kept rows that reach the top (their positions), filed as
  // rows already refactored; empty outside a re-elimination.
  std::vector<int> ext_rows_;
  WaitingRows ext_;
  WorkRow w_;
  FactorRowStore work_;  // the new rows (unless in place), for commit() to append
};

}  // namespace hamal::aprilsam
