// The parts of AprilSAM's state (backends/aprilsam/linearized_graph.h) keep
// their own invariants: the order's two maps stay inverse through every
// change, L and ||dx|| follow each recorded dx, a reweighting is listed once,
// and a new variable gets a position, a column of R and a dx together.
#include "backends/aprilsam/linearized_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "backends/aprilsam/elimination_order.h"
#include "backends/aprilsam/factor_table.h"
#include "backends/aprilsam/relinearization_set.h"
#include "backends/aprilsam/variable_table.h"
#include "backends/aprilsam/visit_stamps.h"
#include "factors/between_factor.h"

namespace hamal::aprilsam {
namespace {

Values::Entry pose(double x) { return {VariableType::kPose2, {x, 0, 0}}; }

// posOf and varAt are inverse on the positions; fixed variables have none.
void expectInverse(const EliminationOrder& order, int variables) {
  int free = 0;
  for (int v = 0; v < variables; ++v) {
    if (order.posOf(v) < 0) continue;
    ++free;
    EXPECT_EQ(order.varAt(order.posOf(v)), v);
  }
  EXPECT_EQ(free, order.size());
}

TEST(EliminationOrder, ItsTwoMapsStayInverse) {
  EliminationOrder order;
  order.add(0, false);
  order.add(1, true);
  order.add(2, false);
  order.add(3, false);
  EXPECT_EQ(order.posOf(1), -1);
  EXPECT_EQ(order.posOf(3), 2);
  expectInverse(order, 4);
  order.layOut({3, 0, 2});
  EXPECT_EQ(order.varAt(0), 3);
  EXPECT_EQ(order.posOf(2), 2);
  expectInverse(order, 4);
  order.permute({1, 2, 0});  // position p's variable moves to new_pos[p]
  EXPECT_EQ(order.varAt(1), 3);
  EXPECT_EQ(order.varAt(0), 2);
  expectInverse(order, 4);
  order.layOut({2});  // a variable left out of a batch's order has none
  EXPECT_EQ(order.posOf(0), -1);
  expectInverse(order, 4);
}

TEST(RelinearizationSet, FollowsEachRecordedChange) {
  RelinearizationSet set(0.1);
  for (int v = 0; v < 3; ++v) set.add();
  set.record(0, 0.04, 0.2);
  set.record(1, 0.0001, 0.01);
  EXPECT_EQ(set.size(), 1);
  EXPECT_TRUE(set.moved(0));
  EXPECT_NEAR(set.dxNorm(), std::sqrt(0.0401), 1e-15);
  set.record(0, 0.0004, 0.02);  // back under delta_T: out of L
  EXPECT_EQ(set.size(), 0);
  EXPECT_NEAR(set.dxNorm(), std::sqrt(0.0005), 1e-15);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  set.record(2, nan, nan);  // NaN counts as moved, and meets ||dx||'s criterion
  EXPECT_TRUE(set.moved(2));
  EXPECT_FALSE(set.dxNorm() < 10);
  set.clear();
  EXPECT_EQ(set.size(), 0);
  EXPECT_EQ(set.dxNorm(), 0);
  EXPECT_EQ(set.dxSquared(1), 0);
}

TEST(FactorTable, ListsAReweightingOnceAndHoldsTheWeightLinearised) {
  VariableTable vars;
  FactorTable factors;
  for (int i = 0; i < 3; ++i) {
    vars.add(X(i), pose(i), false);
    factors.addVariable();
  }
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  const auto a = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), info);
  const auto b = std::make_shared<BetweenFactor>(X(2), X(1), Pose2(1, 0, 0), info);
  EXPECT_EQ(factors.add(a, vars), 0);
  EXPECT_EQ(factors.add(b, vars), 1);
  EXPECT_EQ(factors.vars(1).size(), 2);
  EXPECT_EQ(factors.vars(1)[0], 2);
  EXPECT_EQ(factors.factorsOf(1).size(), 2u);
  EXPECT_EQ(factors.find(b.get()), 1);
  EXPECT_EQ(factors.find(nullptr), -1);
  factors.setWeight(1, 0.5);
  factors.setWeight(1, 0.25);  // still differs from the held weight: listed once
  ASSERT_EQ(factors.reweighted().size(), 1u);
  EXPECT_EQ(factors.linWeight(1), 1);
  EXPECT_EQ(factors.holdAtWeight(1), 0.25);
  EXPECT_EQ(factors.linWeight(1), 0.25);
  factors.clearReweighted();
  EXPECT_TRUE(factors.reweighted().empty());
}

TEST(VisitStamps, AnItemIsNewOncePerPass) {
  VisitStamps stamps;
  stamps.newPass(3);
  EXPECT_TRUE(stamps.visit(2));
  EXPECT_FALSE(stamps.visit(2));
  stamps.newPass(5);
  EXPECT_TRUE(stamps.visit(2));
  EXPECT_TRUE(stamps.visit(4));
}

TEST(LinearizedGraph, ANewVariableGetsAPositionAColumnAndADxTogether) {
  LinearizedGraph g(1e-12, 0.1);
  g.addVariable(X(0), pose(0), true);
  g.addVariable(X(1), pose(1), false);
  g.addVariable(L(0), {VariableType::kPoint2, {2, 1, 0}}, false);
  EXPECT_EQ(g.order().posOf(0), -1);
  EXPECT_EQ(g.order().size(), 2);
  EXPECT_EQ(g.chol().size(), 2);
  EXPECT_EQ(g.chol().dim(1), 2);
  EXPECT_EQ(g.variables().newestPose(), 1);
  EXPECT_EQ(g.variables().find(L(0)), 2);
  EXPECT_EQ(g.variables().find(L(1)), -1);
  // The estimate is the table's own: a retraction shows in it.
  const double dx[2] = {0.5, -0.25};
  double sq = 0, inf = 0;
  g.variables().retract(2, dx, &sq, &inf);
  EXPECT_EQ(g.variables().estimate().entry(L(0)).data[0], 2.5);
  EXPECT_EQ(sq, 0.3125);
  EXPECT_EQ(inf, 0.5);
  g.variables().resetEstimate(2);
  EXPECT_EQ(g.variables().estimate().entry(L(0)).data[1], 1);
}

}  // namespace
}  // namespace hamal::aprilsam
