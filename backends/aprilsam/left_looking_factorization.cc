// LeftLookingFactorization: see left_looking_factorization.h (thesis sec.
// 3.4.2, eq. 3.14 and 3.19).
#include "backends/aprilsam/left_looking_factorization.h"

#include <algorithm>
#include <numeric>

#include "backends/aprilsam/dense_blocks.h"

namespace hamal::aprilsam {

void LeftLookingFactorization::resize(int n) {
  old_.head.assign(n, -1);
  new_.head.assign(n, -1);
  w_.slot.assign(n, -1);
}

void LeftLookingFactorization::append() {
  old_.head.push_back(-1);
  new_.head.push_back(-1);
  w_.slot.push_back(-1);
}

// factor()'s steps are inline (each is called from one place): out of line,
// in a shared library, every call would go through the PLT and cost the hot
// loops their registers.
FactorUpdateOutcome LeftLookingFactorization::factor(CholeskyFactor& r, AffectedRows& aff,
                                                     const BlockNormalEquations& a_new,
                                                     bool in_place) {
  FactorUpdateOutcome out;
  FactorRowStore& out_store = in_place ? r.store() : work_;
  const int m = static_cast<int>(aff.positions.size());
  aff.y.assign(m, {});
  if (!in_place && static_cast<int>(aff.rows.size()) < m) aff.rows.resize(m);
  dims_ = r.dims();
  refs_ = r.refs();
  aff_ = aff.positions.data();
  local_ = aff.index.data();
  c_ = aff.y.data();
  m_ = m;
  formRightHandSide(r, a_new);
  // Kept rows below a re-eliminated top (factorTop) take their share out
  // of the top's right side: c_T -= R_NT^T y_N.
  for (std::size_t e = 0; e < ext_rows_.size(); ++e) {
    const int p = ext_rows_[e];
    const FactorRow row = r.row(p);
    for (std::size_t k = ext_.ptr[e]; k < row.cols.size(); ++k) {
      const int q = row.cols[k];
      subAtx(c_[local_[q]].data(), row.vals.data() + row.offs[k], r.y(p), dims_[p], dims_[q]);
    }
  }
  fileOldRows(in_place);
  // A batch's rows are R's: index i in aff is position i.
  RowRef* out_refs = in_place ? r.refsInPlace() : aff.rows.data();
  const FactorRowStore& old_store = r.store();

  double diag_scale[kMaxDim];
  for (int i = 0; i < m; ++i) {
    const int p = aff_[i];
    const int dp = dims_[p];
    // W_p = (R_aff^T R_aff + A_new)_p, the right side of eq. 3.14, minus
    // what the rows already refactored eliminate (left-looking).
    w_.cols.clear();
    w_.size = 0;
    wblock(p, p);  // the diagonal first, even when nothing lands on it
    if (a_new.hasRow(p))
      for (const auto& b : a_new.row(p))
        addTo(wblock(p, b.col), a_new.values() + b.offset, dp * dims_[b.col]);
    addWaitingRows(
        p, 1.0, old_store, [this](int j) -> const RowRef& { return refs_[aff_[j]]; }, aff_, old_);
    for (int t = 0; t < dp; ++t) diag_scale[t] = w_.vals[t * (dp + 1)];
    if (!ext_rows_.empty() && ext_.head[p] >= 0)
      addWaitingRows(
          p, -1.0, old_store, [this](int j) -> const RowRef& { return refs_[ext_rows_[j]]; },
          ext_rows_.data(), ext_);
    addWaitingRows(
        p, -1.0, out_store, [out_refs](int j) -> const RowRef& { return out_refs[j]; }, aff_, new_);

    if (!factorRow(i, diag_scale, out_store, &out_refs[i])) {
      out.ok = false;
      out.failed_position = p;
      forgetAfterFailure(r, in_place);
      aff.forgetIndex();
      aff.positions.clear();
      return out;
    }
    out.columns_recomputed += dp;
  }
  ext_rows_.clear();
  r.commit(aff, in_place ? CholeskyFactor::NewRows::kInPlace : CholeskyFactor::NewRows::kWork,
           &work_, &out);
  return out;
}

void LeftLookingFactorization::forgetAfterFailure(CholeskyFactor& r, bool in_place) {
  if (in_place) r.clearRows();  // R as it was: empty
  for (int i = 0; i < m_; ++i) old_.head[aff_[i]] = new_.head[aff_[i]] = -1;
  if (!ext_rows_.empty()) std::fill(ext_.head.begin(), ext_.head.end(), -1);
  ext_rows_.clear();
  for (int q : w_.cols) w_.slot[q] = -1;
  w_.cols.clear();
}

FactorUpdateOutcome LeftLookingFactorization::factorTop(CholeskyFactor& r, AffectedRows& aff,
                                                        const BlockNormalEquations& h, int nn) {
  // Each kept row that reaches the top waits at its first top column, as a
  // row already refactored does: the left-looking loop subtracts its share
  // (R_NT^T R_NT, each untouched subtree's marginal on its separator).
  const int n = r.size();
  ext_rows_.clear();
  ext_.next.clear();
  ext_.ptr.clear();
  ext_.head.assign(n, -1);
  for (int k = 0; k < nn; ++k) {
    const FactorRow row = r.row(k);
    if (row.cols.size() < 2) continue;
    const int j = static_cast<int>(std::lower_bound(row.cols.begin() + 1, row.cols.end(), nn) -
                                   row.cols.begin());
    if (j >= static_cast<int>(row.cols.size())) continue;
    const int q = row.cols[j];
    ext_.ptr.push_back(j);
    ext_.next.push_back(ext_.head[q]);
    ext_.head[q] = static_cast<int>(ext_rows_.size());
    ext_rows_.push_back(k);
  }
  aff.positions.resize(n - nn);
  std::iota(aff.positions.begin(), aff.positions.end(), nn);
  aff.indexPositions();
  return factor(r, aff, h, false);
}

inline void LeftLookingFactorization::formRightHandSide(const CholeskyFactor& r,
                                                        const BlockNormalEquations& a_new) {
  // Right side of eq. 3.19: c = R_aff^T y_aff + b_new. Rows in aff only
  // reference columns in aff (their structure lies on their ancestors).
  const int m = m_;
  for (int i = 0; i < m; ++i) {
    const int p = aff_[i];
    const FactorRow row = r.row(p);
    for (std::size_t k = 0; k < row.cols.size(); ++k) {
      const int q = row.cols[k];
      addAtx(c_[local_[q]].data(), row.vals.data() + row.offs[k], r.y(p), dims_[p], dims_[q]);
    }
  }
  for (int s : a_new.touched()) {
    const double* b = a_new.rhs(s);
    for (int t = 0; t < dims_[s]; ++t) c_[local_[s]][t] += b[t];
  }
}

inline void LeftLookingFactorization::fileOldRows(bool in_place) {
  // Old rows wait in the list of the column they contribute to next; the
  // new ones will, as they are made.
  const int m = m_;
  old_.next.assign(m, -1);
  old_.ptr.assign(m, 0);
  new_.next.assign(m, -1);
  new_.ptr.assign(m, 0);
  for (int i = m - 1; i >= 0; --i) {
    const int p = aff_[i];
    if (refs_[p].ncols == 0) continue;
    old_.next[i] = old_.head[p];
    old_.head[p] = i;
  }
  if (!in_place) work_.clear();
}

// Creating a block is the rare path of wblock(): kept out of line.
int LeftLookingFactorization::newWBlock(int p, int q) {
  const int off = w_.size;
  w_.slot[q] = off;
  w_.cols.push_back(q);
  const int sz = dims_[p] * dims_[q];
  w_.size += sz;
  if (w_.size > static_cast<int>(w_.vals.size()))
    w_.vals.resize(std::max<std::size_t>(w_.size, 2 * w_.vals.size()));
  double* w = w_.vals.data() + off;
  if (sz == 9) {  // a pose's block: zeroed in place, not by a call to memset
    for (int k = 0; k < 8; k += 2) storeLanes2(w + k, Lanes2{0, 0});
    w[8] = 0;
  } else {
    std::fill_n(w, sz, 0.0);
  }
  return off;
}

// The rows of one kind waiting at p (old rows of R with sign +1, rows
// already refactored with sign -1) add sign x (their block p)^T (their
// blocks from p on) to W_p, and each moves on to the list of its next
// column. `ref_of(j)` is row j's place in `store`. Every kind runs this one
// loop; the lists are walked in the order rows were filed.
template <typename RefOf>
inline void LeftLookingFactorization::addWaitingRows(int p, double sign,
                                                     const FactorRowStore& store, RefOf ref_of,
                                                     const int* pos_of, WaitingRows& lists) {
  std::vector<int>& head = lists.head;
  std::vector<int>& next_of = lists.next;
  std::vector<int>& ptr = lists.ptr;
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
    const FactorRow r = store.view(ref_of(j));
    const int dr = dims_[pos_of[j]];
    const int k = ptr[j];
    const double* rp = r.vals.data() + r.offs[k];
    // r.cols[k] == p: only the diagonal block's upper triangle is read.
    addAtAUpper(w_.vals.data(), rp, dr, dp, sign);
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

inline bool LeftLookingFactorization::factorRow(int i, const double* diag_scale,
                                                FactorRowStore& store, RowRef* nr) {
  // R~_pp = chol(W_pp), R~_pq = R~_pp^{-T} W_pq, written as row i of the
  // update in `store`, its blocks in increasing column.
  const int p = aff_[i];
  const int dp = dims_[p];
  const int nc = static_cast<int>(w_.cols.size());
  // The columns are distinct positions: sort them by value and find each
  // block through the slots (still set), rather than sorting by indirection.
  w_.order.assign(w_.cols.begin(), w_.cols.end());
  std::sort(w_.order.begin(), w_.order.end());
  *nr = store.add(nc, w_.size, 0);
  int* ncols = store.ints.data() + nr->ints;
  int* noffs = ncols + nc;
  double* nvals = store.vals.data() + nr->vals;
  int off = 0, width = 0;
  for (int k = 0; k < nc; ++k) {
    const int q = w_.order[k];
    ncols[k] = q;
    noffs[k] = off;
    const int sz = dp * dims_[q];
    const double* src = w_.vals.data() + w_.slot[q];
    double* dst = nvals + off;
    if (sz == 9) {  // a pose's block: copied in place, not by a call to memcpy
      for (int t = 0; t < 8; t += 2) storeLanes2(dst + t, loadLanes2(src + t));
      dst[8] = src[8];
    } else
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
  for (int q : w_.cols) w_.slot[q] = -1;
  w_.cols.clear();
  // The new row waits for its first off-diagonal column.
  if (nc > 1) {
    new_.ptr[i] = 1;
    new_.next[i] = new_.head[ncols[1]];
    new_.head[ncols[1]] = i;
  }
  return true;
}

}  // namespace hamal::aprilsam
