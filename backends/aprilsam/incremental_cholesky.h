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
// The right side is never formed as a matrix: the left-looking block
// factorisation below adds the old rows' outer products while it subtracts
// the new ones. A batch factorisation is the same code with R empty and every
// variable affected.
//
// addRows reaches the same R~ and y~ another way: it takes A_new as the
// whitened Jacobian rows W of the new factors (A_new = W^T W) and, walking
// the same affected rows in order, turns [R_p y_p; W e] into [R~_p y~_p; 0 e']
// with dim(p) Householder reflections (a Cholesky rank update in the manner
// of iSAM's Givens rotations, sec. 2.3.3). The affected rows are those of
// eq. 3.14, but a row of width w costs O(k w) for k new rows instead of the
// O(w^2) of re-forming and refactoring it, which is what the dense top of
// the factor of a city-scale graph needs (thesis eq. 3.14 remains the batch
// path and the option factor_update=refactor).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/jacobian_rows.h"
#include "backends/aprilsam/pooled_array.h"

namespace hamal::aprilsam {

// A read-only run of T: a row's columns, offsets or numbers in R's pooled
// arrays. Valid until the factor next changes (an update, append or reset).
template <class T>
class Span {
 public:
  Span() = default;
  Span(const T* p, std::size_t n) : p_(p), n_(n) {}
  const T* data() const { return p_; }
  std::size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  const T& operator[](std::size_t i) const { return p_[i]; }
  const T& front() const { return p_[0]; }
  const T* begin() const { return p_; }
  const T* end() const { return p_ + n_; }
  std::vector<T> vector() const { return std::vector<T>(p_, p_ + n_); }

 private:
  const T* p_ = nullptr;
  std::size_t n_ = 0;
};

class IncrementalCholesky {
 public:
  // One block row of R: the diagonal block first (cols[0] is the row's own
  // position), then the off-diagonal blocks in increasing column position.
  // Block k is dim(row) x dim(cols[k]), column-major, at vals[offs[k]].
  struct Row {
    Span<int> cols;
    Span<int> offs;
    Span<double> vals;
    int width = 0;  // scalar columns the row spans (sum of the blocks' widths)
  };

  struct Outcome {
    bool ok = true;
    int failed_position = -1;     // the block whose Cholesky failed (not PD)
    long columns_recomputed = 0;  // scalar columns of R refactored
    double flops = 0;             // estimated flops of the refactored rows
  };

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
  // and e (see above). flops is update()'s estimate for the same rows (the
  // thesis' cost model, so both paths lead to the same batch decisions). On
  // a failure R and y are left as they were.
  Outcome addRows(const JacobianRows& w);
  // The flops addRows(w) would report, from the structure alone (the
  // symbolic part of the update, no arithmetic, R untouched): what the
  // update policy needs to decide on a batch before paying for the update.
  double addRowsFlops(const JacobianRows& w);

  // The rows an iSAM2-style re-elimination of the top must redo: those of
  // the positions in `path` (the variables of factors added since the last
  // re-elimination: eq. 3.14's S), of every row that references a position
  // in `relin` (a variable moved to a new linearisation point changes the
  // share of each of its factors, and each such factor is in the row of its
  // first variable, which references the moved one), and all their
  // elimination-tree ancestors. Ascending, closed under parent().
  std::vector<int> topOf(const std::vector<int>& path, const std::vector<int>& relin) const;
  // Re-eliminates the rows `top` (as topOf returns them) in a new order, as
  // iSAM2 re-eliminates the top of its Bayes tree: the other rows keep their
  // numbers and their relative order and come first, then top's positions in
  // the order `order` (a permutation of top). `h` holds the factors' share
  // on the top variables at their new positions (top.size() positions from
  // size() - top.size() on): the whole J^T J of a factor on top variables
  // only, and the top blocks of one that also reaches a kept row, linearised
  // where that row was made. The kept rows' share, R_NT^T R_NT (each
  // untouched subtree's marginal on its separator, which iSAM2 caches per
  // clique), is subtracted as the top is factored, so the top's pattern is
  // that of the graph and the separators, not the old order's fill.
  // new_pos[p] is the new position of old position p; affected() is the
  // top's new positions. On a failure (not positive definite at old
  // position failed_position) R is left renumbered without the top's rows:
  // the caller must start again with reset() (a batch).
  Outcome reorderTop(const std::vector<int>& top, const std::vector<int>& order,
                     const BlockNormalEquations& h, std::vector<int>* new_pos);

  // The rows the last successful update refactored, in increasing position.
  const std::vector<int>& affected() const { return aff_; }

  int size() const { return static_cast<int>(dims_.size()); }
  int dim(int p) const { return dims_[p]; }
  Row row(int p) const { return store_.view(refs_[p]); }
  // The same row as raw pointers, for the back-substitution's inner loop,
  // where building row()'s view cost a fifth of the loop: ncols blocks,
  // their columns at ints[0..ncols), offsets at ints[ncols..2 ncols).
  int rowBlocks(int p) const { return refs_[p].ncols; }
  const int* rowInts(int p) const { return store_.ints.data() + refs_[p].ints; }
  const double* rowValues(int p) const { return store_.vals.data() + refs_[p].vals; }
  int parent(int p) const { return parent_[p]; }
  const double* y(int p) const { return y_[p].data(); }
  // Calls f(r) for every row r whose structure references column q (each
  // once, in no particular order), for the partial back-substitution.
  // Structures only grow between resets, so no entry goes stale.
  template <class F>
  void forEachRowReferencing(int q, F&& f) const {
    for (int k = col_ptr_[q]; k < col_ptr_[q + 1]; ++k) f(col_idx_[k]);
    for (int r : col_extra_[q]) f(r);
  }

  // The numbers R holds, and the capacity of the pooled array that holds
  // them (with the rows an update replaced and compaction has not yet
  // dropped): the memory check of the scale study.
  std::size_t storedValues() const { return live_vals_; }
  std::size_t valueCapacity() const { return store_.vals.capacity(); }

  long columnsTotal() const { return columns_total_; }
  // Estimated flops of factoring all of R from scratch (choleskyFlops of every
  // scalar column count), kept up to date row by row.
  double totalFlops() const { return total_flops_; }

 private:
  double rowFlops(int width, int dim) const;
  // Makes the new rows and c_ the rows and y of aff_ and keeps the
  // column lists, the elimination tree and the flop count. Where: kWork,
  // the rows are in work_ (work_refs_); kAppended, already at the end of
  // store_ (work_refs_: the rank update writes them there); kInPlace, R's
  // rows already (refs_: a batch on an empty factor).
  enum class NewRows { kWork, kAppended, kInPlace };
  void commit(Outcome* out, NewRows where = NewRows::kWork);
  // aff_ += s and its elimination-tree ancestors not yet in it (figs. 3.5,
  // 3.6); then sorted, with local_ giving each position's index.
  void addPathToRoot(int s);
  void indexAffected();
  void forgetAffected();
  // col_ptr_/col_idx_ for every row, from store_ and refs_ alone (after a
  // batch or a re-elimination wrote all rows); col_extra_ emptied.
  void buildColumnLists();

  // A set of pending rows of W during addRows: `rows` rows over the blocks
  // at `cols` (increasing), row-major rows x (width + 1), e last.
  struct PendingRows {
    int rows = 0;
    int width = 0;
    std::vector<int> cols;
    std::vector<double> vals;
  };
  std::vector<PendingRows> pending_;

  // R's rows live one after another in two pooled arrays (a row's columns
  // and offsets in `ints`, its blocks in `vals`), not in vectors of their
  // own: a batch rewrites every row, and allocating per row would make
  // batches pay for malloc and free. A batch writes the rows in place,
  // in order; the rank update appends its new rows to store_, and the
  // refactoring update (update(), reorderTop) writes them into work_ for
  // commit() to append; either way the old rows stay as garbage until
  // compact().
  struct RowRef {
    std::size_t ints = 0;  // cols at ints, offs at ints + ncols
    std::size_t vals = 0;
    int ncols = 0;
    int nvals = 0;
    int width = 0;
  };
  struct RowStore {
    // The first n_ints / n_vals entries are in use. The arrays grow by
    // doubling and shrink only in compact(), so adding a row costs no
    // zero-fill (its owner writes every number) and rarely a reallocation.
    PooledArray<int> ints;
    PooledArray<double> vals;
    std::size_t n_ints = 0, n_vals = 0;
    Row view(const RowRef& r) const {
      return {Span<int>(ints.data() + r.ints, r.ncols),
              Span<int>(ints.data() + r.ints + r.ncols, r.ncols),
              Span<double>(vals.data() + r.vals, r.nvals), r.width};
    }
    // Room for a row of ncols blocks and nvals numbers at the end.
    RowRef add(int ncols, int nvals, int width) {
      reserve(ncols, nvals);
      RowRef r{n_ints, n_vals, ncols, nvals, width};
      n_ints += 2 * static_cast<std::size_t>(ncols);
      n_vals += static_cast<std::size_t>(nvals);
      return r;
    }
    // A copy of row r of `from` at the end (from must be another store).
    RowRef append(const RowStore& from, const RowRef& r) {
      const RowRef c = add(r.ncols, r.nvals, r.width);
      std::copy_n(from.ints.data() + r.ints, 2 * r.ncols, ints.data() + c.ints);
      std::copy_n(from.vals.data() + r.vals, r.nvals, vals.data() + c.vals);
      return c;
    }
    void clear() { n_ints = n_vals = 0; }
    // Room for ncols blocks and nvals numbers after the rows in use: a view
    // of a row taken before this may point to freed memory after it.
    void reserve(int ncols, int nvals) {
      const std::size_t ni = n_ints + 2 * static_cast<std::size_t>(ncols);
      const std::size_t nv = n_vals + static_cast<std::size_t>(nvals);
      ints.reserve(ni);
      vals.reserve(nv);
    }
  };
  // Drops the replaced rows from store_ (live rows keep their order).
  void compact();
  // The replaced rows are more than half the live ones: worth a compact()
  // when the store would otherwise grow.
  bool mostlyGarbage() const { return store_.n_vals - live_vals_ > live_vals_ / 2; }

  // update()'s steps, in its order: aff_ from a_new (or every position);
  // c = R_aff^T y_aff + b_new (eq. 3.19); the old rows filed by the column
  // they contribute to first; then for each affected position p, W_p
  // gathered from a_new, the old rows and the rows already refactored
  // (addWaitingRows), and factored into the new row p and y~_p (factorRow,
  // false when W_pp is not positive definite).
  void collectAffected(const BlockNormalEquations& a_new, bool all);
  // The rest of update() for the aff_ already collected (reorderTop's too).
  Outcome factorAffected(const BlockNormalEquations& a_new, bool in_place);
  void formRightHandSide(const BlockNormalEquations& a_new);
  void fileOldRows(bool in_place);
  // `pos_of[j]` is the position of waiting row j (for its dimension).
  template <typename RefOf>
  void addWaitingRows(int p, double sign, const RowStore& store, RefOf ref_of, const int* pos_of,
                      std::vector<int>& head, std::vector<int>& next_of, std::vector<int>& ptr);
  bool factorRow(int i, const double* diag_scale, RowStore& store, RowRef* nr);
  // Block (p, q) of the work row W_p, created zero on first use. slot_[q]
  // holds its offset in w_vals_: the lookup is the factorisation's most
  // frequent cache miss, and this saves one dependent load.
  double* wblock(int p, int q) __attribute__((always_inline)) {
    int off = slot_[q];
    if (__builtin_expect(off < 0, 0)) off = newWBlock(p, q);
    return w_vals_.data() + off;
  }
  int newWBlock(int p, int q);

  // addRows()'s steps, for each affected position p: the pending rows filed
  // by their first block (filePendingRows); the new row's columns
  // (markRowColumns, returning its width); dim(p) Householder reflections
  // computed on the pivot block [R_pp; W_p] alone (pivotReflections, false
  // when a pivot fails); then every other column of [R_p y_p; W e] gathered,
  // reflected and written once, straight into R~_p, y~_p and the pending
  // rows carried on to p's new parent (reflectRest). Reflecting column by
  // column does each column's arithmetic in the order a reflection at a time
  // over the stacked matrix would, so the result is the same to the bit;
  // what it saves is the stacked matrix (three copies of each column) and
  // the loop overhead of k-row inner loops, k being the few pending rows.
  struct Pivot {
    int dp = 0;
    int k = 0;                          // pending rows
    std::vector<double> v;              // k x dp, column-major: reflection t's vector below row t
    std::array<double, kMaxDim> tau{};  // 0 where the reflection is skipped (nothing to zero)
    std::array<bool, kMaxDim> skip{};
    std::array<double, kMaxDim> sign{};  // +-1: R~ has a positive diagonal
    std::vector<double> block;           // R~_pp, dp x dp, column-major
  };
  void filePendingRows(const JacobianRows& w);
  int markRowColumns(int p, const Row& old, int first, int* k_rows);
  bool pivotReflections(int p, const Row& old, int first, int k_rows, Pivot* piv);
  template <int DP, int K>
  void reflectRest(int i, const Row& old, int first, int width, const Pivot& piv, RowRef* nr);
  template <int DQ>
  void gatherBlock(const double* asrc, double* at, double* bt, int j0, int nw, int dp, int q,
                   int dq_runtime = DQ);

  std::vector<int> dims_;
  RowStore store_;
  std::vector<RowRef> refs_;       // position -> its row in store_
  std::size_t live_vals_ = 0;      // numbers in live rows (the rest of n_vals is garbage)
  RowStore work_;                  // a refactoring update's new rows
  std::vector<RowRef> work_refs_;  // index in aff_ -> its new row (in store_ for a rank update)
  std::vector<int> parent_;
  std::vector<std::array<double, kMaxDim>> y_;
  // The rows referencing each column: those of the last batch in CSR form
  // (built in one pass, no allocation per column), those added since in
  // col_extra_.
  std::vector<int> col_ptr_{0}, col_idx_;
  std::vector<std::vector<int>> col_extra_;
  std::vector<double> row_flops_;
  long columns_total_ = 0;
  double total_flops_ = 0;
  bool empty_ = true;  // no row since reset(): a batch may write in place

  // Work space, sized to the number of positions and reset after each use so
  // that an update costs what it touches, not what R holds.
  std::vector<int> aff_;
  std::vector<int> local_;     // position -> index in aff_, -1 outside
  std::vector<int> head_old_;  // position -> first old row waiting for it
  std::vector<int> head_new_;  // position -> first new row waiting for it
  std::vector<int> slot_;      // position -> its block in the work row (update: offset in w_vals_,
                               // addRows: first column), -1 when absent
  std::vector<int> next_old_, next_new_, ptr_old_, ptr_new_;
  // reorderTop: the kept rows that reach the top, filed like rows already
  // refactored (head per position, next and block pointer per row); empty
  // outside a re-elimination.
  std::vector<int> ext_rows_, head_ext_, next_ext_, ptr_ext_;
  std::vector<std::array<double, kMaxDim>> c_;
  std::vector<int> w_cols_, order_;
  // W_p's blocks; only grows, its first w_size_ entries in use, so that a
  // new block costs a few stores, not a vector resize.
  std::vector<double> w_vals_;
  int w_size_ = 0;
  // addRows: the pivot's reflections, the pending sets met at a row, and
  // the rows carried on from it (swapped into the first set's values).
  struct SetCursor {
    const PendingRows* set;
    int block;   // its next block
    int column;  // that block's first scalar column in the set
  };
  Pivot pivot_;
  std::vector<SetCursor> sets_;
  std::vector<double> carry_;
  std::vector<int> merged_;     // markRowColumns: the union of two column lists
  std::vector<double> rows_t_;  // reflectRest: the columns of the row, transposed
  // addRowsFlops: visited / column stamps, the affected positions, and the
  // columns the pending rows carry into each position.
  std::vector<long> sym_mark_, sym_col_mark_;
  long sym_stamp_ = 0, sym_col_stamp_ = 0;
  std::vector<int> sym_aff_, sym_cols_;
  std::vector<std::vector<int>> sym_in_;
};

}  // namespace hamal::aprilsam
