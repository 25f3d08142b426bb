// Dense kernels on the small blocks of AprilSAM's block-sparse R (thesis
// sec. 3.4.1-3.4.2): column-major blocks whose sides are variable dimensions
// (3 for Pose2, 2 for Point2). The hot products are specialised for sides 2
// and 3 so the compiler unrolls them; any other side takes the generic loop,
// so nothing here assumes a dimension.
#pragma once

#include <cmath>

namespace hamal::aprilsam {

namespace detail {
template <int T, int A, int B>
inline void addAtBFixed(double* w, const double* a, const double* b, double sign) {
  for (int j = 0; j < B; ++j)
    for (int i = 0; i < A; ++i) {
      double s = 0;
      for (int t = 0; t < T; ++t) s += a[t + i * T] * b[t + j * T];
      w[i + j * A] += sign * s;
    }
}
template <int T, int A>
inline bool addAtBDispatchB(double* w, const double* a, const double* b, int nb, double sign) {
  if (nb == 3) return addAtBFixed<T, A, 3>(w, a, b, sign), true;
  if (nb == 2) return addAtBFixed<T, A, 2>(w, a, b, sign), true;
  return false;
}
template <int T>
inline bool addAtBDispatchA(double* w, const double* a, const double* b, int na, int nb,
                            double sign) {
  if (na == 3) return addAtBDispatchB<T, 3>(w, a, b, nb, sign);
  if (na == 2) return addAtBDispatchB<T, 2>(w, a, b, nb, sign);
  return false;
}
}  // namespace detail

// w (na x nb) += sign * a^T b, with a (nt x na) and b (nt x nb).
inline void addAtB(double* w, const double* a, const double* b, int nt, int na, int nb,
                   double sign) {
  if (nt == 3 && detail::addAtBDispatchA<3>(w, a, b, na, nb, sign)) return;
  if (nt == 2 && detail::addAtBDispatchA<2>(w, a, b, na, nb, sign)) return;
  for (int j = 0; j < nb; ++j)
    for (int i = 0; i < na; ++i) {
      double s = 0;
      for (int t = 0; t < nt; ++t) s += a[t + i * nt] * b[t + j * nt];
      w[i + j * na] += sign * s;
    }
}

// The pose kernels below keep entries 0 and 1 of a 3-vector in the two
// lanes of a vector (GCC's vector extension: SSE2 on x86-64, plain code
// where there is none) and entry 2 alone. Each lane does the scalar
// kernel's operations in its order, so the results are the same bits.
typedef double Lanes2 __attribute__((vector_size(16)));
inline Lanes2 loadLanes2(const double* p) {
  Lanes2 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline void storeLanes2(double* p, Lanes2 v) { __builtin_memcpy(p, &v, sizeof v); }

// w (3 x B) += a^T b (kSub: -=), with a (3 x 3) given transposed, at[i +
// t * 3] = a[t + i * 3], and b (3 x B): a pose's row reaching a pose, the
// left-looking factorisation's inner product. Each entry is addAtB's sum,
// in the same order from the same zero (w - s and w + (-1) * s round
// alike), and a row's at is made once for all of its blocks.
template <int B, bool kSub>
inline void addAtBPose(double* w, const double* at, const double* b) {
  Lanes2 a01[3];
  for (int t = 0; t < 3; ++t) a01[t] = loadLanes2(at + t * 3);
  for (int j = 0; j < B; ++j) {
    Lanes2 s01 = {0, 0};
    double s2 = 0;
    for (int t = 0; t < 3; ++t) {
      const double bt = b[t + j * 3];
      s01 += a01[t] * bt;
      s2 += at[2 + t * 3] * bt;
    }
    const Lanes2 w01 = loadLanes2(w + j * 3);
    storeLanes2(w + j * 3, kSub ? w01 - s01 : w01 + s01);
    w[2 + j * 3] = kSub ? w[2 + j * 3] - s2 : w[2 + j * 3] + s2;
  }
}

// The upper triangle (i <= j) of w (n x n) += sign * a^T a, a (nt x n): the
// diagonal block of a work row, whose lower triangle choleskyUpper never
// reads. Each entry is addAtB's, operation for operation.
namespace detail {
template <int T, int A>
inline void addAtAUpperFixed(double* w, const double* a, double sign) {
  for (int j = 0; j < A; ++j)
    for (int i = 0; i <= j; ++i) {
      double s = 0;
      for (int t = 0; t < T; ++t) s += a[t + i * T] * a[t + j * T];
      w[i + j * A] += sign * s;
    }
}
}  // namespace detail
inline void addAtAUpper(double* w, const double* a, int nt, int n, double sign) {
  if (nt == 3 && n == 3) return detail::addAtAUpperFixed<3, 3>(w, a, sign);
  if (nt == 3 && n == 2) return detail::addAtAUpperFixed<3, 2>(w, a, sign);
  if (nt == 2 && n == 3) return detail::addAtAUpperFixed<2, 3>(w, a, sign);
  if (nt == 2 && n == 2) return detail::addAtAUpperFixed<2, 2>(w, a, sign);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i <= j; ++i) {
      double s = 0;
      for (int t = 0; t < nt; ++t) s += a[t + i * nt] * a[t + j * nt];
      w[i + j * n] += sign * s;
    }
}

inline void addTo(double* w, const double* a, int n) {
  if (n == 9) {
    for (int i = 0; i < 9; ++i) w[i] += a[i];
    return;
  }
  for (int i = 0; i < n; ++i) w[i] += a[i];
}

// out (nc) += r^T x (sign 1) or -= r^T x (sign -1), r (nr x nc); fixed sides
// so the loops unroll, the same operations in the same order.
namespace detail {
template <int R, int C, bool kAdd>
inline void atxFixed(double* out, const double* r, const double* x) {
  for (int j = 0; j < C; ++j) {
    double s = 0;
    for (int i = 0; i < R; ++i) s += r[i + j * R] * x[i];
    if (kAdd)
      out[j] += s;
    else
      out[j] -= s;
  }
}
template <bool kAdd>
inline void atx(double* out, const double* r, const double* x, int nr, int nc) {
  if (nr == 3 && nc == 3) return atxFixed<3, 3, kAdd>(out, r, x);
  if (nr == 3 && nc == 2) return atxFixed<3, 2, kAdd>(out, r, x);
  if (nr == 2 && nc == 3) return atxFixed<2, 3, kAdd>(out, r, x);
  if (nr == 2 && nc == 2) return atxFixed<2, 2, kAdd>(out, r, x);
  for (int j = 0; j < nc; ++j) {
    double s = 0;
    for (int i = 0; i < nr; ++i) s += r[i + j * nr] * x[i];
    if (kAdd)
      out[j] += s;
    else
      out[j] -= s;
  }
}
}  // namespace detail
inline void addAtx(double* out, const double* r, const double* x, int nr, int nc) {
  detail::atx<true>(out, r, x, nr, nc);
}
inline void subAtx(double* out, const double* r, const double* x, int nr, int nc) {
  detail::atx<false>(out, r, x, nr, nc);
}
// out (nr) -= r x, r (nr x nc): the back-substitution's inner product.
namespace detail {
template <int R, int C>
inline void subAxFixed(double* out, const double* r, const double* x) {
  for (int j = 0; j < C; ++j)
    for (int i = 0; i < R; ++i) out[i] -= r[i + j * R] * x[j];
}
}  // namespace detail
inline void subAx(double* out, const double* r, const double* x, int nr, int nc) {
  if (nr == 3 && nc == 3) return detail::subAxFixed<3, 3>(out, r, x);
  if (nr == 3 && nc == 2) return detail::subAxFixed<3, 2>(out, r, x);
  if (nr == 2 && nc == 3) return detail::subAxFixed<2, 3>(out, r, x);
  if (nr == 2 && nc == 2) return detail::subAxFixed<2, 2>(out, r, x);
  for (int j = 0; j < nc; ++j)
    for (int i = 0; i < nr; ++i) out[i] -= r[i + j * nr] * x[j];
}

// (s01, s2) -= r x for a pose's row, r (3 x nc): the back-substitution's
// inner product on the accumulators a row keeps in registers over its
// blocks, each term subAxFixed's in its order.
inline void subAxPose(Lanes2& s01, double& s2, const double* r, const double* x, int nc) {
  const auto column = [&](int j) __attribute__((always_inline)) {
    s01 -= loadLanes2(r + j * 3) * x[j];
    s2 -= r[2 + j * 3] * x[j];
  };
  if (nc == 3) {
    column(0);
    column(1);
    column(2);
  } else {
    for (int j = 0; j < nc; ++j) column(j);
  }
}

// In place: the upper-triangular u with u^T u = w (w symmetric, d x d, its
// upper triangle read). False when a pivot is not positive, not finite, or
// below 1e-13 of `scale` (the diagonal before elimination): a block that is
// not numerically positive definite.
inline bool choleskyUpper(double* u, int d, const double* scale) {
  for (int j = 0; j < d; ++j) {
    double s = u[j + j * d];
    for (int t = 0; t < j; ++t) s -= u[t + j * d] * u[t + j * d];
    if (!(s > 0) || !std::isfinite(s) || s <= 1e-13 * std::fabs(scale[j])) return false;
    const double r = std::sqrt(s);
    u[j + j * d] = r;
    for (int k = j + 1; k < d; ++k) {
      double v = u[j + k * d];
      for (int t = 0; t < j; ++t) v -= u[t + j * d] * u[t + k * d];
      u[j + k * d] = v / r;
    }
    for (int k = j + 1; k < d; ++k) u[k + j * d] = 0;  // below the diagonal
  }
  return true;
}

// x <- u^{-T} x for a vector x (forward substitution with u^T lower).
namespace detail {
template <int D>
inline void solveUtxFixed(const double* u, double* x) {
  for (int i = 0; i < D; ++i) {
    double s = x[i];
    for (int t = 0; t < i; ++t) s -= u[t + i * D] * x[t];
    x[i] = s / u[i + i * D];
  }
}
}  // namespace detail
inline void solveUtx(const double* u, double* x, int d) {
  if (d == 3) return detail::solveUtxFixed<3>(u, x);
  if (d == 2) return detail::solveUtxFixed<2>(u, x);
  for (int i = 0; i < d; ++i) {
    double s = x[i];
    for (int t = 0; t < i; ++t) s -= u[t + i * d] * x[t];
    x[i] = s / u[i + i * d];
  }
}
// X (d x c) <- u^{-T} X.
inline void solveUtX(const double* u, double* x, int d, int c) {
  if (d == 3) {
    for (int j = 0; j < c; ++j) detail::solveUtxFixed<3>(u, x + j * 3);
    return;
  }
  if (d == 2) {
    for (int j = 0; j < c; ++j) detail::solveUtxFixed<2>(u, x + j * 2);
    return;
  }
  for (int j = 0; j < c; ++j) solveUtx(u, x + j * d, d);
}
// x <- u^{-1} x (backward substitution).
inline void solveUx(const double* u, double* x, int d) {
  for (int i = d - 1; i >= 0; --i) {
    double s = x[i];
    for (int t = i + 1; t < d; ++t) s -= u[i + t * d] * x[t];
    x[i] = s / u[i + i * d];
  }
}

}  // namespace hamal::aprilsam
