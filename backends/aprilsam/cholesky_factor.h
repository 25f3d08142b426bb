// CholeskyFactor: AprilSAM's factor R (R^T R = A) and right-hand side y
// (R^T y = b) as kept between steps in a fixed elimination order (thesis
// sec. 3.4.1), with what the updates of sec. 3.4.2 read from it: the
// elimination tree (a row's first off-diagonal block names its parent), the
// rows referencing each column, and the flops of each row (the cost model
// of sec. 3.4.3).
//
// It holds R; the algorithms that change it live in files of their own
// (left_looking_factorization.h, householder_rank_update.h,
// top_reordering.h) and hand it their new rows for the affected positions
// (AffectedRows), which commit() puts in place.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/factor_row_store.h"

namespace hamal::aprilsam {

// What an update of R did.
struct FactorUpdateOutcome {
  bool ok = true;
  int failed_position = -1;     // the block whose Cholesky failed (not PD)
  long columns_recomputed = 0;  // scalar columns of R refactored
  double flops = 0;             // estimated flops of the refactored rows
};

struct AffectedRows;

class CholeskyFactor {
 public:
  // Empties R and y and sets the dimensions of positions 0..n-1 (a batch).
  void reset(const std::vector<int>& dims);
  // A new variable at the end of the order: an empty row, y = 0.
  void append(int dim);

  int size() const { return static_cast<int>(dims_.size()); }
  int dim(int p) const { return dims_[p]; }
  const int* dims() const { return dims_.data(); }
  FactorRow row(int p) const { return store_.view(refs_[p]); }
  const RowRef& ref(int p) const { return refs_[p]; }
  const RowRef* refs() const { return refs_.data(); }
  int parent(int p) const { return parent_[p]; }
  const double* y(int p) const { return y_[p].data(); }
  const std::array<double, kMaxDim>* ys() const { return y_.data(); }
  // The pooled rows. An update appends its new rows to them (the rank
  // update), or writes them in place (a batch on an empty factor, whose
  // row references are then refsInPlace()).
  const FactorRowStore& store() const { return store_; }
  FactorRowStore& store() { return store_; }
  RowRef* refsInPlace() { return refs_.data(); }
  // No row since reset(): a batch may write R's rows in place.
  bool empty() const { return empty_; }
  // Back to the empty rows of reset() (an in-place batch that failed).
  void clearRows();

  template <class F>
  void forEachRowReferencing(int q, F&& f) const {
    for (int k = col_ptr_[q]; k < col_ptr_[q + 1]; ++k) f(col_idx_[k]);
    for (int r : col_extra_[q]) f(r);
  }

  std::size_t storedValues() const { return live_vals_; }
  std::size_t valueCapacity() const { return store_.vals.capacity(); }
  long columnsTotal() const { return columns_total_; }
  double totalFlops() const { return total_flops_; }
  // choleskyFlops of a block row of `dim` scalar rows spanning `width`
  // columns: its scalar columns of L (rows of R) hold width, width-1, ...
  // nonzeros (diagonal included). choleskyFlops' sum, in its order, without
  // building the vector of counts for every row.
  static double rowFlops(int width, int dim) {
    double flops = 0;
    for (int t = 0; t < dim; ++t) {
      const long c = width - t;
      flops += static_cast<double>(c) * static_cast<double>(c);
    }
    return flops;
  }

  // Where an update's new rows are: kWork, in `work` (aff.rows); kAppended,
  // already at the end of store() (aff.rows: the rank update writes them
  // there); kInPlace, R's rows already (refsInPlace(): a batch on an empty
  // factor).
  enum class NewRows { kWork, kAppended, kInPlace };
  // Makes the new rows and aff.y the rows and y of aff.positions, keeps the
  // column lists, the elimination tree and the flop count, and forgets
  // aff's index.
  void commit(AffectedRows& aff, NewRows where, const FactorRowStore* work,
              FactorUpdateOutcome* out);

  // The replaced rows are more than half the live ones: worth a compact()
  // when the store would otherwise grow.
  bool mostlyGarbage() const { return store_.n_vals - live_vals_ > live_vals_ / 2; }
  // Drops the replaced rows from the store (live rows keep their order).
  void compact();

  // The top's rows (`order`, old positions) emptied and put last in that
  // order; the kept rows (`kept`, ascending) first, their numbers untouched
  // and their columns renumbered: new_pos[p] is old position p's new one.
  void moveTopLast(const std::vector<int>& kept, const std::vector<int>& order,
                   const std::vector<int>& new_pos);

 private:
  // col_ptr_/col_idx_ for every row, from store_ and refs_ alone (after a
  // batch or a re-elimination wrote all rows); col_extra_ emptied.
  void buildColumnLists();

  std::vector<int> dims_;
  FactorRowStore store_;
  std::vector<RowRef> refs_;   // position -> its row in store_
  std::size_t live_vals_ = 0;  // numbers in live rows (the rest of n_vals is garbage)
  std::vector<int> parent_;
  std::vector<std::array<double, kMaxDim>> y_;
  // The rows referencing each column: those of the last batch in CSR form
  // (built in one pass, no allocation per column), those added since in
  // col_extra_.
  std::vector<int> col_ptr_{0}, col_idx_;
  std::vector<std::vector<int>> col_extra_;
  std::vector<int> col_cursor_;  // buildColumnLists: a cursor per column
  std::vector<double> row_flops_;
  long columns_total_ = 0;
  double total_flops_ = 0;
  bool empty_ = true;
};

// The rows an update rewrites: eq. 3.14's aff, the positions of S and all
// their elimination-tree ancestors (figs. 3.5, 3.6), ascending, and the new
// rows and y~ (eq. 3.19) an algorithm made for them.
struct AffectedRows {
  std::vector<int> positions;
  std::vector<int> index;  // position -> index in positions, -1 outside
  std::vector<RowRef> rows;
  std::vector<std::array<double, kMaxDim>> y;

  // positions += s and its ancestors not yet in it (unsorted, unindexed).
  void addPathToRoot(const CholeskyFactor& r, int s) {
    for (int p = s; p >= 0 && index[p] < 0; p = r.parent(p)) {
      index[p] = 0;  // mark
      positions.push_back(p);
    }
  }
  // Sorts positions and indexes them.
  void indexPositions();
  void forgetIndex() {
    for (int a : positions) index[a] = -1;
  }
};

}  // namespace hamal::aprilsam
