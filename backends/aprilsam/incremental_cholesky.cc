// IncrementalCholesky: see incremental_cholesky.h (thesis sec. 3.4.1-3.4.2,
// eq. 3.14 and 3.19).
#include "backends/aprilsam/incremental_cholesky.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>
#include <utility>

#include "backends/aprilsam/dense_blocks.h"

namespace hamal::aprilsam {

void IncrementalCholesky::reset(const std::vector<int>& dims) {
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
  aff_.clear();
  local_.assign(n, -1);
  head_old_.assign(n, -1);
  head_new_.assign(n, -1);
  slot_.assign(n, -1);
}

void IncrementalCholesky::append(int dim) {
  dims_.push_back(dim);
  refs_.emplace_back();
  parent_.push_back(-1);
  y_.push_back({});
  col_ptr_.push_back(col_ptr_.back());
  col_extra_.emplace_back();
  row_flops_.push_back(0);
  columns_total_ += dim;
  local_.push_back(-1);
  head_old_.push_back(-1);
  head_new_.push_back(-1);
  slot_.push_back(-1);
}

double IncrementalCholesky::rowFlops(int width, int dim) const {
  // The scalar columns of L (rows of R) in this block row hold width,
  // width-1, ... nonzeros (diagonal included). choleskyFlops' sum, in its
  // order, without building the vector of counts for every row.
  double flops = 0;
  for (int t = 0; t < dim; ++t) {
    const long c = width - t;
    flops += static_cast<double>(c) * static_cast<double>(c);
  }
  return flops;
}

// update()'s and addRows()' steps are inline (each is called from one
// place): out of line, in a shared library, every call would go through the
// PLT and cost the hot loops their registers.
IncrementalCholesky::Outcome IncrementalCholesky::update(const BlockNormalEquations& a_new,
                                                         bool all) {
  // A batch after reset() reads no old row, so it writes R's rows in place
  // instead of into work rows that commit() would copy.
  const bool in_place = all && empty_;
  collectAffected(a_new, all);
  return factorAffected(a_new, in_place);
}

inline IncrementalCholesky::Outcome IncrementalCholesky::factorAffected(
    const BlockNormalEquations& a_new, bool in_place) {
  Outcome out;
  RowStore& out_store = in_place ? store_ : work_;
  const int m = static_cast<int>(aff_.size());
  formRightHandSide(a_new);
  // Kept rows below a re-eliminated top (reorderTop) take their share out
  // of the top's right side: c_T -= R_NT^T y_N.
  for (std::size_t e = 0; e < ext_rows_.size(); ++e) {
    const int p = ext_rows_[e];
    const Row r = row(p);
    for (std::size_t k = ptr_ext_[e]; k < r.cols.size(); ++k) {
      const int q = r.cols[k];
      subAtx(c_[local_[q]].data(), r.vals.data() + r.offs[k], y_[p].data(), dims_[p], dims_[q]);
    }
  }
  fileOldRows(in_place);
  // A batch's rows are R's: index i in aff_ is position i.
  RowRef* out_refs = in_place ? refs_.data() : work_refs_.data();

  double diag_scale[kMaxDim];
  for (int i = 0; i < m; ++i) {
    const int p = aff_[i];
    const int dp = dims_[p];
    // W_p = (R_aff^T R_aff + A_new)_p, the right side of eq. 3.14, minus
    // what the rows already refactored eliminate (left-looking).
    w_cols_.clear();
    w_size_ = 0;
    wblock(p, p);  // the diagonal first, even when nothing lands on it
    if (a_new.hasRow(p))
      for (const auto& b : a_new.row(p))
        addTo(wblock(p, b.col), a_new.values() + b.offset, dp * dims_[b.col]);
    addWaitingRows(
        p, 1.0, store_, [this](int j) -> const RowRef& { return refs_[aff_[j]]; }, aff_.data(),
        head_old_, next_old_, ptr_old_);
    for (int t = 0; t < dp; ++t) diag_scale[t] = w_vals_[t * (dp + 1)];
    if (!ext_rows_.empty() && head_ext_[p] >= 0)
      addWaitingRows(
          p, -1.0, store_, [this](int j) -> const RowRef& { return refs_[ext_rows_[j]]; },
          ext_rows_.data(), head_ext_, next_ext_, ptr_ext_);
    addWaitingRows(
        p, -1.0, out_store, [out_refs](int j) -> const RowRef& { return out_refs[j]; }, aff_.data(),
        head_new_, next_new_, ptr_new_);

    if (!factorRow(i, diag_scale, out_store, &out_refs[i])) {
      out.ok = false;
      out.failed_position = p;
      if (in_place) {  // R as it was: empty
        store_.clear();
        std::fill(refs_.begin(), refs_.end(), RowRef());
      }
      for (int a : aff_) head_old_[a] = head_new_[a] = -1;
      if (!ext_rows_.empty()) std::fill(head_ext_.begin(), head_ext_.end(), -1);
      ext_rows_.clear();
      for (int q : w_cols_) slot_[q] = -1;
      w_cols_.clear();
      forgetAffected();
      aff_.clear();
      return out;
    }
    out.columns_recomputed += dp;
  }
  ext_rows_.clear();
  commit(&out, in_place ? NewRows::kInPlace : NewRows::kWork);
  return out;
}

inline void IncrementalCholesky::collectAffected(const BlockNormalEquations& a_new, bool all) {
  // aff = S and its elimination-tree ancestors (figs. 3.5, 3.6).
  aff_.clear();
  if (all) {
    aff_.resize(size());
    std::iota(aff_.begin(), aff_.end(), 0);
  } else {
    for (int s : a_new.touched()) addPathToRoot(s);
  }
  indexAffected();
}

inline void IncrementalCholesky::formRightHandSide(const BlockNormalEquations& a_new) {
  // Right side of eq. 3.19: c = R_aff^T y_aff + b_new. Rows in aff only
  // reference columns in aff (their structure lies on their ancestors).
  const int m = static_cast<int>(aff_.size());
  c_.assign(m, {});
  for (int i = 0; i < m; ++i) {
    const int p = aff_[i];
    const Row r = row(p);
    for (std::size_t k = 0; k < r.cols.size(); ++k) {
      const int q = r.cols[k];
      addAtx(c_[local_[q]].data(), r.vals.data() + r.offs[k], y_[p].data(), dims_[p], dims_[q]);
    }
  }
  for (int s : a_new.touched()) {
    const double* b = a_new.rhs(s);
    for (int t = 0; t < dims_[s]; ++t) c_[local_[s]][t] += b[t];
  }
}

inline void IncrementalCholesky::fileOldRows(bool in_place) {
  // Old rows wait in the list of the column they contribute to next; the
  // new ones will, as they are made.
  const int m = static_cast<int>(aff_.size());
  next_old_.assign(m, -1);
  ptr_old_.assign(m, 0);
  next_new_.assign(m, -1);
  ptr_new_.assign(m, 0);
  for (int i = m - 1; i >= 0; --i) {
    const int p = aff_[i];
    if (refs_[p].ncols == 0) continue;
    next_old_[i] = head_old_[p];
    head_old_[p] = i;
  }
  if (!in_place) {
    work_.clear();
    if (static_cast<int>(work_refs_.size()) < m) work_refs_.resize(m);
  }
}

// Creating a block is the rare path of wblock(): kept out of line.
int IncrementalCholesky::newWBlock(int p, int q) {
  const int off = w_size_;
  slot_[q] = off;
  w_cols_.push_back(q);
  const int sz = dims_[p] * dims_[q];
  w_size_ += sz;
  if (w_size_ > static_cast<int>(w_vals_.size()))
    w_vals_.resize(std::max<std::size_t>(w_size_, 2 * w_vals_.size()));
  std::fill_n(w_vals_.data() + off, sz, 0.0);
  return off;
}

// The rows of one kind waiting at p (old rows of R with sign +1, rows
// already refactored with sign -1) add sign x (their block p)^T (their
// blocks from p on) to W_p, and each moves on to the list of its next
// column. `ref_of(j)` is row j's place in `store`. Both kinds run this one
// loop; the lists are walked in the order rows were filed.
template <typename RefOf>
inline void IncrementalCholesky::addWaitingRows(int p, double sign, const RowStore& store,
                                                RefOf ref_of, const int* pos_of,
                                                std::vector<int>& head, std::vector<int>& next_of,
                                                std::vector<int>& ptr) {
  const int dp = dims_[p];
  for (int j = head[p]; j >= 0;) {
    const int next = next_of[j];
    if (next >= 0) {  // the next row is cold: start its loads now
      const RowRef& rn = ref_of(next);
      const int* ints = store.ints.data() + rn.ints;
      const int kn = ptr[next];
      __builtin_prefetch(store.vals.data() + rn.vals + ints[rn.ncols + kn]);
      __builtin_prefetch(ints + kn);
    }
    const Row r = store.view(ref_of(j));
    const int dr = dims_[pos_of[j]];
    const int k = ptr[j];
    const double* rp = r.vals.data() + r.offs[k];
    // r.cols[k] == p: only the diagonal block's upper triangle is read.
    addAtAUpper(w_vals_.data(), rp, dr, dp, sign);
    if (dr == 3 && dp == 3) {  // a pose's row reaching a pose: the common case
      double at[9];
      for (int i = 0; i < 3; ++i)
        for (int t = 0; t < 3; ++t) at[i + t * 3] = rp[t + i * 3];
      for (std::size_t k2 = k + 1; k2 < r.cols.size(); ++k2) {
        const int q = r.cols[k2];
        double* w = wblock(p, q);
        const double* b = r.vals.data() + r.offs[k2];
        if (dims_[q] == 3)
          sign < 0 ? addAtBPose<3, true>(w, at, b) : addAtBPose<3, false>(w, at, b);
        else
          addAtB(w, rp, b, dr, dp, dims_[q], sign);
      }
    } else {
      for (std::size_t k2 = k + 1; k2 < r.cols.size(); ++k2) {
        const int q = r.cols[k2];
        addAtB(wblock(p, q), rp, r.vals.data() + r.offs[k2], dr, dp, dims_[q], sign);
      }
    }
    if (k + 1 < static_cast<int>(r.cols.size())) {
      ptr[j] = k + 1;
      const int q = r.cols[k + 1];
      next_of[j] = head[q];
      head[q] = j;
    }
    j = next;
  }
  head[p] = -1;
}

inline bool IncrementalCholesky::factorRow(int i, const double* diag_scale, RowStore& store,
                                           RowRef* nr) {
  // R~_pp = chol(W_pp), R~_pq = R~_pp^{-T} W_pq, written as row i of the
  // update in `store`, its blocks in increasing column.
  const int p = aff_[i];
  const int dp = dims_[p];
  const int nc = static_cast<int>(w_cols_.size());
  // The columns are distinct positions: sort them by value and find each
  // block through slot_ (still set), rather than sorting by indirection.
  order_.assign(w_cols_.begin(), w_cols_.end());
  std::sort(order_.begin(), order_.end());
  *nr = store.add(nc, w_size_, 0);
  int* ncols = store.ints.data() + nr->ints;
  int* noffs = ncols + nc;
  double* nvals = store.vals.data() + nr->vals;
  int off = 0, width = 0;
  for (int k = 0; k < nc; ++k) {
    const int q = order_[k];
    ncols[k] = q;
    noffs[k] = off;
    const int sz = dp * dims_[q];
    const double* src = w_vals_.data() + slot_[q];
    double* dst = nvals + off;
    if (sz == 9)
      std::copy(src, src + 9, dst);
    else
      std::copy(src, src + sz, dst);
    off += sz;
    width += dims_[q];
  }
  nr->width = width;
  double* u = nvals;
  if (!choleskyUpper(u, dp, diag_scale)) return false;
  for (int k = 1; k < nc; ++k) solveUtX(u, nvals + noffs[k], dp, dims_[ncols[k]]);
  // y~_p from R~_aff^T y~_aff = c (eq. 3.19), by forward substitution
  // pushed to the right while the new row is still in cache: every row
  // before p has already taken its share out of c_p.
  double* yp = c_[i].data();
  solveUtx(u, yp, dp);
  for (int k = 1; k < nc; ++k) {
    const int q = ncols[k];
    subAtx(c_[local_[q]].data(), nvals + noffs[k], yp, dp, dims_[q]);
  }
  for (int q : w_cols_) slot_[q] = -1;
  w_cols_.clear();
  // The new row waits for its first off-diagonal column.
  if (nc > 1) {
    ptr_new_[i] = 1;
    next_new_[i] = head_new_[ncols[1]];
    head_new_[ncols[1]] = i;
  }
  return true;
}

void IncrementalCholesky::addPathToRoot(int s) {
  for (int p = s; p >= 0 && local_[p] < 0; p = parent_[p]) {
    local_[p] = 0;  // mark
    aff_.push_back(p);
  }
}

void IncrementalCholesky::indexAffected() {
  if (!std::is_sorted(aff_.begin(), aff_.end())) std::sort(aff_.begin(), aff_.end());
  for (int i = 0; i < static_cast<int>(aff_.size()); ++i) local_[aff_[i]] = i;
}

void IncrementalCholesky::forgetAffected() {
  for (int a : aff_) local_[a] = -1;
}

void IncrementalCholesky::commit(Outcome* out, NewRows where) {
  const int m = static_cast<int>(aff_.size());
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
        new_ints += 2 * static_cast<std::size_t>(work_refs_[i].ncols);
        new_vals += work_refs_[i].nvals;
      }
      if (store_.n_vals + new_vals > store_.vals.capacity() ||
          store_.n_ints + new_ints > store_.ints.capacity())
        compact();
    }
    const RowStore& from = where == NewRows::kWork ? work_ : store_;
    for (int i = 0; i < m; ++i) {
      const int p = aff_[i];
      const RowRef& w = work_refs_[i];
      const Row nr = from.view(w);
      {
        // Structures only grow (the symbolic factor of A + A_new contains
        // that of A), so only columns new to the row are recorded.
        const Row old = row(p);
        std::size_t a = 1;
        for (std::size_t k = 1; k < nr.cols.size(); ++k) {
          const int q = nr.cols[k];
          while (a < old.cols.size() && old.cols[a] < q) ++a;
          if (a < old.cols.size() && old.cols[a] == q) continue;
          col_extra_[q].push_back(p);
        }
      }
      live_vals_ += w.nvals - refs_[p].nvals;
      refs_[p] = where == NewRows::kWork ? store_.append(work_, w) : w;
    }
  }
  // A peak that has passed (a top or a batch that needs far fewer numbers
  // than R held) does not keep its memory.
  if (store_.vals.capacity() > 8 * live_vals_ + 8192) compact();
  for (int i = 0; i < m; ++i) {
    const int p = aff_[i];
    const RowRef& r = refs_[p];
    parent_[p] = r.ncols > 1 ? store_.ints[r.ints + 1] : -1;
    for (int t = 0; t < dims_[p]; ++t) y_[p][t] = c_[i][t];
    const double f = rowFlops(r.width, dims_[p]);
    total_flops_ += f - row_flops_[p];
    row_flops_[p] = f;
    out->flops += f;
  }
  forgetAffected();
}

void IncrementalCholesky::buildColumnLists() {
  // CSR in two passes: no allocation per column.
  const int n = size();
  col_ptr_.assign(n + 1, 0);
  for (int p = 0; p < n; ++p) {
    const Row r = row(p);
    for (std::size_t k = 1; k < r.cols.size(); ++k) ++col_ptr_[r.cols[k] + 1];
  }
  for (int q = 0; q < n; ++q) col_ptr_[q + 1] += col_ptr_[q];
  col_idx_.resize(col_ptr_[n]);
  next_old_.assign(col_ptr_.begin(), col_ptr_.end() - 1);  // a cursor per column
  for (int p = 0; p < n; ++p) {
    const Row r = row(p);
    for (std::size_t k = 1; k < r.cols.size(); ++k) col_idx_[next_old_[r.cols[k]]++] = p;
  }
  col_extra_.assign(n, {});
}

std::vector<int> IncrementalCholesky::topOf(const std::vector<int>& path,
                                            const std::vector<int>& relin) const {
  const int n = size();
  std::vector<char> in(n, 0);
  for (int s : path) in[s] = 1;
  for (int q : relin) {
    in[q] = 1;
    forEachRowReferencing(q, [&](int r) { in[r] = 1; });
  }
  // Ancestors have larger positions: one ascending pass closes the set.
  std::vector<int> top;
  for (int p = 0; p < n; ++p) {
    if (!in[p]) continue;
    top.push_back(p);
    if (parent_[p] >= 0) in[parent_[p]] = 1;
  }
  return top;
}

IncrementalCholesky::Outcome IncrementalCholesky::reorderTop(const std::vector<int>& top,
                                                             const std::vector<int>& order,
                                                             const BlockNormalEquations& h,
                                                             std::vector<int>* new_pos) {
  const int n = size();
  const int nt = static_cast<int>(top.size());
  const int nn = n - nt;
  std::vector<int> local(n, -1);  // old position -> index in the top's new order
  for (int k = 0; k < nt; ++k) local[order[k]] = k;
  std::vector<int>& np = *new_pos;
  np.assign(n, -1);
  std::vector<int> kept;
  kept.reserve(nn);
  for (int p = 0; p < n; ++p) {
    if (local[p] >= 0) {
      np[p] = nn + local[p];
    } else {
      np[p] = static_cast<int>(kept.size());
      kept.push_back(p);
    }
  }

  // The kept rows stay where they are in store_, their columns renumbered
  // (their numbers do not change: eliminating a top row never touched them,
  // since a row's structure lies on its ancestors, all in the top). The
  // top's rows become empty; their numbers are garbage until compact().
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

  // Each kept row that reaches the top waits at its first top column, as a
  // row already refactored does: the left-looking loop subtracts its share
  // (R_NT^T R_NT, each untouched subtree's marginal on its separator).
  ext_rows_.clear();
  next_ext_.clear();
  ptr_ext_.clear();
  head_ext_.assign(n, -1);
  for (int k = 0; k < nn; ++k) {
    const Row r = row(k);
    if (r.cols.size() < 2) continue;
    const int j =
        static_cast<int>(std::lower_bound(r.cols.begin() + 1, r.cols.end(), nn) - r.cols.begin());
    if (j >= static_cast<int>(r.cols.size())) continue;
    const int q = r.cols[j];
    ptr_ext_.push_back(j);
    next_ext_.push_back(head_ext_[q]);
    head_ext_[q] = static_cast<int>(ext_rows_.size());
    ext_rows_.push_back(k);
  }
  aff_.resize(nt);
  std::iota(aff_.begin(), aff_.end(), nn);
  indexAffected();
  Outcome out = factorAffected(h, false);
  if (!out.ok) out.failed_position = order[out.failed_position - nn];
  return out;
}

void IncrementalCholesky::compact() {
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

namespace hamal::aprilsam {

// The rank update (see the header): the affected rows in increasing
// position; at row p the pending rows of W whose first block is p meet R_p,
// and dim(p) Householder reflections zero their block p. What is left of
// them continues, merged into one set, to the first block after p (p's new
// parent), so the rows visited are p's ancestors: aff of eq. 3.14.
IncrementalCholesky::Outcome IncrementalCholesky::addRows(const JacobianRows& w) {
  Outcome out;
  aff_.clear();
  for (const JacobianRows::Group& g : w.groups())
    for (int s : g.cols) addPathToRoot(s);
  indexAffected();
  const int m = static_cast<int>(aff_.size());
  filePendingRows(w);
  if (static_cast<int>(work_refs_.size()) < m) work_refs_.resize(m);
  c_.assign(m, {});
  // The new rows go straight to the end of store_ (commit() has nothing to
  // copy); on a failure store_ is cut back to where it ended. The garbage
  // of earlier steps is reclaimed first when it is more than half the live
  // rows and the room left is less than a quarter of them.
  if (mostlyGarbage() && store_.vals.capacity() - store_.n_vals < live_vals_ / 4) compact();
  const std::size_t n_ints = store_.n_ints, n_vals = store_.n_vals;

  for (int i = 0; i < m; ++i) {
    const int p = aff_[i];
    const int dp = dims_[p];
    RowRef& nr = work_refs_[i];
    const int first = head_new_[p];
    head_new_[p] = -1;
    if (first < 0) {  // nothing reaches p (cannot happen for an ancestor; kept exact anyway)
      nr = refs_[p];
      for (int t = 0; t < dp; ++t) c_[i][t] = y_[p][t];
      continue;
    }
    int k_rows = 0;
    const int width = markRowColumns(p, row(p), first, &k_rows);
    store_.reserve(static_cast<int>(w_cols_.size()), dp * width);
    const Row old = row(p);  // after reserve(), which may move store_
    if (!pivotReflections(p, old, first, k_rows, &pivot_)) {
      out.ok = false;
      out.failed_position = p;
      store_.n_ints = n_ints;
      store_.n_vals = n_vals;
      for (int q : w_cols_) slot_[q] = -1;
      w_cols_.clear();
      for (int a : aff_) head_new_[a] = -1;
      forgetAffected();
      aff_.clear();
      return out;
    }
    // The common shapes (a pose, the rows of one to four factors) with the
    // column kernel unrolled; any other through the same code, not unrolled.
    if (dp == 3) {
      switch (k_rows) {
        case 3:
          reflectRest<3, 3>(i, old, first, width, pivot_, &nr);
          break;
        case 6:
          reflectRest<3, 6>(i, old, first, width, pivot_, &nr);
          break;
        case 9:
          reflectRest<3, 9>(i, old, first, width, pivot_, &nr);
          break;
        case 12:
          reflectRest<3, 12>(i, old, first, width, pivot_, &nr);
          break;
        default:
          reflectRest<3, 0>(i, old, first, width, pivot_, &nr);
          break;
      }
    } else {
      reflectRest<0, 0>(i, old, first, width, pivot_, &nr);
    }
    for (int q : w_cols_) slot_[q] = -1;
    w_cols_.clear();
    out.columns_recomputed += dp;
  }
  // out.flops is the refactoring's estimate for the same rows, as update()
  // gives it: the update policy then decides the same way on either path,
  // so factor_update changes the run time, not the run.
  commit(&out, NewRows::kAppended);
  return out;
}

double IncrementalCholesky::addRowsFlops(const JacobianRows& w) {
  // addRows' structure: the rows met are the groups' paths to the root; row
  // p becomes p, its old blocks and the blocks of the pending rows reaching
  // it, and those rows carry all but p on to the first block after p.
  const int n = size();
  if (static_cast<int>(sym_mark_.size()) < n) {
    sym_mark_.resize(n, 0);
    sym_col_mark_.resize(n, 0);
    sym_in_.resize(n);
  }
  ++sym_stamp_;
  sym_aff_.clear();
  for (const JacobianRows::Group& g : w.groups()) {
    for (int s : g.cols)
      for (int p = s; p >= 0 && sym_mark_[p] != sym_stamp_; p = parent_[p]) {
        sym_mark_[p] = sym_stamp_;
        sym_aff_.push_back(p);
      }
    std::vector<int>& in = sym_in_[g.cols.front()];
    in.insert(in.end(), g.cols.begin(), g.cols.end());
  }
  std::sort(sym_aff_.begin(), sym_aff_.end());
  double flops = 0;
  for (int p : sym_aff_) {
    const Row old = row(p);
    ++sym_col_stamp_;
    sym_cols_.clear();
    const auto mark = [&](int q) {
      if (sym_col_mark_[q] == sym_col_stamp_) return;
      sym_col_mark_[q] = sym_col_stamp_;
      sym_cols_.push_back(q);
    };
    mark(p);
    for (int q : old.cols) mark(q);
    const bool reached = !sym_in_[p].empty();
    for (int q : sym_in_[p]) mark(q);
    sym_in_[p].clear();
    int width = 0;
    int next = -1;
    for (int q : sym_cols_) {
      width += dims_[q];
      if (q > p && (next < 0 || q < next)) next = q;
    }
    // A row no pending rows reach is copied as it is.
    flops += rowFlops(reached ? width : old.width, dims_[p]);
    if (reached && next >= 0)
      for (int q : sym_cols_)
        if (q > p) sym_in_[next].push_back(q);
  }
  return flops;
}

inline void IncrementalCholesky::filePendingRows(const JacobianRows& w) {
  // Each factor's rows start as one pending set, filed under its first block.
  const int ng = static_cast<int>(w.groups().size());
  if (static_cast<int>(pending_.size()) < ng) pending_.resize(ng);
  next_new_.assign(ng, -1);
  for (int g = 0; g < ng; ++g) {
    const JacobianRows::Group& in = w.groups()[g];
    PendingRows& pr = pending_[g];
    pr.rows = in.rows;
    pr.width = in.width;
    pr.cols = in.cols;
    // JacobianRows is column-major; a set is kept row-major (reflectRest).
    const double* v = w.values() + in.offset;
    const int ncol = in.width + 1;
    pr.vals.resize(static_cast<std::size_t>(in.rows) * ncol);
    for (int c = 0; c < ncol; ++c)
      for (int r = 0; r < in.rows; ++r) pr.vals[r * ncol + c] = v[r + c * in.rows];
    next_new_[g] = head_new_[in.cols[0]];
    head_new_[in.cols[0]] = g;
  }
}

inline int IncrementalCholesky::markRowColumns(int p, const Row& old, int first, int* k_rows) {
  // The row's new structure: R_p's blocks and the pending rows' blocks, in
  // increasing column, merged from their sorted lists (a sort of the union
  // cost a tenth of the rank update); slot_[q] becomes block q's first
  // scalar column.
  w_cols_.clear();
  if (old.cols.empty())
    w_cols_.push_back(p);
  else
    w_cols_.assign(old.cols.begin(), old.cols.end());
  *k_rows = 0;
  for (int g = first; g >= 0; g = next_new_[g]) {
    const std::vector<int>& cols = pending_[g].cols;
    merged_.clear();
    std::set_union(w_cols_.begin(), w_cols_.end(), cols.begin(), cols.end(),
                   std::back_inserter(merged_));
    w_cols_.swap(merged_);
    *k_rows += pending_[g].rows;
  }
  int width = 0;
  for (int q : w_cols_) {
    slot_[q] = width;
    width += dims_[q];
  }
  return width;
}

inline bool IncrementalCholesky::pivotReflections(int p, const Row& old, int first, int k_rows,
                                                  Pivot* piv) {
  // P = [R_pp; W_p] (ld x dp, column-major): R_p's diagonal block (absent
  // for a new variable's empty row) over each pending set's block p, the
  // first block of every set filed at p.
  const int dp = dims_[p];
  const int ld = dp + k_rows;
  piv->dp = dp;
  piv->k = k_rows;
  double* mat = w_vals_.data();
  if (static_cast<int>(w_vals_.size()) < ld * dp) {
    w_vals_.resize(std::max<std::size_t>(ld * dp, 2 * w_vals_.size()));
    mat = w_vals_.data();
  }
  std::fill_n(mat, ld * dp, 0.0);
  if (!old.cols.empty()) {
    const double* src = old.vals.data() + old.offs[0];
    for (int c = 0; c < dp; ++c)
      for (int r = 0; r < dp; ++r) mat[r + c * ld] = src[r + c * dp];
  }
  int row0 = dp;
  for (int g = first; g >= 0; g = next_new_[g]) {
    const PendingRows& pr = pending_[g];
    for (int c = 0; c < dp; ++c)
      for (int r = 0; r < pr.rows; ++r) mat[row0 + r + c * ld] = pr.vals[r * (pr.width + 1) + c];
    row0 += pr.rows;
  }
  // The diagonal of R_p^T R_p + W_p^T W_p: the scale of the pivot test,
  // as the refactoring path uses the diagonal before elimination.
  double diag_scale[kMaxDim];
  for (int t = 0; t < dp; ++t) {
    double s = 0;
    for (int r = 0; r < ld; ++r) s += mat[r + t * ld] * mat[r + t * ld];
    diag_scale[t] = s;
  }
  // Householder reflections on rows {t} and the k pending rows: rows
  // t+1..dp-1 of column t are zero in the triangular R_pp and stay so.
  piv->v.assign(static_cast<std::size_t>(k_rows) * dp, 0.0);
  for (int t = 0; t < dp; ++t) {
    double* ct = mat + static_cast<std::size_t>(t) * ld;
    double sigma = 0;
    for (int r = dp; r < ld; ++r) sigma += ct[r] * ct[r];
    piv->skip[t] = sigma == 0;
    piv->tau[t] = 0;
    if (sigma == 0) continue;
    const double x0 = ct[t];
    const double norm = std::sqrt(x0 * x0 + sigma);
    const double beta = x0 <= 0 ? norm : -norm;
    const double v0 = x0 - beta;
    const double tau = (beta - x0) / beta;
    for (int r = dp; r < ld; ++r) ct[r] /= v0;
    ct[t] = beta;
    for (int c = t + 1; c < dp; ++c) {
      double* cc = mat + static_cast<std::size_t>(c) * ld;
      double s = cc[t];
      for (int r = dp; r < ld; ++r) s += ct[r] * cc[r];
      s *= tau;
      cc[t] -= s;
      for (int r = dp; r < ld; ++r) cc[r] -= s * ct[r];
    }
    piv->tau[t] = tau;
    std::copy(ct + dp, ct + ld, piv->v.data() + static_cast<std::size_t>(t) * k_rows);
  }
  // The Cholesky factor has a positive diagonal: rows that came out
  // negative are flipped (reflectRest flips the rest of them), then the
  // pivots are tested as choleskyUpper does.
  piv->block.resize(static_cast<std::size_t>(dp) * dp);
  for (int t = 0; t < dp; ++t) {
    piv->sign[t] = mat[t + static_cast<std::size_t>(t) * ld] < 0 ? -1.0 : 1.0;
    for (int c = 0; c < dp; ++c) piv->block[t + c * dp] = mat[t + static_cast<std::size_t>(c) * ld];
    if (piv->sign[t] < 0)
      for (int c = t; c < dp; ++c) piv->block[t + c * dp] = -piv->block[t + c * dp];
    const double d = piv->block[t + t * dp];
    const double s = d * d;
    if (!(s > 0 && std::isfinite(s) && s > 1e-13 * diag_scale[t])) return false;
  }
  return true;
}

// One block q of reflectRest's gather: the old row's dp x dq block (asrc,
// null when the row does not reach q) into at, and each pending set's rows
// on q (zero where the set does not reach it) into bt, from column j0 of
// the nw. DQ > 0 fixes the block's width so the copies unroll.
template <int DQ>
void IncrementalCholesky::gatherBlock(const double* asrc, double* __restrict at,
                                      double* __restrict bt, int j0, int nw, int dp, int q,
                                      int dq_runtime) {
  const int dq = DQ > 0 ? DQ : dq_runtime;
  for (int c = 0; c < dq; ++c)
    for (int t = 0; t < dp; ++t) at[t * nw + j0 + c] = asrc ? asrc[t + c * dp] : 0.0;
  int row0 = 0;
  for (SetCursor& sc : sets_) {
    const int rows = sc.set->rows;
    double* dst = bt + static_cast<std::size_t>(row0) * nw + j0;
    if (sc.block < static_cast<int>(sc.set->cols.size()) && sc.set->cols[sc.block] == q) {
      const int ld = sc.set->width + 1;
      const double* src = sc.set->vals.data() + sc.column;
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < dq; ++c) dst[r * nw + c] = src[r * ld + c];
      ++sc.block;
      sc.column += dq;
    } else {
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < dq; ++c) dst[r * nw + c] = 0.0;
    }
    row0 += rows;
  }
}

// One function although it is long: the gather, the reflections and the
// scatter share the transposed buffers and the pivot's numbers, and the
// reflection loops are the rank update's inner loop, specialised by DP and
// K; the gather of each block is already its own function (gatherBlock).
template <int DP, int K>
void IncrementalCholesky::reflectRest(int i, const Row& old, int first, int width, const Pivot& piv,
                                      RowRef* nr) {
  // Every column after the pivot block, and the right side last: a = its dp
  // numbers in R_p (or y_p), b = its k numbers in the pending rows (zero
  // where a row or set does not reach the block), reflected by the pivot's
  // reflections in order, a (sign-flipped) into R~_p and b into the carried
  // rows, row-major k x (width - dp + 1).
  //
  // The columns are gathered transposed (row t of a, row r of b, each nw
  // columns long), so that each reflection runs along the columns: its
  // loops are independent per column and vectorise, where one column's k
  // numbers make a short dot product whose additions wait on each other.
  // Every column sees the same operations in the same order as it would
  // alone, so the numbers are the same to the bit. The pending sets are
  // row-major for the same reason: b is gathered from them a block row at
  // a time, and the carried rows are b as it stands.
  const int dp = DP > 0 ? DP : piv.dp;
  const int k = K > 0 ? K : piv.k;
  const int nc = static_cast<int>(w_cols_.size());
  *nr = store_.add(nc, dp * width, width);  // room reserved: `old` stays valid
  int* ncols = store_.ints.data() + nr->ints;
  int* noffs = ncols + nc;
  double* nvals = store_.vals.data() + nr->vals;
  for (int b = 0; b < nc; ++b) {
    ncols[b] = w_cols_[b];
    noffs[b] = dp * slot_[w_cols_[b]];
  }
  std::copy(piv.block.begin(), piv.block.end(), nvals);
  const bool carried = nc > 1;
  const int carry_width = width - dp;
  const int nw = carry_width + 1;
  const std::size_t need = static_cast<std::size_t>(dp) * nw;
  if (rows_t_.size() < need) rows_t_.resize(std::max(need, 2 * rows_t_.size()));
  carry_.resize(static_cast<std::size_t>(k) * nw);
  double* __restrict at = rows_t_.data();  // dp x nw
  double* __restrict bt = carry_.data();   // k x nw

  // The pending sets, and where each stands in its blocks (all start at p).
  sets_.clear();
  for (int g = first; g >= 0; g = next_new_[g]) sets_.push_back({&pending_[g], 1, dp});
  std::size_t ko = 1;  // old row's next block after the diagonal
  for (int blk = 1; blk < nc; ++blk) {
    const int q = w_cols_[blk];
    const int dq = dims_[q];
    const double* asrc = nullptr;
    if (ko < old.cols.size() && old.cols[ko] == q) asrc = old.vals.data() + old.offs[ko++];
    const int j0 = slot_[q] - dp;  // the block's first column among the nw
    if (dq == 3)
      gatherBlock<3>(asrc, at, bt, j0, nw, dp, q);
    else
      gatherBlock<0>(asrc, at, bt, j0, nw, dp, q, dq);
  }
  // The right side: y_p over each set's e (its last column).
  for (int t = 0; t < dp; ++t) at[t * nw + nw - 1] = y_[aff_[i]][t];
  {
    int row0 = 0;
    for (const SetCursor& sc : sets_) {
      const PendingRows& pr = *sc.set;
      const int ld = pr.width + 1;
      for (int r = 0; r < pr.rows; ++r) bt[(row0 + r) * nw + nw - 1] = pr.vals[r * ld + pr.width];
      row0 += pr.rows;
    }
  }

  const double* v = piv.v.data();
  int j = 0;
  if constexpr (DP > 0 && K > 0) {
    // Two columns at a time through all dp reflections, their numbers held
    // in vector registers (Lanes2) from the load to the store. The
    // reflections' numbers are set in both lanes once for all columns, so
    // the loop multiplies by them from memory instead of spreading each
    // scalar anew.
    Lanes2 v2[DP][K], tau2[DP];
    for (int t = 0; t < DP; ++t) {
      tau2[t] = Lanes2{piv.tau[t], piv.tau[t]};
      for (int r = 0; r < K; ++r) v2[t][r] = Lanes2{v[t * K + r], v[t * K + r]};
    }
    for (; j + 2 <= nw; j += 2) {
      Lanes2 ac[DP], bc[K];
      for (int t = 0; t < DP; ++t) ac[t] = loadLanes2(at + t * nw + j);
      for (int r = 0; r < K; ++r) bc[r] = loadLanes2(bt + r * nw + j);
      for (int t = 0; t < DP; ++t) {
        if (piv.skip[t]) continue;
        Lanes2 sc = ac[t];
        for (int r = 0; r < K; ++r) sc += v2[t][r] * bc[r];
        sc *= tau2[t];
        ac[t] -= sc;
        for (int r = 0; r < K; ++r) bc[r] -= sc * v2[t][r];
      }
      for (int t = 0; t < DP; ++t) storeLanes2(at + t * nw + j, ac[t]);
      for (int r = 0; r < K; ++r) storeLanes2(bt + r * nw + j, bc[r]);
    }
  }
  // The remaining columns (all of them for shapes not unrolled), one
  // reflection at a time.
  const int j_rest = j;
  for (int t = 0; t < dp; ++t) {
    if (piv.skip[t]) continue;
    const double* vt = v + t * k;
    const double tau = piv.tau[t];
    double* __restrict a = at + t * nw;
    // kLanes columns at a time, their sums side by side (vector registers).
    constexpr int kLanes = 4;
    for (j = j_rest; j + kLanes <= nw; j += kLanes) {
      double sj[kLanes];
      for (int l = 0; l < kLanes; ++l) sj[l] = a[j + l];
      for (int r = 0; r < k; ++r) {
        const double vr = vt[r];
        const double* b = bt + r * nw + j;
        for (int l = 0; l < kLanes; ++l) sj[l] += vr * b[l];
      }
      for (int l = 0; l < kLanes; ++l) {
        sj[l] *= tau;
        a[j + l] -= sj[l];
      }
      for (int r = 0; r < k; ++r) {
        const double vr = vt[r];
        double* b = bt + r * nw + j;
        for (int l = 0; l < kLanes; ++l) b[l] -= sj[l] * vr;
      }
    }
    for (; j < nw; ++j) {
      double sj = a[j];
      for (int r = 0; r < k; ++r) sj += vt[r] * bt[r * nw + j];
      sj *= tau;
      a[j] -= sj;
      for (int r = 0; r < k; ++r) bt[r * nw + j] -= sj * vt[r];
    }
  }

  for (int j = 0; j + 1 < nw; ++j) {
    double* dst = nvals + static_cast<std::size_t>(dp + j) * dp;
    for (int t = 0; t < dp; ++t) dst[t] = piv.sign[t] * at[t * nw + j];
  }
  for (int t = 0; t < dp; ++t) c_[i][t] = piv.sign[t] * at[t * nw + nw - 1];
  if (!carried) return;

  // The rest of the pending rows, now zero on block p, go on as one set to
  // the row's first block after p (p's new parent).
  PendingRows& pr = pending_[first];
  pr.rows = k;
  pr.width = carry_width;
  pr.cols.assign(w_cols_.begin() + 1, w_cols_.end());
  pr.vals.swap(carry_);
  next_new_[first] = head_new_[pr.cols[0]];
  head_new_[pr.cols[0]] = first;
}

}  // namespace hamal::aprilsam
