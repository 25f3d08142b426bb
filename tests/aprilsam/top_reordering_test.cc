// Tests of the top re-elimination (top_reordering.h): the top is S, the
// rows referencing relinearised variables and all their ancestors, and
// re-eliminating it in a new order from the factors' share on it gives the
// dense from-scratch Cholesky factor of the system in the new order, the
// kept rows untouched; on random systems of Pose2-sized and Point2-sized
// blocks.
#include "backends/aprilsam/top_reordering.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "tests/aprilsam/dense_factor_check.h"

namespace hamal::aprilsam {
namespace {

using testing::denseSystem;
using testing::expectFactorOf;
using testing::FactorUnderTest;
using testing::RandomFactor;

TEST(TopReordering, TopIsTheAffectedRowsClosedUnderParent) {
  std::mt19937 rng(7);
  std::vector<int> dims(30, 3);
  std::vector<RandomFactor> fs = testing::randomChain(rng, dims);
  for (int e = 0; e < 6; ++e) fs.push_back(testing::randomFactor(rng, dims, {3 * e, 29 - e}, 3));
  FactorUnderTest f;
  f.reset(dims);
  BlockNormalEquations neq;
  neq.clear(30);
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  ASSERT_TRUE(f.refactorRows(neq, true).ok);
  const std::vector<int> path{4}, relin{10};
  const std::vector<int> top = topOfFactor(f.r, path, relin);
  ASSERT_TRUE(std::is_sorted(top.begin(), top.end()));
  const std::set<int> in(top.begin(), top.end());
  EXPECT_TRUE(in.count(4));
  EXPECT_TRUE(in.count(10));
  for (int p = 0; p < f.r.size(); ++p) {
    const FactorRow row = f.r.row(p);
    if (std::find(row.cols.begin() + 1, row.cols.end(), 10) != row.cols.end())
      EXPECT_TRUE(in.count(p)) << p << " references 10";
  }
  for (int p : top)
    if (f.r.parent(p) >= 0) EXPECT_TRUE(in.count(f.r.parent(p))) << p;
  EXPECT_LT(top.size(), dims.size());  // the chain's first rows are kept
}

// Re-eliminates random tops in random orders, step after step, and checks
// R against the dense factor of the system in the new order.
TEST(TopReordering, EqualsDenseCholeskyInTheNewOrder) {
  std::mt19937 rng(13);
  std::vector<int> dims;
  for (int p = 0; p < 24; ++p) dims.push_back(p % 4 == 1 ? 2 : 3);
  std::vector<RandomFactor> fs = testing::randomChain(rng, dims);
  for (int e = 0; e < 5; ++e) fs.push_back(testing::randomFactor(rng, dims, {2 * e, 23 - e}, 3));
  FactorUnderTest f;
  f.reset(dims);
  BlockNormalEquations neq;
  neq.clear(24);
  for (const RandomFactor& x : fs) testing::addTo(&neq, x);
  ASSERT_TRUE(f.refactorRows(neq, true).ok);
  std::uniform_int_distribution<int> pick(0, 23);
  for (int step = 0; step < 8; ++step) {
    const std::string where = "step " + std::to_string(step);
    const std::vector<int> top = topOfFactor(f.r, {pick(rng)}, {pick(rng)});
    std::vector<int> order = top;
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<int> new_pos;
    // h: every factor's share on the top, at the new positions (computed
    // from the old ones, which the factor's positions still are).
    const int nt = static_cast<int>(top.size());
    const int nn = static_cast<int>(dims.size()) - nt;
    std::vector<int> np(dims.size(), -1);
    for (int k = 0; k < nt; ++k) np[order[k]] = nn + k;
    BlockNormalEquations h;
    h.clear(static_cast<int>(dims.size()));
    for (const RandomFactor& x : fs) {
      RandomFactor share;
      share.lin.residual = x.lin.residual;
      for (std::size_t k = 0; k < x.pos.size(); ++k) {
        if (np[x.pos[k]] < 0) continue;
        share.pos.push_back(np[x.pos[k]]);
        share.dims.push_back(x.dims[k]);
        share.lin.jacobians.push_back(x.lin.jacobians[k]);
      }
      if (!share.pos.empty()) testing::addTo(&h, share);
    }
    const std::vector<double> kept_row0 = f.r.row(0).vals.vector();
    const FactorUpdateOutcome out =
        reorderFactorTop(f.r, f.aff, f.refactor, top, order, h, &new_pos);
    ASSERT_TRUE(out.ok) << where;
    for (int k = 0; k < nt; ++k) EXPECT_EQ(new_pos[order[k]], nn + k) << where;
    EXPECT_EQ(f.aff.positions.size(), top.size()) << where;
    if (np[0] < 0) EXPECT_EQ(f.r.row(new_pos[0]).vals.vector(), kept_row0) << where;
    // The system in the new order: dims and the factors' positions moved.
    std::vector<int> new_dims(dims.size());
    for (std::size_t p = 0; p < dims.size(); ++p) new_dims[new_pos[p]] = dims[p];
    for (RandomFactor& x : fs) {
      std::vector<int> perm(x.pos.size());
      for (std::size_t k = 0; k < perm.size(); ++k) perm[k] = static_cast<int>(k);
      std::sort(perm.begin(), perm.end(),
                [&](int a, int b) { return new_pos[x.pos[a]] < new_pos[x.pos[b]]; });
      RandomFactor moved;
      moved.lin.residual = x.lin.residual;
      for (int k : perm) {
        moved.pos.push_back(new_pos[x.pos[k]]);
        moved.dims.push_back(x.dims[k]);
        moved.lin.jacobians.push_back(x.lin.jacobians[k]);
      }
      x = moved;
    }
    dims = new_dims;
    expectFactorOf(f.r, denseSystem(dims, fs), where.c_str());
  }
}

}  // namespace
}  // namespace hamal::aprilsam
