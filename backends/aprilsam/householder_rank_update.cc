// HouseholderRankUpdate: see householder_rank_update.h (thesis sec. 3.4.2,
// eq. 3.14 and 3.19 reached by Householder reflections; sec. 2.3.3).
#include "backends/aprilsam/householder_rank_update.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

#include "backends/aprilsam/dense_blocks.h"

namespace hamal::aprilsam {

void HouseholderRankUpdate::resize(int n) {
  head_.assign(n, -1);
  slot_.assign(n, -1);
}

void HouseholderRankUpdate::append() {
  head_.push_back(-1);
  slot_.push_back(-1);
}

// The affected rows in increasing position; at row p the pending rows of W
// whose first block is p meet R_p, and dim(p) Householder reflections zero
// their block p. What is left of them continues, merged into one set, to
// the first block after p (p's new parent), so the rows visited are p's
// ancestors: aff of eq. 3.14. addRows()' steps are inline (each is called
// from one place): out of line, in a shared library, every call would go
// through the PLT and cost the hot loops their registers.
FactorUpdateOutcome HouseholderRankUpdate::addRows(CholeskyFactor& r, AffectedRows& aff,
                                                   const JacobianRows& w) {
  FactorUpdateOutcome out;
  aff.positions.clear();
  for (const JacobianRows::Group& g : w.groups())
    for (int s : g.cols) aff.addPathToRoot(r, s);
  aff.indexPositions();
  const int m = static_cast<int>(aff.positions.size());
  filePendingRows(w);
  if (static_cast<int>(aff.rows.size()) < m) aff.rows.resize(m);
  aff.y.assign(m, {});
  dims_ = r.dims();
  y_ = r.ys();
  store_ = &r.store();
  aff_ = aff.positions.data();
  c_ = aff.y.data();
  FactorRowStore& store = r.store();
  // The new rows go straight to the end of the store (commit() has nothing
  // to copy); on a failure the store is cut back to where it ended. The
  // garbage of earlier steps is reclaimed first when it is more than half
  // the live rows and the room left is less than a quarter of them.
  if (r.mostlyGarbage() && store.vals.capacity() - store.n_vals < r.storedValues() / 4) r.compact();
  const std::size_t n_ints = store.n_ints, n_vals = store.n_vals;

  for (int i = 0; i < m; ++i) {
    const int p = aff_[i];
    const int dp = dims_[p];
    RowRef& nr = aff.rows[i];
    const int first = head_[p];
    head_[p] = -1;
    if (first < 0) {  // nothing reaches p (cannot happen for an ancestor; kept exact anyway)
      nr = r.ref(p);
      for (int t = 0; t < dp; ++t) c_[i][t] = y_[p][t];
      continue;
    }
    int k_rows = 0;
    const int width = markRowColumns(p, r.row(p), first, &k_rows);
    store.reserve(static_cast<int>(w_cols_.size()), dp * width);
    const FactorRow old = r.row(p);  // after reserve(), which may move the store
    if (!pivotReflections(p, old, first, k_rows, &pivot_)) {
      out.ok = false;
      out.failed_position = p;
      store.n_ints = n_ints;
      store.n_vals = n_vals;
      for (int q : w_cols_) slot_[q] = -1;
      w_cols_.clear();
      for (int a : aff.positions) head_[a] = -1;
      aff.forgetIndex();
      aff.positions.clear();
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
  // out.flops is the refactoring's estimate for the same rows, as the
  // left-looking update gives it: the update policy then decides the same
  // way on either path, so factor_update changes the run time, not the run.
  r.commit(aff, CholeskyFactor::NewRows::kAppended, nullptr, &out);
  return out;
}

double HouseholderRankUpdate::predictedFlops(const CholeskyFactor& r, const JacobianRows& w) {
  // addRows' structure: the rows met are the groups' paths to the root; row
  // p becomes p, its old blocks and the blocks of the pending rows reaching
  // it, and those rows carry all but p on to the first block after p.
  const int n = r.size();
  if (static_cast<int>(sym_.mark.size()) < n) {
    sym_.mark.resize(n, 0);
    sym_.col_mark.resize(n, 0);
    sym_.in.resize(n);
  }
  ++sym_.stamp;
  sym_.aff.clear();
  for (const JacobianRows::Group& g : w.groups()) {
    for (int s : g.cols)
      for (int p = s; p >= 0 && sym_.mark[p] != sym_.stamp; p = r.parent(p)) {
        sym_.mark[p] = sym_.stamp;
        sym_.aff.push_back(p);
      }
    std::vector<int>& in = sym_.in[g.cols.front()];
    in.insert(in.end(), g.cols.begin(), g.cols.end());
  }
  std::sort(sym_.aff.begin(), sym_.aff.end());
  const int* dims = r.dims();
  double flops = 0;
  for (int p : sym_.aff) {
    const FactorRow old = r.row(p);
    ++sym_.col_stamp;
    sym_.cols.clear();
    const auto mark = [&](int q) {
      if (sym_.col_mark[q] == sym_.col_stamp) return;
      sym_.col_mark[q] = sym_.col_stamp;
      sym_.cols.push_back(q);
    };
    mark(p);
    for (int q : old.cols) mark(q);
    const bool reached = !sym_.in[p].empty();
    for (int q : sym_.in[p]) mark(q);
    sym_.in[p].clear();
    int width = 0;
    int next = -1;
    for (int q : sym_.cols) {
      width += dims[q];
      if (q > p && (next < 0 || q < next)) next = q;
    }
    // A row no pending rows reach is copied as it is.
    flops += CholeskyFactor::rowFlops(reached ? width : old.width, dims[p]);
    if (reached && next >= 0)
      for (int q : sym_.cols)
        if (q > p) sym_.in[next].push_back(q);
  }
  return flops;
}

inline void HouseholderRankUpdate::filePendingRows(const JacobianRows& w) {
  // Each factor's rows start as one pending set, filed under its first block.
  const int ng = static_cast<int>(w.groups().size());
  if (static_cast<int>(pending_.size()) < ng) pending_.resize(ng);
  next_.assign(ng, -1);
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
    next_[g] = head_[in.cols[0]];
    head_[in.cols[0]] = g;
  }
}

inline int HouseholderRankUpdate::markRowColumns(int p, const FactorRow& old, int first,
                                                 int* k_rows) {
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
  for (int g = first; g >= 0; g = next_[g]) {
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

inline bool HouseholderRankUpdate::pivotReflections(int p, const FactorRow& old, int first,
                                                    int k_rows, Pivot* piv) {
  // P = [R_pp; W_p] (ld x dp, column-major): R_p's diagonal block (absent
  // for a new variable's empty row) over each pending set's block p, the
  // first block of every set filed at p.
  const int dp = dims_[p];
  const int ld = dp + k_rows;
  piv->dp = dp;
  piv->k = k_rows;
  double* mat = piv->mat.data();
  if (static_cast<int>(piv->mat.size()) < ld * dp) {
    piv->mat.resize(std::max<std::size_t>(ld * dp, 2 * piv->mat.size()));
    mat = piv->mat.data();
  }
  std::fill_n(mat, ld * dp, 0.0);
  if (!old.cols.empty()) {
    const double* src = old.vals.data() + old.offs[0];
    for (int c = 0; c < dp; ++c)
      for (int r = 0; r < dp; ++r) mat[r + c * ld] = src[r + c * dp];
  }
  int row0 = dp;
  for (int g = first; g >= 0; g = next_[g]) {
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
// the nw (reflectTransposed). DQ > 0 fixes the block's width so the copies
// unroll.
template <int DQ>
void HouseholderRankUpdate::gatherBlock(const double* asrc, double* __restrict at,
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

// The new row's header and pivot block, the reflections of the other
// columns (reflectInPlace or reflectTransposed), and the carried rows
// filed at p's new parent.
template <int DP, int K>
void HouseholderRankUpdate::reflectRest(int i, const FactorRow& old, int first, int width,
                                        const Pivot& piv, RowRef* nr) {
  // Every column after the pivot block, and the right side last: a = its dp
  // numbers in R_p (or y_p), b = its k numbers in the pending rows (zero
  // where a row or set does not reach the block), reflected by the pivot's
  // reflections in order, a (sign-flipped) into R~_p and b into the carried
  // rows, row-major k x (width - dp + 1).
  //
  // The reflections run along the columns, several at a time: their loops
  // are independent per column and vectorise, where one column's k numbers
  // make a short dot product whose additions wait on each other. Every
  // column sees the same operations in the same order as it would alone,
  // so the numbers are the same to the bit. The pending sets are row-major
  // for the same reason: b is gathered from them a block row at a time
  // (gatherPending, gatherBlock), and the carried rows are b as it stands.
  const int dp = DP > 0 ? DP : piv.dp;
  const int k = K > 0 ? K : piv.k;
  const int nc = static_cast<int>(w_cols_.size());
  *nr = store_->add(nc, dp * width, width);  // room reserved: `old` stays valid
  int* ncols = store_->ints.data() + nr->ints;
  int* noffs = ncols + nc;
  double* nvals = store_->vals.data() + nr->vals;
  for (int b = 0; b < nc; ++b) {
    ncols[b] = w_cols_[b];
    noffs[b] = dp * slot_[w_cols_[b]];
  }
  std::copy(piv.block.begin(), piv.block.end(), nvals);
  const bool carried = nc > 1;
  const int carry_width = width - dp;
  const int nw = carry_width + 1;
  carry_.resize(static_cast<std::size_t>(k) * nw);
  double* __restrict bt = carry_.data();  // k x nw

  // The pending sets, and where each stands in its blocks (all start at p).
  sets_.clear();
  for (int g = first; g >= 0; g = next_[g]) sets_.push_back({&pending_[g], 1, dp});
  if constexpr (DP > 0 && K > 0) {
    reflectInPlace<DP, K>(i, old, nw, piv, nvals, bt);
  } else {
    reflectTransposed(i, old, nw, piv, nvals, bt);
  }
  if (!carried) return;

  // The rest of the pending rows, now zero on block p, go on as one set to
  // the row's first block after p (p's new parent).
  PendingRows& pr = pending_[first];
  pr.rows = k;
  pr.width = carry_width;
  pr.cols.assign(w_cols_.begin() + 1, w_cols_.end());
  pr.vals.swap(carry_);
  next_[first] = head_[pr.cols[0]];
  head_[pr.cols[0]] = first;
}

// The pivot's reflections on the columns of the shapes not unrolled, as
// the header of reflectRest says: gathered transposed (row t of a, row r
// of b, each nw columns long), so that each reflection runs along the
// columns, kLanes at a time, then a scattered into R~_p (sign-flipped).
void HouseholderRankUpdate::reflectTransposed(int i, const FactorRow& old, int nw, const Pivot& piv,
                                              double* nvals, double* __restrict bt) {
  const int dp = piv.dp;
  const int k = piv.k;
  const int nc = static_cast<int>(w_cols_.size());
  const std::size_t need = static_cast<std::size_t>(dp) * nw;
  if (rows_t_.size() < need) rows_t_.resize(std::max(need, 2 * rows_t_.size()));
  double* __restrict at = rows_t_.data();  // dp x nw
  std::size_t ko = 1;                      // old row's next block after the diagonal
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
  gatherRightSide(bt, nw);

  const double* v = piv.v.data();
  for (int t = 0; t < dp; ++t) {
    if (piv.skip[t]) continue;
    const double* vt = v + t * k;
    const double tau = piv.tau[t];
    double* __restrict a = at + t * nw;
    // kLanes columns at a time, their sums side by side (vector registers).
    constexpr int kLanes = 4;
    int j = 0;
    for (; j + kLanes <= nw; j += kLanes) {
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
}

// The pivot's reflections on the columns of the unrolled shapes, read
// where a and b already lie (R_p's column-major blocks, the pending set's
// rows) and written once where R~_p and the carried rows keep them,
// rather than gathered into a transposed copy and scattered back (each
// number read and written twice more, for reflections of a few operations
// each). Two columns at a time through all dp reflections, their numbers
// held in vector registers (Lanes2) from the load to the store; the sign
// flip (by +-1, exact) is done on the store. The reflections' numbers are
// set in both lanes once for all columns, so the loop multiplies by them
// from memory instead of spreading each scalar anew. Each column has the
// transposed path's operations in its order.
template <int DP, int K>
void HouseholderRankUpdate::reflectInPlace(int i, const FactorRow& old, int nw, const Pivot& piv,
                                           double* nvals, double* __restrict bt) {
  // a is read from R_p itself when the row gains no block (its layout is
  // R~_p's), else from a copy of its blocks put in their new places; b
  // from the one pending set when it covers the row (its rows after block
  // p are b's), else from a gather (gatherPending). Either way the
  // reflected numbers are written to R~_p and the carried rows.
  const int nc = static_cast<int>(w_cols_.size());
  const double* a_base = nvals;
  if (static_cast<int>(old.cols.size()) == nc) {
    a_base = old.vals.data();
  } else {
    std::size_t ko = 1;  // old row's next block after the diagonal
    for (int blk = 1; blk < nc; ++blk) {
      const int q = w_cols_[blk];
      const int n = DP * dims_[q];
      double* dst = nvals + static_cast<std::size_t>(DP) * slot_[q];
      if (ko < old.cols.size() && old.cols[ko] == q) {
        const double* asrc = old.vals.data() + old.offs[ko++];
        std::copy(asrc, asrc + n, dst);
      } else {
        std::fill_n(dst, n, 0.0);
      }
    }
  }
  const double* b_in = bt;
  int b_ld = nw;
  if (sets_.size() == 1 && sets_[0].set->cols.size() == static_cast<std::size_t>(nc)) {
    b_in = sets_[0].set->vals.data() + DP;
    b_ld = sets_[0].set->width + 1;
  } else {
    gatherPending(bt, nw, DP);
  }

  // Column j of a: R~_p's column DP + j, the last (nw - 1) y_p in and y~_p
  // out.
  const double* y_in = y_[aff_[i]].data();
  double* y_out = c_[i].data();
  const auto a_in = [&](int j) -> const double* {
    return j + 1 < nw ? a_base + static_cast<std::size_t>(DP + j) * DP : y_in;
  };
  const auto a_out = [&](int j) -> double* {
    return j + 1 < nw ? nvals + static_cast<std::size_t>(DP + j) * DP : y_out;
  };
  const double* v = piv.v.data();
  Lanes2 v2[DP][K], tau2[DP], sign2[DP];
  for (int t = 0; t < DP; ++t) {
    tau2[t] = Lanes2{piv.tau[t], piv.tau[t]};
    sign2[t] = Lanes2{piv.sign[t], piv.sign[t]};
    for (int r = 0; r < K; ++r) v2[t][r] = Lanes2{v[t * K + r], v[t * K + r]};
  }
  int j = 0;
  for (; j + 2 <= nw; j += 2) {
    const double* a0 = a_in(j);
    const double* a1 = a_in(j + 1);
    Lanes2 ac[DP], bc[K];
    for (int t = 0; t < DP; ++t) ac[t] = Lanes2{a0[t], a1[t]};
    for (int r = 0; r < K; ++r) bc[r] = loadLanes2(b_in + r * b_ld + j);
    for (int t = 0; t < DP; ++t) {
      if (piv.skip[t]) continue;
      Lanes2 sc = ac[t];
      for (int r = 0; r < K; ++r) sc += v2[t][r] * bc[r];
      sc *= tau2[t];
      ac[t] -= sc;
      for (int r = 0; r < K; ++r) bc[r] -= sc * v2[t][r];
    }
    double* o0 = a_out(j);
    double* o1 = a_out(j + 1);
    for (int t = 0; t < DP; ++t) {
      const Lanes2 s = sign2[t] * ac[t];
      o0[t] = s[0];
      o1[t] = s[1];
    }
    for (int r = 0; r < K; ++r) storeLanes2(bt + r * nw + j, bc[r]);
  }
  if (j < nw) {  // the last column alone
    double a[DP], b[K];
    const double* in = a_in(j);
    for (int t = 0; t < DP; ++t) a[t] = in[t];
    for (int r = 0; r < K; ++r) b[r] = b_in[r * b_ld + j];
    for (int t = 0; t < DP; ++t) {
      if (piv.skip[t]) continue;
      const double* vt = v + t * K;
      double sj = a[t];
      for (int r = 0; r < K; ++r) sj += vt[r] * b[r];
      sj *= piv.tau[t];
      a[t] -= sj;
      for (int r = 0; r < K; ++r) b[r] -= sj * vt[r];
    }
    double* out = a_out(j);
    for (int t = 0; t < DP; ++t) out[t] = piv.sign[t] * a[t];
    for (int r = 0; r < K; ++r) bt[r * nw + j] = b[r];
  }
}

// b for reflectInPlace: each pending set's rows after block p, e last, at
// their columns among the nw (zero where the set does not reach a block).
// A set over every block of the row (the common case on a path to the
// root: a row's structure holds its children's) is laid out as b already,
// row by row; another is copied a block at a time over zeros.
void HouseholderRankUpdate::gatherPending(double* __restrict bt, int nw, int dp) {
  const std::size_t nc = w_cols_.size();
  int row0 = 0;
  for (const SetCursor& sc : sets_) {
    const PendingRows& pr = *sc.set;
    const int ld = pr.width + 1;
    const double* src = pr.vals.data();
    double* dst = bt + static_cast<std::size_t>(row0) * nw;
    if (pr.cols.size() == nc) {
      for (int r = 0; r < pr.rows; ++r) std::copy_n(src + r * ld + dp, nw, dst + r * nw);
    } else {
      std::fill_n(dst, static_cast<std::size_t>(pr.rows) * nw, 0.0);
      int column = dp;
      for (std::size_t b = 1; b < pr.cols.size(); ++b) {
        const int q = pr.cols[b];
        const int dq = dims_[q];
        const int j0 = slot_[q] - dp;
        for (int r = 0; r < pr.rows; ++r)
          for (int c = 0; c < dq; ++c) dst[r * nw + j0 + c] = src[r * ld + column + c];
        column += dq;
      }
      for (int r = 0; r < pr.rows; ++r) dst[r * nw + nw - 1] = src[r * ld + pr.width];
    }
    row0 += pr.rows;
  }
}

// The right side of the pending rows: each set's e (its last column) into
// bt's last column.
inline void HouseholderRankUpdate::gatherRightSide(double* bt, int nw) {
  int row0 = 0;
  for (const SetCursor& sc : sets_) {
    const PendingRows& pr = *sc.set;
    const int ld = pr.width + 1;
    for (int r = 0; r < pr.rows; ++r) bt[(row0 + r) * nw + nw - 1] = pr.vals[r * ld + pr.width];
    row0 += pr.rows;
  }
}

}  // namespace hamal::aprilsam
