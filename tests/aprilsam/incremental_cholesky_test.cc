// Tests of the incremental Cholesky core (thesis sec. 3.4.1-3.4.2): after
// incremental steps, R, y and dx equal a from-scratch factorisation of the
// accumulated A, b at the same linearisation points and in the same order
// (eq. 3.14, 3.19), on pose graphs and on graphs with Point2 landmarks.
#include "backends/aprilsam/incremental_cholesky.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "backends/aprilsam/block_normal_equations.h"
#include "backends/aprilsam/jacobian_rows.h"
#include "backends/aprilsam/partial_backsolve.h"
#include "tests/aprilsam/aprilsam_test_graphs.h"

namespace hamal::aprilsam {
namespace {

using testing::makeAprilSam;
using testing::randomGraph;
using testing::RandomGraphOptions;

// An r x c matrix of standard normal numbers drawn from rng.
Eigen::MatrixXd randomMatrix(std::mt19937& rng, int r, int c) {
  std::normal_distribution<double> n01;
  Eigen::MatrixXd m(r, c);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) m(i, j) = n01(rng);
  return m;
}

// Factors R and y from scratch at the back-end's linearisation points and
// order, and checks the back-end's R, y and dx against them.
void expectMatchesScratch(const AprilSamBackend& be, const std::string& where) {
  const IncrementalCholesky& inc = be.factor();
  const int n = inc.size();
  BlockNormalEquations neq;
  neq.clear(n);
  Linearization lin;
  for (const FactorPtr& f : be.factors()) {
    std::vector<const double*> params;
    std::vector<int> pos, dims;
    for (const Key& k : f->keys()) {
      params.push_back(be.linearizationPoint(k).data.data());
      pos.push_back(be.positionOf(k));
      dims.push_back(dimension(be.linearizationPoint(k).type));
    }
    ASSERT_TRUE(linearize(*f, params.data(), &lin));
    neq.add(lin, pos.data(), dims.data());
  }
  std::vector<int> dims(n);
  for (int p = 0; p < n; ++p) dims[p] = inc.dim(p);
  IncrementalCholesky scratch;
  scratch.reset(dims);
  ASSERT_TRUE(scratch.update(neq, true).ok) << where;
  PartialBacksolve solve;
  solve.reset(n);
  solve.solve(scratch, true, 0.0);

  double rmax = 0, ymax = 0, dxmax = 0;
  for (int p = 0; p < n; ++p) {
    for (double v : scratch.row(p).vals) rmax = std::max(rmax, std::fabs(v));
    for (int t = 0; t < dims[p]; ++t) {
      ymax = std::max(ymax, std::fabs(scratch.y(p)[t]));
      dxmax = std::max(dxmax, std::fabs(solve.dx(p)[t]));
    }
  }
  for (int p = 0; p < n; ++p) {
    const auto& a = inc.row(p);
    const auto& b = scratch.row(p);
    std::map<int, const double*> inc_blocks;
    for (std::size_t k = 0; k < a.cols.size(); ++k) inc_blocks[a.cols[k]] = &a.vals[a.offs[k]];
    ASSERT_EQ(a.cols.front(), p);
    for (std::size_t k = 0; k < b.cols.size(); ++k) {
      const int q = b.cols[k];
      auto it = inc_blocks.find(q);
      ASSERT_NE(it, inc_blocks.end()) << where << ": row " << p << " lacks column " << q;
      for (int e = 0; e < dims[p] * dims[q]; ++e)
        ASSERT_NEAR(it->second[e], b.vals[b.offs[k] + e], 1e-9 * rmax)
            << where << ": R(" << p << "," << q << ")[" << e << "]";
      inc_blocks.erase(it);
    }
    for (const auto& [q, block] : inc_blocks)  // structure the scratch factor lacks
      for (int e = 0; e < dims[p] * dims[q]; ++e) ASSERT_NEAR(block[e], 0.0, 1e-9 * rmax);
    for (int t = 0; t < dims[p]; ++t) {
      ASSERT_NEAR(inc.y(p)[t], scratch.y(p)[t], 1e-9 * ymax) << where << ": y" << p;
      ASSERT_NEAR(be.backsolve().dx(p)[t], solve.dx(p)[t], 1e-9 * dxmax) << where << ": dx" << p;
    }
  }
}

void runAndCompareOne(const Graph& graph, const std::map<std::string, std::string>& options,
                      int check_every) {
  auto be = makeAprilSam(options);
  ThesisProtocol protocol(graph);
  int incremental = 0;
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const UpdateResult r = be->update(protocol.step(i, be->estimate()));
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    if (r.kind == UpdateKind::kIncremental) ++incremental;
    if (i % check_every == 0 || i + 1 == protocol.size())
      expectMatchesScratch(*be, "step " + std::to_string(i));
    if (::testing::Test::HasFatalFailure()) return;
  }
  EXPECT_GT(incremental, static_cast<int>(protocol.size()) / 2);
}

// Both ways of updating the affected rows: Householder reflections of the
// new Jacobian rows (factor_update=rank, the default) and eq. 3.14's
// refactoring of R_aff^T R_aff + A_new.
void runAndCompare(const Graph& graph, std::map<std::string, std::string> options,
                   int check_every) {
  // dx is compared with the exact solve: no partial-solve tolerance.
  options.emplace("backsolve_tolerance", "0");
  for (const char* update : {"rank", "refactor"}) {
    SCOPED_TRACE(std::string("factor_update=") + update);
    options["factor_update"] = update;
    runAndCompareOne(graph, options, check_every);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

TEST(IncrementalCholesky, PoseGraphMatchesScratchInNaturalOrder) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    RandomGraphOptions o;
    o.seed = seed;
    runAndCompare(randomGraph(o), {{"mode", "incremental"}, {"ordering", "natural"}}, 1);
  }
}

TEST(IncrementalCholesky, MatchesScratchAfterMinHeapBatches) {
  RandomGraphOptions o;
  o.poses = 120;
  o.seed = 7;
  // Periodic batches reorder with the min-heap ordering; the incremental
  // steps in between append to that order.
  runAndCompare(randomGraph(o), {{"mode", "periodic"}, {"period", "17"}}, 1);
}

TEST(IncrementalCholesky, LandmarkGraphMatchesScratch) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    RandomGraphOptions o;
    o.seed = seed;
    o.landmarks = 8;
    runAndCompare(randomGraph(o), {{"mode", "periodic"}, {"period", "23"}, {"ordering", "amd"}}, 1);
  }
}

// reeliminate=top (iSAM2's re-elimination of the top in a new order, from
// the factors and the kept rows' marginals): after each step, R, y and dx
// equal a from-scratch factorisation in the back-end's new order at its
// linearisation points (a kept row linearised where its variables were,
// the top's free variables moved to the estimate).
void runTopAndCompare(const Graph& graph, std::map<std::string, std::string> options,
                      int min_tops) {
  options.emplace("backsolve_tolerance", "0");
  options.emplace("reeliminate", "top");
  for (const char* update : {"rank", "refactor"}) {
    SCOPED_TRACE(std::string("factor_update=") + update);
    options["factor_update"] = update;
    auto be = makeAprilSam(options);
    ThesisProtocol protocol(graph);
    int tops = 0;
    for (std::size_t i = 0; i < protocol.size(); ++i) {
      const UpdateResult r = be->update(protocol.step(i, be->estimate()));
      ASSERT_TRUE(r.status.ok()) << r.status.message;
      const bool top = r.reason.find("top re-eliminated") != std::string::npos;
      tops += top;
      expectMatchesScratch(*be, "step " + std::to_string(i) + " (" + r.reason + ")");
      if (::testing::Test::HasFatalFailure()) return;
    }
    EXPECT_GE(tops, min_tops);
  }
}

TEST(IncrementalCholesky, TopReeliminationMatchesScratch) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    RandomGraphOptions o;
    o.seed = seed;
    o.poses = 150;
    // A batch decision whenever 3 nodes moved by 0.01, every one a top
    // re-elimination however large: many of them, of every size.
    runTopAndCompare(randomGraph(o), {{"nl_t", "3"}, {"delta_t", "0.01"}, {"top_share", "1"}}, 20);
  }
}

TEST(IncrementalCholesky, TopReeliminationMatchesScratchWithLandmarks) {
  for (unsigned seed = 1; seed <= 2; ++seed) {
    RandomGraphOptions o;
    o.seed = seed;
    o.poses = 150;
    o.landmarks = 8;
    runTopAndCompare(randomGraph(o), {{"nl_t", "3"}, {"delta_t", "0.01"}, {"top_share", "1"}}, 20);
  }
}

TEST(IncrementalCholesky, FailedUpdateLeavesFactorUnchanged) {
  IncrementalCholesky chol;
  chol.reset({3, 2});
  BlockNormalEquations neq;
  neq.clear(2);
  Linearization lin;
  lin.residual = Eigen::VectorXd::Ones(3);
  lin.jacobians.resize(2);
  lin.jacobians[0] = Eigen::MatrixXd::Identity(3, 3);
  lin.jacobians[1] = Eigen::MatrixXd::Zero(3, 2);
  lin.jacobians[1](0, 0) = 1;  // rank one on the Point2: not PD
  const int pos[2] = {0, 1}, dims[2] = {3, 2};
  neq.add(lin, pos, dims);
  const auto out = chol.update(neq, true);
  EXPECT_FALSE(out.ok);
  EXPECT_EQ(out.failed_position, 1);
  EXPECT_TRUE(chol.row(0).cols.empty());
  EXPECT_TRUE(chol.row(1).cols.empty());
}

// addRows on a rank-deficient new variable: a failure that names the
// position and leaves R and y as they were.
TEST(IncrementalCholesky, FailedRankUpdateLeavesFactorUnchanged) {
  IncrementalCholesky chol;
  chol.reset({3});
  BlockNormalEquations neq;
  neq.clear(1);
  Linearization prior;
  prior.residual = Eigen::VectorXd::Ones(3);
  prior.jacobians = {Eigen::MatrixXd::Identity(3, 3)};
  const int p0 = 0, d3 = 3;
  neq.add(prior, &p0, &d3);
  ASSERT_TRUE(chol.update(neq, true).ok);
  const std::vector<double> r_before = chol.row(0).vals.vector();
  const std::vector<double> y_before(chol.y(0), chol.y(0) + 3);

  chol.append(2);
  JacobianRows rows;
  Linearization lin;
  lin.residual = Eigen::VectorXd::Ones(3);
  lin.jacobians.resize(2);
  lin.jacobians[0] = Eigen::MatrixXd::Identity(3, 3);
  lin.jacobians[1] = Eigen::MatrixXd::Zero(3, 2);
  lin.jacobians[1](0, 0) = 1;  // rank one on the new Point2: not PD
  const int pos[2] = {0, 1}, dims[2] = {3, 2};
  rows.add(lin, pos, dims);
  const auto out = chol.addRows(rows);
  EXPECT_FALSE(out.ok);
  EXPECT_EQ(out.failed_position, 1);
  EXPECT_EQ(chol.row(0).vals.vector(), r_before);
  EXPECT_EQ(chol.row(0).cols.vector(), std::vector<int>{0});
  EXPECT_EQ(std::vector<double>(chol.y(0), chol.y(0) + 3), y_before);
  EXPECT_TRUE(chol.row(1).cols.empty());
}

// The rank update and the refactoring agree on one step that fills in a
// row of a Point2 and a Pose2 (mixed block sides) far from the root.
TEST(IncrementalCholesky, RankUpdateEqualsRefactorOnMixedBlocks) {
  auto build = [](IncrementalCholesky* chol) {
    chol->reset({3, 2, 3, 3});
    BlockNormalEquations neq;
    neq.clear(4);
    Linearization l;
    std::mt19937 rng(5);
    const auto rnd = [&](int r, int c) { return randomMatrix(rng, r, c); };
    const int dims[4] = {3, 2, 3, 3};
    for (int a = 0; a < 3; ++a) {  // a chain 0-1-2-3 with full-rank blocks
      l.residual = rnd(3, 1);
      l.jacobians = {rnd(3, dims[a]), rnd(3, dims[a + 1])};
      const int pos[2] = {a, a + 1}, d[2] = {dims[a], dims[a + 1]};
      neq.add(l, pos, d);
    }
    l.residual = rnd(3, 1);
    l.jacobians = {rnd(3, 3)};
    const int p0 = 0;
    neq.add(l, &p0, dims);
    ASSERT_TRUE(chol->update(neq, true).ok);
  };
  IncrementalCholesky a, b;
  build(&a);
  build(&b);
  Linearization l;
  l.residual = Eigen::Vector2d(0.3, -1.2);
  l.jacobians = {Eigen::MatrixXd::Random(2, 2), Eigen::MatrixXd::Random(2, 3)};
  const int pos[2] = {1, 3}, dims[2] = {2, 3};
  BlockNormalEquations neq;
  neq.clear(4);
  neq.add(l, pos, dims);
  JacobianRows rows;
  rows.add(l, pos, dims);
  ASSERT_TRUE(a.update(neq, false).ok);
  ASSERT_TRUE(b.addRows(rows).ok);
  EXPECT_EQ(a.affected(), b.affected());
  for (int p = 0; p < 4; ++p) {
    ASSERT_EQ(a.row(p).cols.vector(), b.row(p).cols.vector()) << p;
    for (std::size_t e = 0; e < a.row(p).vals.size(); ++e)
      EXPECT_NEAR(a.row(p).vals[e], b.row(p).vals[e], 1e-12) << p;
    for (int t = 0; t < a.dim(p); ++t) EXPECT_NEAR(a.y(p)[t], b.y(p)[t], 1e-12) << p;
  }
}

// The rank update equals the refactoring over many random steps whose new
// factors have 1 to 3 rows each and meet on shared ancestors, so that the
// pending sets merge into every row count the column kernel unrolls (3, 6,
// 9, 12 rows on a pose) and many it does not (1, 2, 4, 5, 7, ..., more than
// 12; and on landmarks), with variables appended between steps.
TEST(IncrementalCholesky, RankUpdateEqualsRefactorForEveryPendingRowCount) {
  std::mt19937 rng(23);
  const auto rnd = [&](int r, int c) { return randomMatrix(rng, r, c); };
  std::vector<int> dims;
  for (int p = 0; p < 40; ++p) dims.push_back(p % 5 == 4 ? 2 : 3);
  IncrementalCholesky a, b;
  a.reset(dims);
  b.reset(dims);
  {  // a chain with a prior: every variable determined
    BlockNormalEquations neq;
    neq.clear(static_cast<int>(dims.size()));
    Linearization l;
    for (std::size_t p = 0; p + 1 < dims.size(); ++p) {
      l.residual = rnd(3, 1);
      l.jacobians = {rnd(3, dims[p]), rnd(3, dims[p + 1])};
      const int pos[2] = {static_cast<int>(p), static_cast<int>(p + 1)};
      const int d[2] = {dims[p], dims[p + 1]};
      neq.add(l, pos, d);
    }
    l.residual = rnd(3, 1);
    l.jacobians = {rnd(3, 3) + 3 * Eigen::MatrixXd::Identity(3, 3)};
    const int p0 = 0;
    neq.add(l, &p0, dims.data());
    ASSERT_TRUE(a.update(neq, true).ok);
    ASSERT_TRUE(b.update(neq, true).ok);
  }
  // A step's rows -> how often: every path ends at the root (the chain's
  // elimination tree is a path), so the root row meets all of them at once.
  std::map<int, int> seen;
  for (int step = 0; step < 60; ++step) {
    if (step % 4 == 3) {  // a new variable, joined to the last by the step's first factor
      const int d = step % 8 == 7 ? 2 : 3;
      dims.push_back(d);
      a.append(d);
      b.append(d);
    }
    const int n = static_cast<int>(dims.size());
    BlockNormalEquations neq;
    neq.clear(n);
    JacobianRows rows;
    const int factors = 1 + static_cast<int>(rng() % 6);
    int total = 0;
    for (int f = 0; f < factors; ++f) {
      // The first factor ties the newest variable with 3 rows (a new
      // variable needs its full rank); the others have 1 to 3.
      const int r = f == 0 ? 3 : 1 + static_cast<int>(rng() % 3);
      int u = static_cast<int>(rng() % n), v = static_cast<int>(rng() % n);
      if (f == 0) {
        u = n - 2;
        v = n - 1;
      }
      Linearization l;
      l.residual = rnd(r, 1);
      std::vector<int> pos{u}, d{dims[u]};
      if (v != u) {
        pos.push_back(v);
        d.push_back(dims[v]);
      }
      for (std::size_t k = 0; k < pos.size(); ++k) l.jacobians.push_back(rnd(r, d[k]));
      neq.add(l, pos.data(), d.data());
      rows.add(l, pos.data(), d.data());
      total += r;
    }
    ++seen[total];
    const auto ua = a.update(neq, false);
    const auto ub = b.addRows(rows);
    ASSERT_TRUE(ua.ok) << step;
    ASSERT_TRUE(ub.ok) << step;
    ASSERT_EQ(a.affected(), b.affected()) << step;
    for (int p = 0; p < n; ++p) {
      ASSERT_EQ(a.row(p).cols.vector(), b.row(p).cols.vector()) << "step " << step << " row " << p;
      for (std::size_t e = 0; e < a.row(p).vals.size(); ++e)
        ASSERT_NEAR(a.row(p).vals[e], b.row(p).vals[e], 1e-8 * (1 + std::abs(a.row(p).vals[e])))
            << "step " << step << " row " << p;
      for (int t = 0; t < a.dim(p); ++t)
        ASSERT_NEAR(a.y(p)[t], b.y(p)[t], 1e-8 * (1 + std::abs(a.y(p)[t])))
            << "step " << step << " row " << p;
    }
  }
  // The steps' row counts span the unrolled shapes and others on each side.
  for (int k : {3, 6, 9, 12}) EXPECT_GT(seen[k], 0) << k;
  EXPECT_GT(seen.rbegin()->first, 12);
}

// R holds its numbers, not the buffers of the widest rows earlier orderings
// put at each position (per-row buffers had grown to 4x on city10000): after
// many batches in changing orders, and incremental updates that replace
// rows in between, the pooled array stays within what its growth and the
// compaction rule allow: it grows only when full, to twice what it held,
// and past 8x the live numbers it shrinks.
TEST(IncrementalCholesky, BatchesDoNotRatchetRowMemory) {
  RandomGraphOptions o;
  o.poses = 300;
  o.seed = 3;
  const Graph graph = randomGraph(o);
  auto be = makeAprilSam({{"mode", "periodic"}, {"period", "7"}});
  ThesisProtocol protocol(graph);
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    ASSERT_TRUE(be->update(protocol.step(i, be->estimate())).status.ok());
    if (be->batches() < 2) continue;
    const IncrementalCholesky& r = be->factor();
    std::size_t size = 0;
    for (int p = 0; p < r.size(); ++p) size += r.row(p).vals.size();
    ASSERT_EQ(r.storedValues(), size) << "step " << i;
    ASSERT_LE(static_cast<double>(r.valueCapacity()), 8.0 * size + 8192)
        << "step " << i << ", batch " << be->batches();
  }
  EXPECT_GT(be->batches(), 30);
}

// addRowsFlops, from the structure alone, is the flops addRows then reports
// (what batch_first decides on), over rank updates that chain, fill in and
// reach appended variables, on a factor that is not a chain.
TEST(IncrementalCholesky, PredictedRankUpdateFlopsAreTheUpdatesOwn) {
  std::mt19937 rng(11);
  const auto rnd = [&](int r, int c) { return randomMatrix(rng, r, c); };
  std::vector<int> dims;
  for (int p = 0; p < 30; ++p) dims.push_back(p % 3 == 0 ? 2 : 3);
  IncrementalCholesky chol;
  chol.reset(dims);
  BlockNormalEquations neq;
  neq.clear(static_cast<int>(dims.size()));
  Linearization l;
  for (int p = 0; p < static_cast<int>(dims.size()); ++p) {
    // A prior on each block, and a sparse set of links.
    l.residual = rnd(dims[p], 1);
    l.jacobians = {rnd(dims[p], dims[p])};
    neq.add(l, &p, &dims[p]);
    if (p % 4 == 3) {
      const int pos[2] = {p - 3, p}, d[2] = {dims[p - 3], dims[p]};
      l.residual = rnd(2, 1);
      l.jacobians = {rnd(2, d[0]), rnd(2, d[1])};
      neq.add(l, pos, d);
    }
  }
  ASSERT_TRUE(chol.update(neq, true).ok);
  std::uniform_int_distribution<int> coin(0, 3);
  for (int round = 0; round < 40; ++round) {
    JacobianRows rows;
    if (coin(rng) == 0) {  // a new variable with a prior of its own
      dims.push_back(3);
      chol.append(3);
      const int p = static_cast<int>(dims.size()) - 1;
      l.residual = rnd(3, 1);
      l.jacobians = {rnd(3, 3)};
      rows.add(l, &p, &dims[p]);
    }
    const int n = static_cast<int>(dims.size());
    for (int g = 0; g < 1 + coin(rng); ++g) {
      int a = static_cast<int>(rng() % n), b = n - 1 - static_cast<int>(rng() % 3);
      if (a == b) a = (a + 1) % n;
      const int pos[2] = {a, b}, d[2] = {dims[a], dims[b]};
      l.residual = rnd(2, 1);
      l.jacobians = {rnd(2, d[0]), rnd(2, d[1])};
      rows.add(l, pos, d);
    }
    const double predicted = chol.addRowsFlops(rows);
    const auto out = chol.addRows(rows);
    ASSERT_TRUE(out.ok) << "round " << round;
    EXPECT_EQ(predicted, out.flops) << "round " << round;
    EXPECT_GT(out.flops, 0);
  }
}

}  // namespace
}  // namespace hamal::aprilsam
