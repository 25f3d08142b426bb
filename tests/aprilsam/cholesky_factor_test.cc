// Tests of R's bookkeeping (cholesky_factor.h, thesis sec. 3.4.1): after
// batches and incremental updates the rows referencing each column are
// those whose structure holds it, the flop count is the sum over the rows,
// and compacting the row store drops the replaced rows only.
#include "backends/aprilsam/cholesky_factor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "tests/aprilsam/dense_factor_check.h"

namespace hamal::aprilsam {
namespace {

using testing::denseR;
using testing::FactorUnderTest;
using testing::RandomFactor;

// A random factor after a batch and `steps` updates by either algorithm.
void buildRandomFactor(std::mt19937& rng, int steps, FactorUnderTest* f) {
  std::vector<int> dims;
  for (int p = 0; p < 20; ++p) dims.push_back(p % 3 == 2 ? 2 : 3);
  f->reset(dims);
  BlockNormalEquations neq;
  neq.clear(20);
  for (const RandomFactor& x : testing::randomChain(rng, dims)) testing::addTo(&neq, x);
  ASSERT_TRUE(f->refactorRows(neq, true).ok);
  std::uniform_int_distribution<int> pick(0, 19);
  for (int step = 0; step < steps; ++step) {
    const RandomFactor x = testing::randomFactor(rng, dims, {pick(rng), pick(rng)}, 3);
    if (step % 2) {
      neq.clear(20);
      testing::addTo(&neq, x);
      ASSERT_TRUE(f->refactorRows(neq, false).ok);
    } else {
      JacobianRows rows;
      rows.clear();
      testing::addTo(&rows, x);
      ASSERT_TRUE(f->rank.addRows(f->r, f->aff, rows).ok);
    }
  }
}

TEST(CholeskyFactor, ColumnListsAndFlopsFollowTheRows) {
  std::mt19937 rng(31);
  FactorUnderTest f;
  buildRandomFactor(rng, 25, &f);
  const CholeskyFactor& r = f.r;
  double flops = 0;
  for (int q = 0; q < r.size(); ++q) {
    std::multiset<int> listed, expected;
    r.forEachRowReferencing(q, [&](int p) { listed.insert(p); });
    for (int p = 0; p < r.size(); ++p) {
      const FactorRow row = r.row(p);
      if (std::find(row.cols.begin() + (row.cols.empty() ? 0 : 1), row.cols.end(), q) !=
          row.cols.end())
        expected.insert(p);
    }
    EXPECT_EQ(listed, expected) << "column " << q;
    flops += CholeskyFactor::rowFlops(r.row(q).width, r.dim(q));
  }
  EXPECT_DOUBLE_EQ(r.totalFlops(), flops);
}

TEST(CholeskyFactor, CompactDropsOnlyTheReplacedRows) {
  std::mt19937 rng(37);
  FactorUnderTest f;
  buildRandomFactor(rng, 12, &f);
  ASSERT_GT(f.r.store().n_vals, f.r.storedValues());  // updates left garbage
  const Eigen::MatrixXd before = denseR(f.r);
  const Eigen::VectorXd y_before = testing::denseY(f.r);
  f.r.compact();
  EXPECT_EQ(f.r.store().n_vals, f.r.storedValues());
  EXPECT_EQ(denseR(f.r), before);
  EXPECT_EQ(testing::denseY(f.r), y_before);
}

}  // namespace
}  // namespace hamal::aprilsam
