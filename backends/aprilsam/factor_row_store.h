// FactorRowStore: where the block rows of AprilSAM's factor R live (thesis
// sec. 3.4.1: R is kept between steps, stored by rows in elimination order).
//
// A block row is its column positions, the offsets of its blocks and the
// blocks' numbers. The rows lie one after another in two pooled arrays (the
// columns and offsets in `ints`, the numbers in `vals`), not in vectors of
// their own: a batch rewrites every row, and allocating per row would make
// batches pay for malloc and free. A row is replaced by appending its new
// version; the old one stays as garbage until its owner compacts the store
// (CholeskyFactor::compact).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

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

// One block row of R: the diagonal block first (cols[0] is the row's own
// position), then the off-diagonal blocks in increasing column position.
// Block k is dim(row) x dim(cols[k]), column-major, at vals[offs[k]].
struct FactorRow {
  Span<int> cols;
  Span<int> offs;
  Span<double> vals;
  int width = 0;  // scalar columns the row spans (sum of the blocks' widths)
};

// Where a row is in a FactorRowStore.
struct RowRef {
  std::size_t ints = 0;  // cols at ints, offs at ints + ncols
  std::size_t vals = 0;
  int ncols = 0;
  int nvals = 0;
  int width = 0;
};

struct FactorRowStore {
  // The first n_ints / n_vals entries are in use. The arrays grow by
  // doubling and shrink only when their owner releases them, so adding a
  // row costs no zero-fill (its owner writes every number) and rarely a
  // reallocation.
  PooledArray<int> ints;
  PooledArray<double> vals;
  std::size_t n_ints = 0, n_vals = 0;
  FactorRow view(const RowRef& r) const {
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
  RowRef append(const FactorRowStore& from, const RowRef& r) {
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

}  // namespace hamal::aprilsam
