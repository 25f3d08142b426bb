// HouseholderRankUpdate: R and y updated for new factors given as the rows
// of their whitened Jacobian W and error e (A_new = W^T W, b_new = W^T e),
// the factor_update=rank path of AprilSAM (thesis sec. 3.4.2, reaching the
// R~, y~ of eq. 3.14 and 3.19 another way; a Cholesky rank update in the
// manner of iSAM's Givens rotations, sec. 2.3.3).
//
// Walking the affected rows in increasing position, at row p the pending
// rows of W whose first block is p meet R_p, and dim(p) Householder
// reflections turn [R_p y_p; W e] into [R~_p y~_p; 0 e']. What is left of
// the pending rows continues, merged into one set, to the first block after
// p (p's new parent), so the rows visited are p's ancestors: aff of eq.
// 3.14. A row of width w costs O(k w) for k new rows instead of the O(w^2)
// of re-forming and refactoring it, which is what the dense top of the
// factor of a city-scale graph needs.
#pragma once

#include <array>
#include <vector>

#include "backends/aprilsam/cholesky_factor.h"
#include "backends/aprilsam/jacobian_rows.h"

namespace hamal::aprilsam {

class HouseholderRankUpdate {
 public:
  // The work space for n positions (reset) or one more (append).
  void resize(int n);
  void append();

  // Folds w into r and commits the new rows (appended to r's store): aff
  // becomes the rows updated. flops is the refactoring's estimate for the
  // same rows (the thesis' cost model, so both paths lead to the same batch
  // decisions). On a failure r is left as it was and aff is emptied.
  FactorUpdateOutcome addRows(CholeskyFactor& r, AffectedRows& aff, const JacobianRows& w);
  // The flops addRows(r, w) would report, from the structure alone (the
  // symbolic part of the update, no arithmetic, r untouched).
  double predictedFlops(const CholeskyFactor& r, const JacobianRows& w);

 private:
  // A set of pending rows of W: `rows` rows over the blocks at `cols`
  // (increasing), row-major rows x (width + 1), e last.
  struct PendingRows {
    int rows = 0;
    int width = 0;
    std::vector<int> cols;
    std::vector<double> vals;
  };
  // The pivot block's reflections (pivotReflections) and R~_pp.
  struct Pivot {
    int dp = 0;
    int k = 0;                          // pending rows
    std::vector<double> v;              // k x dp, column-major: reflection t's vector below row t
    std::array<double, kMaxDim> tau{};  // 0 where the reflection is skipped (nothing to zero)
    std::array<bool, kMaxDim> skip{};
    std::array<double, kMaxDim> sign{};  // +-1: R~ has a positive diagonal
    std::vector<double> block;           // R~_pp, dp x dp, column-major
    std::vector<double> mat;             // [R_pp; W_p] as it is reflected, column-major
  };
  // A pending set met at a row, and where reflectRest's gather stands in it.
  struct SetCursor {
    const PendingRows* set;
    int block;   // its next block
    int column;  // that block's first scalar column in the set
  };
  // predictedFlops()' work space: visited / column stamps, the affected positions,
  // and the columns the pending rows carry into each position.
  struct Symbolic {
    std::vector<long> mark, col_mark;
    long stamp = 0, col_stamp = 0;
    std::vector<int> aff, cols;
    std::vector<std::vector<int>> in;
  };

  // addRows()' steps, for each affected position p: the pending rows filed
  // by their first block (filePendingRows); the new row's columns
  // (markRowColumns, returning its width); dim(p) Householder reflections
  // computed on the pivot block [R_pp; W_p] alone (pivotReflections, false
  // when a pivot fails); then every other column of [R_p y_p; W e]
  // reflected and written once, into R~_p, y~_p and the pending rows
  // carried on to p's new parent (reflectRest): for the unrolled shapes in
  // R~_p's own layout (reflectInPlace), for the others through a transposed
  // copy (reflectTransposed). Reflecting column by column does each
  // column's arithmetic in the order a reflection at a time over the
  // stacked matrix would, so the result is the same to the bit; what it
  // saves is the stacked matrix (three copies of each column) and the loop
  // overhead of k-row inner loops, k being the few pending rows.
  void filePendingRows(const JacobianRows& w);
  int markRowColumns(int p, const FactorRow& old, int first, int* k_rows);
  bool pivotReflections(int p, const FactorRow& old, int first, int k_rows, Pivot* piv);
  template <int DP, int K>
  void reflectRest(int i, const FactorRow& old, int first, int width, const Pivot& piv, RowRef* nr);
  template <int DP, int K>
  void reflectInPlace(int i, const FactorRow& old, int nw, const Pivot& piv, double* nvals,
                      double* bt);
  void reflectTransposed(int i, const FactorRow& old, int nw, const Pivot& piv, double* nvals,
                         double* bt);
  template <int DQ>
  void gatherBlock(const double* asrc, double* at, double* bt, int j0, int nw, int dp, int q,
                   int dq_runtime = DQ);
  void gatherRightSide(double* bt, int nw);
  void gatherPending(double* bt, int nw, int dp);

  // The factor and affected rows of the update under way (set by addRows).
  const int* dims_ = nullptr;
  const std::array<double, kMaxDim>* y_ = nullptr;
  FactorRowStore* store_ = nullptr;
  const int* aff_ = nullptr;
  std::array<double, kMaxDim>* c_ = nullptr;

  // The pending sets; head_[p] the first set filed at position p (-1:
  // none), next_[g] the set after g in its list.
  std::vector<PendingRows> pending_;
  std::vector<int> head_, next_;
  // The new row's blocks (increasing) and slot_[q], block q's first scalar
  // column in it (-1 when absent); merged_ is markRowColumns' union.
  std::vector<int> w_cols_, slot_, merged_;
  Pivot pivot_;
  // reflectRest: the sets met at the row, the rows carried on from it
  // (swapped into the first set's values), the row's columns transposed
  // (reflectTransposed).
  std::vector<SetCursor> sets_;
  std::vector<double> carry_;
  std::vector<double> rows_t_;
  Symbolic sym_;
};

}  // namespace hamal::aprilsam
