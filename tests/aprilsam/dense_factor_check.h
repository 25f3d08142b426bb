// Random block systems for the tests of R's algorithms (cholesky_factor.h,
// left_looking_factorization.h, householder_rank_update.h,
// top_reordering.h), and their dense from-scratch factorisation: the
// upper Cholesky factor of A = sum J^T J and y = R^-T b, b = -sum J^T r,
// computed by Eigen, independent of the block code under test.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/cholesky_factor.h"
#include "backends/aprilsam/householder_rank_update.h"
#include "backends/aprilsam/jacobian_rows.h"
#include "backends/aprilsam/left_looking_factorization.h"
#include "core/linearization.h"

namespace hamal::aprilsam::testing {

// One random factor: 1 to 3 rows (or `rows`) over the positions `pos`.
struct RandomFactor {
  std::vector<int> pos;
  std::vector<int> dims;
  Linearization lin;
};

inline Eigen::MatrixXd standardNormal(std::mt19937& rng, int r, int c) {
  std::normal_distribution<double> n01;
  Eigen::MatrixXd m(r, c);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) m(i, j) = n01(rng);
  return m;
}

inline RandomFactor randomFactor(std::mt19937& rng, const std::vector<int>& dims,
                                 std::vector<int> pos, int rows) {
  std::sort(pos.begin(), pos.end());
  pos.erase(std::unique(pos.begin(), pos.end()), pos.end());
  RandomFactor f;
  f.pos = pos;
  f.lin.residual = standardNormal(rng, rows, 1);
  for (int p : pos) {
    f.dims.push_back(dims[p]);
    f.lin.jacobians.push_back(standardNormal(rng, rows, dims[p]));
  }
  return f;
}

// A chain over `dims` with a prior on position 0 (every variable
// determined), the poses' and landmarks' blocks full rank.
inline std::vector<RandomFactor> randomChain(std::mt19937& rng, const std::vector<int>& dims) {
  std::vector<RandomFactor> fs;
  fs.push_back(randomFactor(rng, dims, {0}, 3));
  fs.back().lin.jacobians[0] += 3 * Eigen::MatrixXd::Identity(3, dims[0]);
  for (int p = 0; p + 1 < static_cast<int>(dims.size()); ++p)
    fs.push_back(randomFactor(rng, dims, {p, p + 1}, 3));
  return fs;
}

inline void addTo(BlockNormalEquations* neq, const RandomFactor& f) {
  neq->add(f.lin, f.pos.data(), f.dims.data());
}
inline void addTo(JacobianRows* rows, const RandomFactor& f) {
  rows->add(f.lin, f.pos.data(), f.dims.data());
}

inline std::vector<int> scalarOffsets(const std::vector<int>& dims) {
  std::vector<int> off(dims.size() + 1, 0);
  for (std::size_t p = 0; p < dims.size(); ++p) off[p + 1] = off[p] + dims[p];
  return off;
}

// A and b of the factors, dense, in the positions' order.
struct DenseSystem {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
};
inline DenseSystem denseSystem(const std::vector<int>& dims, const std::vector<RandomFactor>& fs) {
  const std::vector<int> off = scalarOffsets(dims);
  DenseSystem s{Eigen::MatrixXd::Zero(off.back(), off.back()), Eigen::VectorXd::Zero(off.back())};
  for (const RandomFactor& f : fs) {
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(f.lin.residual.size(), off.back());
    for (std::size_t k = 0; k < f.pos.size(); ++k)
      j.block(0, off[f.pos[k]], j.rows(), f.dims[k]) = f.lin.jacobians[k];
    s.a += j.transpose() * j;
    s.b -= j.transpose() * f.lin.residual;
  }
  return s;
}

// r's R and y as dense matrices.
inline Eigen::MatrixXd denseR(const CholeskyFactor& r) {
  std::vector<int> dims(r.size());
  for (int p = 0; p < r.size(); ++p) dims[p] = r.dim(p);
  const std::vector<int> off = scalarOffsets(dims);
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(off.back(), off.back());
  for (int p = 0; p < r.size(); ++p) {
    const FactorRow row = r.row(p);
    for (std::size_t k = 0; k < row.cols.size(); ++k) {
      const int q = row.cols[k];
      for (int c = 0; c < dims[q]; ++c)
        for (int t = 0; t < dims[p]; ++t)
          m(off[p] + t, off[q] + c) = row.vals[row.offs[k] + t + c * dims[p]];
    }
  }
  return m;
}
inline Eigen::VectorXd denseY(const CholeskyFactor& r) {
  std::vector<int> dims(r.size());
  for (int p = 0; p < r.size(); ++p) dims[p] = r.dim(p);
  const std::vector<int> off = scalarOffsets(dims);
  Eigen::VectorXd y(off.back());
  for (int p = 0; p < r.size(); ++p)
    for (int t = 0; t < dims[p]; ++t) y(off[p] + t) = r.y(p)[t];
  return y;
}

// r holds the Cholesky factor of s (R upper with a positive diagonal, the
// unique one) and y = R^-T b, to a relative 1e-9.
inline void expectFactorOf(const CholeskyFactor& r, const DenseSystem& s, const char* where) {
  const Eigen::LLT<Eigen::MatrixXd> llt(s.a);
  ASSERT_EQ(llt.info(), Eigen::Success) << where;
  const Eigen::MatrixXd u = llt.matrixU();
  const Eigen::VectorXd y = llt.matrixL().solve(s.b);
  const Eigen::MatrixXd got = denseR(r);
  EXPECT_LE((got - u).norm(), 1e-9 * u.norm()) << where << "\nR:\n" << got << "\nexpected:\n" << u;
  EXPECT_LE((denseY(r) - y).norm(), 1e-9 * (1 + y.norm())) << where;
  // The structure R keeps contains the factor's nonzeros and names each
  // row's parent as its first off-diagonal block.
  for (int p = 0; p < r.size(); ++p) {
    const FactorRow row = r.row(p);
    EXPECT_EQ(r.parent(p), row.cols.size() > 1 ? row.cols[1] : -1) << where;
  }
}

// R with the two update algorithms, driven as IncrementalCholesky drives
// them, so that each algorithm's test calls it directly.
struct FactorUnderTest {
  CholeskyFactor r;
  AffectedRows aff;
  LeftLookingFactorization refactor;
  HouseholderRankUpdate rank;

  void reset(const std::vector<int>& dims) {
    r.reset(dims);
    aff.positions.clear();
    aff.index.assign(dims.size(), -1);
    refactor.resize(static_cast<int>(dims.size()));
    rank.resize(static_cast<int>(dims.size()));
  }
  void append(int dim) {
    r.append(dim);
    aff.index.push_back(-1);
    refactor.append();
    rank.append();
  }
  // A batch (every position) or the update of S = a_new.touched() and its
  // ancestors, by the left-looking factorisation.
  FactorUpdateOutcome refactorRows(const BlockNormalEquations& a_new, bool all) {
    const bool in_place = all && r.empty();
    aff.positions.clear();
    if (all)
      for (int p = 0; p < r.size(); ++p) aff.positions.push_back(p);
    else
      for (int s : a_new.touched()) aff.addPathToRoot(r, s);
    aff.indexPositions();
    return refactor.factor(r, aff, a_new, in_place);
  }
};

}  // namespace hamal::aprilsam::testing
