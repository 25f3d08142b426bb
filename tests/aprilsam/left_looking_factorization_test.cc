// Tests of the left-looking factorisation (left_looking_factorization.h,
// thesis sec. 3.4.2, eq. 3.14 and 3.19) against a dense from-scratch
// Cholesky factorisation: a batch, then incremental updates that refactor
// only the affected rows (S and its elimination-tree ancestors, figs. 3.5,
// 3.6), on random systems of Pose2-sized and Point2-sized blocks.
#include "backends/aprilsam/left_looking_factorization.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "tests/aprilsam/dense_factor_check.h"

namespace hamal::aprilsam {
namespace {

using testing::denseR;
using testing::DenseSystem;
using testing::denseSystem;
using testing::expectFactorOf;
using testing::FactorUnderTest;
using testing::RandomFactor;

std::vector<int> mixedDims(int n) {
  std::vector<int> dims;
  for (int p = 0; p < n; ++p) dims.push_back(p % 4 == 3 ? 2 : 3);
  return dims;
}

TEST(LeftLookingFactorization, BatchEqualsDenseCholesky) {
  std::mt19937 rng(3);
  const std::vector<int> dims = mixedDims(24);
  std::vector<RandomFactor> fs = testing::randomChain(rng, dims);
  for (int e = 0; e < 10; ++e)  // closures: fill-in far from the diagonal
    fs.push_back(testing::randomFactor(rng, dims, {e, 23 - e / 2}, 3));
  FactorUnderTest f;
  f.reset(dims);
  BlockNormalEquations neq;
  neq.clear(24);
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  const FactorUpdateOutcome out = f.refactorRows(neq, true);
  ASSERT_TRUE(out.ok);
  EXPECT_EQ(out.columns_recomputed, f.r.columnsTotal());
  EXPECT_EQ(f.aff.positions.size(), dims.size());
  expectFactorOf(f.r, denseSystem(dims, fs), "batch");
}

// Every step adds a few random factors; the rows outside the affected set
// keep their numbers, and R is the dense factor of everything added.
TEST(LeftLookingFactorization, UpdatesRefactorOnlyTheAffectedRows) {
  std::mt19937 rng(11);
  std::vector<int> dims = mixedDims(20);
  std::vector<RandomFactor> fs = testing::randomChain(rng, dims);
  FactorUnderTest f;
  f.reset(dims);
  BlockNormalEquations neq;
  neq.clear(20);
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  ASSERT_TRUE(f.refactorRows(neq, true).ok);
  for (int step = 0; step < 30; ++step) {
    const std::string where = "step " + std::to_string(step);
    std::vector<RandomFactor> added;
    if (step % 3 == 0) {  // a new variable, reached by a factor to the last
      dims.push_back(step % 2 ? 2 : 3);
      f.append(dims.back());
      const int n = static_cast<int>(dims.size());
      added.push_back(testing::randomFactor(rng, dims, {n - 2, n - 1}, 3));
    }
    const int n = static_cast<int>(dims.size());
    std::uniform_int_distribution<int> pick(0, n - 1);
    for (int k = 0; k < 1 + step % 2; ++k)
      added.push_back(testing::randomFactor(rng, dims, {pick(rng), pick(rng)}, 1 + step % 3));
    fs.insert(fs.end(), added.begin(), added.end());
    neq.clear(n);
    for (const RandomFactor& x : added) testing::addTo(&neq, x);
    const Eigen::MatrixXd before = denseR(f.r);
    std::vector<bool> was_affected(n, false);
    const FactorUpdateOutcome out = f.refactorRows(neq, false);
    ASSERT_TRUE(out.ok) << where;
    for (int p : f.aff.positions) was_affected[p] = true;
    // S and every ancestor of it are affected.
    for (int s : neq.touched())
      for (int p = s; p >= 0; p = f.r.parent(p)) EXPECT_TRUE(was_affected[p]) << where;
    const std::vector<int> off = testing::scalarOffsets(dims);
    const Eigen::MatrixXd after = denseR(f.r);
    for (int p = 0; p < n; ++p)
      if (!was_affected[p] && off[p + 1] <= before.rows())
        EXPECT_EQ(after.block(off[p], 0, dims[p], before.cols()),
                  before.block(off[p], 0, dims[p], before.cols()))
            << where << " row " << p;
    expectFactorOf(f.r, denseSystem(dims, fs), where.c_str());
  }
}

// A new variable whose information is rank deficient: the update fails at
// it and leaves R and y as they were.
TEST(LeftLookingFactorization, FailureLeavesTheFactorAsItWas) {
  std::mt19937 rng(5);
  std::vector<int> dims = mixedDims(8);
  std::vector<RandomFactor> fs = testing::randomChain(rng, dims);
  FactorUnderTest f;
  f.reset(dims);
  BlockNormalEquations neq;
  neq.clear(8);
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  ASSERT_TRUE(f.refactorRows(neq, true).ok);
  const Eigen::MatrixXd r_before = denseR(f.r);
  const Eigen::VectorXd y_before = testing::denseY(f.r);

  dims.push_back(2);
  f.append(2);
  RandomFactor bad = testing::randomFactor(rng, dims, {7, 8}, 1);  // rank one on position 8
  neq.clear(9);
  testing::addTo(&neq, bad);
  const FactorUpdateOutcome out = f.refactorRows(neq, false);
  EXPECT_FALSE(out.ok);
  EXPECT_EQ(out.failed_position, 8);
  EXPECT_TRUE(f.aff.positions.empty());
  const Eigen::MatrixXd r_after = denseR(f.r);
  EXPECT_EQ(r_after.topLeftCorner(r_before.rows(), r_before.cols()), r_before);
  EXPECT_EQ(r_after.bottomRows(2).norm(), 0.0);
  EXPECT_EQ(testing::denseY(f.r).head(y_before.size()), y_before);

  // The work space is clean: a good update of the same factor succeeds.
  RandomFactor good = testing::randomFactor(rng, dims, {7, 8}, 3);
  neq.clear(9);
  testing::addTo(&neq, good);
  ASSERT_TRUE(f.refactorRows(neq, false).ok);
  fs.push_back(good);
  expectFactorOf(f.r, denseSystem(dims, fs), "after the failure");
}

}  // namespace
}  // namespace hamal::aprilsam
