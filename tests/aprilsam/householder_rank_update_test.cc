// Tests of the Householder rank update (householder_rank_update.h, thesis
// sec. 3.4.2 reached by reflections of the new factors' Jacobian rows)
// against a dense from-scratch Cholesky factorisation of everything added,
// on random systems of Pose2-sized and Point2-sized blocks, with new
// variables appended between steps and factors of 1 to 4 rows; and its
// symbolic flop prediction against the update's own count.
#include "backends/aprilsam/householder_rank_update.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "tests/aprilsam/dense_factor_check.h"

namespace hamal::aprilsam {
namespace {

using testing::denseR;
using testing::denseSystem;
using testing::expectFactorOf;
using testing::FactorUnderTest;
using testing::RandomFactor;

TEST(HouseholderRankUpdate, EqualsDenseCholeskyOfEverythingAdded) {
  std::mt19937 rng(17);
  std::vector<int> dims;
  for (int p = 0; p < 16; ++p) dims.push_back(p % 5 == 2 ? 2 : 3);
  std::vector<RandomFactor> fs = testing::randomChain(rng, dims);
  FactorUnderTest f;
  f.reset(dims);
  BlockNormalEquations neq;
  neq.clear(16);
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  ASSERT_TRUE(f.refactorRows(neq, true).ok);
  for (int step = 0; step < 40; ++step) {
    const std::string where = "step " + std::to_string(step);
    std::vector<RandomFactor> added;
    if (step % 4 == 0) {  // a new variable (its row empty until now)
      dims.push_back(step % 8 ? 3 : 2);
      f.append(dims.back());
      const int n = static_cast<int>(dims.size());
      added.push_back(testing::randomFactor(rng, dims, {n - 2, n - 1}, 3));
    }
    const int n = static_cast<int>(dims.size());
    std::uniform_int_distribution<int> pick(0, n - 1);
    // 1 to 3 factors of 1 to 4 rows, on one to three positions: pending sets
    // of many row counts merging on shared ancestors.
    for (int k = 0; k <= step % 3; ++k) {
      std::vector<int> pos{pick(rng), pick(rng)};
      if (step % 5 == 0) pos.push_back(pick(rng));
      added.push_back(testing::randomFactor(rng, dims, pos, 1 + (step + k) % 4));
    }
    fs.insert(fs.end(), added.begin(), added.end());
    JacobianRows rows;
    rows.clear();
    for (const RandomFactor& x : added) testing::addTo(&rows, x);
    const double predicted = f.rank.predictedFlops(f.r, rows);
    const FactorUpdateOutcome out = f.rank.addRows(f.r, f.aff, rows);
    ASSERT_TRUE(out.ok) << where;
    EXPECT_EQ(out.flops, predicted) << where;
    // The rows updated are the new factors' positions and their ancestors.
    std::vector<bool> affected(n, false);
    for (int p : f.aff.positions) affected[p] = true;
    for (const RandomFactor& x : added)
      for (int s : x.pos)
        for (int p = s; p >= 0; p = f.r.parent(p)) EXPECT_TRUE(affected[p]) << where;
    expectFactorOf(f.r, denseSystem(dims, fs), where.c_str());
  }
  // The rank update's rows and the left-looking factorisation's of the same
  // system are the same factor (one more batch, from scratch).
  FactorUnderTest g;
  g.reset(dims);
  neq.clear(static_cast<int>(dims.size()));
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  ASSERT_TRUE(g.refactorRows(neq, true).ok);
  EXPECT_LE((denseR(g.r) - denseR(f.r)).norm(), 1e-9 * denseR(g.r).norm());
}

// A new variable reached by rank-deficient rows: the update fails there
// and leaves R, y and the store as they were; the next update succeeds.
TEST(HouseholderRankUpdate, FailureLeavesTheFactorAsItWas) {
  std::mt19937 rng(29);
  std::vector<int> dims{3, 3, 2, 3};
  std::vector<RandomFactor> fs = testing::randomChain(rng, dims);
  FactorUnderTest f;
  f.reset(dims);
  BlockNormalEquations neq;
  neq.clear(4);
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  ASSERT_TRUE(f.refactorRows(neq, true).ok);
  const Eigen::MatrixXd r_before = denseR(f.r);
  const Eigen::VectorXd y_before = testing::denseY(f.r);
  const std::size_t stored = f.r.store().n_vals;

  dims.push_back(3);
  f.append(3);
  JacobianRows rows;
  rows.clear();
  testing::addTo(&rows, testing::randomFactor(rng, dims, {1, 4}, 2));  // rank two on position 4
  const FactorUpdateOutcome out = f.rank.addRows(f.r, f.aff, rows);
  EXPECT_FALSE(out.ok);
  EXPECT_EQ(out.failed_position, 4);
  EXPECT_EQ(f.r.store().n_vals, stored);
  const Eigen::MatrixXd r_after = denseR(f.r);
  EXPECT_EQ(r_after.topLeftCorner(r_before.rows(), r_before.cols()), r_before);
  EXPECT_EQ(r_after.bottomRows(3).norm(), 0.0);
  EXPECT_EQ(testing::denseY(f.r).head(y_before.size()), y_before);

  const RandomFactor good = testing::randomFactor(rng, dims, {3, 4}, 3);
  rows.clear();
  testing::addTo(&rows, good);
  ASSERT_TRUE(f.rank.addRows(f.r, f.aff, rows).ok);
  fs.push_back(good);
  expectFactorOf(f.r, denseSystem(dims, fs), "after the failure");
}

}  // namespace
}  // namespace hamal::aprilsam
