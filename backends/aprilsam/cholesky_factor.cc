// CholeskyFactor: see cholesky_factor.h (thesis sec. 3.4.1, R kept between
// steps; its row and flop bookkeeping).
#include "backends/aprilsam/cholesky_factor.h"

#include <algorithm>
#include <utility>

namespace hamal::aprilsam {

void CholeskyFactor::reset(const std::vector<int>& dims) {
  // The pooled arrays keep their capacity: the batch that follows writes
  // about as many numbers, in place and in order. Pooling also keeps memory
  // proportional to R's numbers: per-row buffers would each grow to the
  // widest row any ordering ever put at their position.
  const int n = static_cast<int>(dims.size());
  store_.clear();
  refs_.assign(n, RowRef());
  live_vals_ = 0;
  empty_ = true;
  col_ptr_.assign(n + 1, 0);
  col_idx_.clear();
  col_extra_.assign(n, {});
  dims_ = dims;
  parent_.assign(n, -1);
  y_.assign(n, {});
  row_flops_.assign(n, 0.0);
  columns_total_ = 0;
  for (int d : dims) columns_total_ += d;
  total_flops_ = 0;
}

void CholeskyFactor::append(int dim) {
  dims_.push_back(dim);
  refs_.emplace_back();
  parent_.push_back(-1);
  y_.push_back({});
  col_ptr_.push_back(col_ptr_.back());
  col_extra_.emplace_back();
  row_flops_.push_back(0);
  columns_total_ += dim;
}

void CholeskyFactor::clearRows() {
  store_.clear();
  std::fill(refs_.begin(), refs_.end(), RowRef());
}

void AffectedRows::indexPositions() {
  if (!std::is_sorted(positions.begin(), positions.end()))
    std::sort(positions.begin(), positions.end());
  for (int i = 0; i < static_cast<int>(positions.size()); ++i) index[positions[i]] = i;
}

void CholeskyFactor::commit(AffectedRows& aff, NewRows where, const FactorRowStore* work,
                            FactorUpdateOutcome* out) {
  const int m = static_cast<int>(aff.positions.size());
  empty_ = false;
  if (where == NewRows::kInPlace) {
    // A batch on an empty factor: the rows are store_'s already, and every
    // column's list is new.
    buildColumnLists();
    live_vals_ = store_.n_vals;
  } else {
    // The garbage of earlier steps is reclaimed only when the new rows would
    // not fit: compacting costs a sort and a copy of the live rows, and
    // growing instead costs a copy, a zero-fill and fresh pages of the whole
    // store, so neither should happen on every step.
    if (where == NewRows::kWork && mostlyGarbage()) {
      std::size_t new_ints = 0, new_vals = 0;
      for (int i = 0; i < m; ++i) {
        new_ints += 2 * static_cast<std::size_t>(aff.rows[i].ncols);
        new_vals += aff.rows[i].nvals;
      }
      if (store_.n_vals + new_vals > store_.vals.capacity() ||
          store_.n_ints + new_ints > store_.ints.capacity())
        compact();
    }
    const FactorRowStore& from = where == NewRows::kWork ? *work : store_;
    for (int i = 0; i < m; ++i) {
      const int p = aff.positions[i];
      const RowRef& w = aff.rows[i];
      const FactorRow nr = from.view(w);
      {
        // Structures only grow (the symbolic factor of A + A_new contains
        // that of A), so only columns new to the row are recorded.
        const FactorRow old = row(p);
        std::size_t a = 1;
        for (std::size_t k = 1; k < nr.cols.size(); ++k) {
          const int q = nr.cols[k];
          while (a < old.cols.size() && old.cols[a] < q) ++a;
          if (a < old.cols.size() && old.cols[a] == q) continue;
          col_extra_[q].push_back(p);
        }
      }
      live_vals_ += w.nvals - refs_[p].nvals;
      refs_[p] = where == NewRows::kWork ? store_.append(*work, w) : w;
    }
  }
  // A peak that has passed (a top or a batch that needs far fewer numbers
  // than R held) does not keep its memory.
  if (store_.vals.capacity() > 8 * live_vals_ + 8192) compact();
  for (int i = 0; i < m; ++i) {
    const int p = aff.positions[i];
    const RowRef& r = refs_[p];
    parent_[p] = r.ncols > 1 ? store_.ints[r.ints + 1] : -1;
    for (int t = 0; t < dims_[p]; ++t) y_[p][t] = aff.y[i][t];
    const double f = rowFlops(r.width, dims_[p]);
    total_flops_ += f - row_flops_[p];
    row_flops_[p] = f;
    out->flops += f;
  }
  aff.forgetIndex();
}

void CholeskyFactor::buildColumnLists() {
  // CSR in two passes: no allocation per column.
  const int n = size();
  col_ptr_.assign(n + 1, 0);
  for (int p = 0; p < n; ++p) {
    const FactorRow r = row(p);
    for (std::size_t k = 1; k < r.cols.size(); ++k) ++col_ptr_[r.cols[k] + 1];
  }
  for (int q = 0; q < n; ++q) col_ptr_[q + 1] += col_ptr_[q];
  col_idx_.resize(col_ptr_[n]);
  col_cursor_.assign(col_ptr_.begin(), col_ptr_.end() - 1);
  for (int p = 0; p < n; ++p) {
    const FactorRow r = row(p);
    for (std::size_t k = 1; k < r.cols.size(); ++k) col_idx_[col_cursor_[r.cols[k]]++] = p;
  }
  col_extra_.assign(n, {});
}

void CholeskyFactor::moveTopLast(const std::vector<int>& kept, const std::vector<int>& order,
                                 const std::vector<int>& new_pos) {
  // The kept rows stay where they are in store_, their columns renumbered
  // (their numbers do not change: eliminating a top row never touched them,
  // since a row's structure lies on its ancestors, all in the top). The
  // top's rows become empty; their numbers are garbage until compact().
  const int n = size();
  const int nn = static_cast<int>(kept.size());
  const int nt = static_cast<int>(order.size());
  const std::vector<int>& np = new_pos;
  std::vector<RowRef> refs(n);
  std::vector<std::array<double, kMaxDim>> y(n);
  std::vector<int> dims(n), parent(n, -1);
  std::vector<double> flops(n, 0.0);
  std::vector<std::pair<int, int>> blocks;
  total_flops_ = 0;
  for (int k = 0; k < nn; ++k) {
    const int p = kept[k];
    const RowRef& r = refs_[p];
    int* ints = store_.ints.data() + r.ints;
    blocks.clear();
    for (int j = 0; j < r.ncols; ++j) blocks.push_back({np[ints[j]], ints[r.ncols + j]});
    // An empty row (a variable no factor reaches yet) has no diagonal block.
    if (r.ncols > 1) std::sort(blocks.begin() + 1, blocks.end());
    for (int j = 0; j < r.ncols; ++j) {
      ints[j] = blocks[j].first;
      ints[r.ncols + j] = blocks[j].second;
    }
    refs[k] = r;
    y[k] = y_[p];
    dims[k] = dims_[p];
    parent[k] = r.ncols > 1 ? ints[1] : -1;
    flops[k] = row_flops_[p];
    total_flops_ += flops[k];
  }
  for (int k = 0; k < nt; ++k) {
    live_vals_ -= refs_[order[k]].nvals;
    dims[nn + k] = dims_[order[k]];
  }
  refs_ = std::move(refs);
  y_ = std::move(y);
  dims_ = std::move(dims);
  parent_ = std::move(parent);
  row_flops_ = std::move(flops);
  buildColumnLists();
}

void CholeskyFactor::compact() {
  // In place, in storage order: each live row moves down over the garbage
  // before it, so nothing is allocated and no row is overwritten before it
  // has moved.
  std::vector<int> by_offset;
  by_offset.reserve(refs_.size());
  for (int p = 0; p < size(); ++p)
    if (refs_[p].ncols > 0) by_offset.push_back(p);
  std::sort(by_offset.begin(), by_offset.end(),
            [&](int a, int b) { return refs_[a].vals < refs_[b].vals; });
  std::size_t ni = 0, nv = 0;
  for (int p : by_offset) {
    RowRef& r = refs_[p];
    std::copy_n(store_.ints.data() + r.ints, 2 * r.ncols, store_.ints.data() + ni);
    std::copy_n(store_.vals.data() + r.vals, r.nvals, store_.vals.data() + nv);
    r.ints = ni;
    r.vals = nv;
    ni += 2 * static_cast<std::size_t>(r.ncols);
    nv += r.nvals;
  }
  store_.n_ints = ni;
  store_.n_vals = nv;
  // The arrays grow only when full, to at most twice what they held, so in
  // steady growth they stay within 4x the live rows; past 8x (a peak that
  // has passed), they shrink to 2x, room for the next steps' rows.
  if (store_.vals.capacity() > 8 * nv + 8192) {
    store_.ints.release(2 * ni + 1024);
    store_.vals.release(2 * nv + 4096);
  }
}

}  // namespace hamal::aprilsam
