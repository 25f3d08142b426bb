// Tests of AprilSAM's orderings (thesis sec. 3.4.3, Alg. 3.2, eq. 3.20) and
// the BHAMD/AMD orderings it is compared with (sec. 3.5.1): valid
// permutations, the loop-closure nodes last in score order, and fill-in
// against AMD on the node graphs of M3500 and city10000.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include "backends/aprilsam/bhamd_ordering.h"
#include "backends/aprilsam/factorization_cost.h"
#include "backends/aprilsam/min_heap_ordering.h"
#include "backends/builtins.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/registry.h"
#include "tests/testing/test_data.h"

namespace hamal::aprilsam {
namespace {

bool isPermutation(const std::vector<int>& order, int n) {
  if (static_cast<int>(order.size()) != n) return false;
  std::vector<char> seen(n, 0);
  for (int v : order) {
    if (v < 0 || v >= n || seen[v]) return false;
    seen[v] = 1;
  }
  return true;
}

long nnzL(const OrderingInput& in, const std::vector<int>& order) {
  const std::vector<long> counts = choleskyColumnCounts(in.adjacency, order);
  return std::accumulate(counts.begin(), counts.end(), 0L);
}

void addEdge(OrderingInput& in, int a, int b) {
  in.adjacency[a].push_back(b);
  in.adjacency[b].push_back(a);
}

// A random SLAM-like graph: a few odometry chains of poses (disconnected
// from each other), random loop closures within a chain, landmarks seen
// from one or more poses, and isolated nodes.
OrderingInput randomGraph(std::mt19937& rng, int poses) {
  std::uniform_int_distribution<int> landmarks_dist(0, poses / 3);
  const int landmarks = landmarks_dist(rng);
  const int isolated = poses % 3;
  const int n = poses + landmarks + isolated;
  OrderingInput in;
  in.adjacency.resize(n);
  in.positions.resize(n);
  std::normal_distribution<double> step(0.0, 1.0);
  Eigen::Vector2d p(0, 0);
  const int chains = 1 + poses / 40;
  for (int i = 0; i < poses; ++i) {
    p += Eigen::Vector2d(step(rng), step(rng));
    in.positions[i] = p;
    if (i % std::max(1, poses / chains) != 0) addEdge(in, i - 1, i);
  }
  if (poses > 2) {
    std::uniform_int_distribution<int> pick(0, poses - 1);
    for (int k = 0; k < poses / 5; ++k) {
      const int a = pick(rng), b = pick(rng);
      if (a != b) addEdge(in, a, b);
    }
  }
  for (int l = 0; l < landmarks; ++l) {
    const int id = poses + l;
    std::uniform_int_distribution<int> pick(0, poses - 1);
    const int seen = 1 + l % 3;
    for (int s = 0; s < seen; ++s) {
      const int pose = pick(rng);
      addEdge(in, pose, id);
      in.positions[id] = in.positions[pose] + Eigen::Vector2d(step(rng), step(rng));
    }
  }
  for (int k = 0; k < isolated; ++k) in.positions[poses + landmarks + k] = Eigen::Vector2d(k, -k);
  if (poses > 0) in.newest = poses - 1;
  return in;
}

OrderingInput chain(int n) {
  OrderingInput in;
  in.adjacency.resize(n);
  in.positions.resize(n);
  for (int i = 0; i < n; ++i) {
    in.positions[i] = Eigen::Vector2d(i, 0);
    if (i > 0) addEdge(in, i - 1, i);
  }
  in.newest = n - 1;
  return in;
}

// Exact nnz(L) by eliminating on an explicit graph: the reference for
// choleskyColumnCounts.
long bruteForceNnzL(const OrderingInput& in, const std::vector<int>& order) {
  const int n = static_cast<int>(in.adjacency.size());
  std::vector<std::set<int>> g(n);
  for (int i = 0; i < n; ++i) {
    for (int j : in.adjacency[i]) {
      if (i != j) {
        g[i].insert(j);
        g[j].insert(i);
      }
    }
  }
  long nnz = 0;
  for (int p : order) {
    nnz += 1 + static_cast<long>(g[p].size());
    for (int a : g[p]) {
      g[a].erase(p);
      for (int b : g[p]) {
        if (a != b) g[a].insert(b);
      }
    }
    g[p].clear();
  }
  return nnz;
}

// A workspace carried from graph to graph, larger and smaller ones in turn
// (as AprilSAM's batches and tops are), gives each the order a fresh call
// gives: what it keeps between calls is buffers, not state.
TEST(Orderings, WorkspaceReusedAcrossGraphsChangesNoOrder) {
  std::mt19937 rng(19);
  OrderingWorkspace ws;
  for (int poses : {500, 3, 200, 0, 60, 800, 17, 1, 500}) {
    for (double radius : {0.0, 3.0}) {
      OrderingInput in = randomGraph(rng, poses);
      SCOPED_TRACE("poses=" + std::to_string(poses) + " radius=" + std::to_string(radius));
      EXPECT_EQ(minHeapOrdering(in, radius, &ws), minHeapOrdering(in, radius));
      for (Rescoring r : {Rescoring::kNeighbours, Rescoring::kOnExtraction})
        EXPECT_EQ(scoreListOrdering(in, {}, r, &ws), scoreListOrdering(in, {}, r));
    }
  }
  // A bad input leaves the workspace fit for the next call.
  OrderingInput bad = randomGraph(rng, 50);
  bad.adjacency[0].push_back(static_cast<int>(bad.adjacency.size()));
  EXPECT_THROW(minHeapOrdering(bad, 1.0, &ws), Error);
  OrderingInput in = randomGraph(rng, 300);
  EXPECT_EQ(minHeapOrdering(in, 2.0, &ws), minHeapOrdering(in, 2.0));
}

TEST(Orderings, ValidPermutationsOnRandomGraphs) {
  std::mt19937 rng(7);
  for (int poses : {0, 1, 2, 3, 5, 17, 60, 200, 500}) {
    for (int rep = 0; rep < 3; ++rep) {
      OrderingInput in = randomGraph(rng, poses);
      const int n = static_cast<int>(in.adjacency.size());
      SCOPED_TRACE("poses=" + std::to_string(poses) + " n=" + std::to_string(n));
      for (double radius : {0.0, 3.0, 1e9}) {
        const std::vector<int> mh = minHeapOrdering(in, radius);
        EXPECT_TRUE(isPermutation(mh, n));
        if (in.newest >= 0) EXPECT_EQ(mh.back(), in.newest);
      }
      const std::vector<int> bh = bhamdOrdering(in);
      EXPECT_TRUE(isPermutation(bh, n));
      if (in.newest >= 0) EXPECT_EQ(bh.back(), in.newest);
      EXPECT_TRUE(isPermutation(amdOrdering(in), n));
      in.newest = -1;
      EXPECT_TRUE(isPermutation(minHeapOrdering(in, 3.0), n));
      EXPECT_TRUE(isPermutation(bhamdOrdering(in), n));
    }
  }
}

TEST(Orderings, EmptyAndSingleNode) {
  OrderingInput empty;
  EXPECT_TRUE(minHeapOrdering(empty, 1.0).empty());
  EXPECT_TRUE(bhamdOrdering(empty).empty());
  EXPECT_TRUE(amdOrdering(empty).empty());
  OrderingInput one;
  one.adjacency.resize(1);
  one.positions = {Eigen::Vector2d(1, 2)};
  one.newest = 0;
  EXPECT_EQ(minHeapOrdering(one, 1.0), std::vector<int>{0});
  EXPECT_EQ(bhamdOrdering(one), std::vector<int>{0});
  EXPECT_EQ(amdOrdering(one), std::vector<int>{0});
}

TEST(Orderings, ToleratesOneSidedDuplicateAndSelfLoopEntries) {
  OrderingInput in;
  in.adjacency = {{1, 1, 0}, {}, {1}};  // 0-1 twice and a self loop, 2-1 one-sided
  for (const auto& order : {minHeapOrdering(in, 1.0), bhamdOrdering(in), amdOrdering(in)}) {
    EXPECT_TRUE(isPermutation(order, 3));
    EXPECT_EQ(nnzL(in, order), 5);  // a chain: no fill whatever the min-degree order
  }
}

TEST(Orderings, RejectBadInput) {
  OrderingInput in = chain(4);
  in.adjacency[2].push_back(4);
  EXPECT_THROW(minHeapOrdering(in, 1.0), Error);
  EXPECT_THROW(bhamdOrdering(in), Error);
  EXPECT_THROW(amdOrdering(in), Error);
  in = chain(4);
  in.newest = 4;
  EXPECT_THROW(minHeapOrdering(in, 1.0), Error);
  EXPECT_THROW(bhamdOrdering(in), Error);
  in = chain(4);
  EXPECT_THROW(minHeapOrdering(in, -1.0), Error);
  EXPECT_THROW(minHeapOrdering(in, std::nan("")), Error);
  in.positions.pop_back();
  EXPECT_THROW(minHeapOrdering(in, 1.0), Error);
  EXPECT_THROW(scoreListOrdering(chain(4), {1, 1}, Rescoring::kNeighbours), Error);
}

// eq. 3.20: nodes within R_T score N + 1/r, above every degree, so they are
// the last ones, farthest first and the newest (r = 0) last of all.
TEST(MinHeapOrdering, LoopClosureCandidatesLastInIncreasingScore) {
  std::mt19937 rng(11);
  for (int rep = 0; rep < 5; ++rep) {
    const OrderingInput in = randomGraph(rng, 300);
    const int n = static_cast<int>(in.adjacency.size());
    const double radius = 4.0;
    const Eigen::Vector2d centre = in.positions[in.newest];
    std::set<int> near;
    for (int i = 0; i < n; ++i) {
      if ((in.positions[i] - centre).norm() < radius) near.insert(i);
    }
    ASSERT_GT(near.size(), 2u);
    const std::vector<int> order = minHeapOrdering(in, radius);
    ASSERT_TRUE(isPermutation(order, n));
    const std::vector<int> tail(order.end() - near.size(), order.end());
    EXPECT_EQ(std::set<int>(tail.begin(), tail.end()), near);
    EXPECT_EQ(tail.back(), in.newest);
    for (std::size_t k = 1; k + 1 < tail.size(); ++k) {
      const double r_before = (in.positions[tail[k - 1]] - centre).norm();
      const double r = (in.positions[tail[k]] - centre).norm();
      EXPECT_GE(r_before, r) << "scores N + 1/r must increase towards the end";
    }
  }
}

TEST(MinHeapOrdering, NewestLastEvenWhenAnotherNodeSharesItsPosition) {
  OrderingInput in = chain(5);
  in.newest = 1;
  in.positions[3] = in.positions[1];  // r = 0 too: score +inf for both
  const std::vector<int> order = minHeapOrdering(in, 0.5);
  EXPECT_EQ(order[3], 3);
  EXPECT_EQ(order[4], 1);
}

// A chain has a zero-fill elimination order and minimum degree with Alg.
// 3.2's re-filing finds one, wherever the newest node sits. BHAMD, which
// leaves a node whose degree fell in its old list, does not when the newest
// node is held back at the start of the chain: its neighbour keeps score 2
// and is eliminated before the nodes whose degree dropped to 1 (the case
// the thesis' re-scoring prevents, sec. 3.4.3).
TEST(Orderings, ChainHasNoFill) {
  const long no_fill = 100 + 99;
  for (int newest : {-1, 0, 37, 99}) {
    OrderingInput in = chain(100);
    in.newest = newest;
    EXPECT_EQ(nnzL(in, minHeapOrdering(in, 0.0)), no_fill) << "newest " << newest;
    EXPECT_EQ(nnzL(in, minHeapOrdering(in, 1.5)), no_fill) << "newest " << newest;
    EXPECT_EQ(nnzL(in, amdOrdering(in)), no_fill);
  }
  OrderingInput in = chain(100);
  in.newest = -1;
  EXPECT_EQ(nnzL(in, bhamdOrdering(in)), no_fill);
  in.newest = 99;
  EXPECT_EQ(nnzL(in, bhamdOrdering(in)), no_fill);
  in.newest = 0;
  EXPECT_GT(nnzL(in, bhamdOrdering(in)), no_fill);
  EXPECT_EQ(nnzL(in, scoreListOrdering(in, {0}, Rescoring::kNeighbours)), no_fill);
  // The natural order of a star centred on node 0 fills completely; min
  // degree takes the leaves first and does not fill at all.
  OrderingInput star;
  star.adjacency.resize(30);
  for (int i = 1; i < 30; ++i) addEdge(star, 0, i);
  std::vector<int> natural(30);
  std::iota(natural.begin(), natural.end(), 0);
  EXPECT_EQ(nnzL(star, natural), 30 * 31 / 2);
  EXPECT_EQ(nnzL(star, minHeapOrdering(star, 1.0)), 59);
  EXPECT_EQ(nnzL(star, bhamdOrdering(star)), 59);
}

TEST(FactorizationCost, ColumnCountsMatchExplicitElimination) {
  std::mt19937 rng(3);
  for (int poses : {1, 8, 40, 120}) {
    const OrderingInput in = randomGraph(rng, poses);
    const int n = static_cast<int>(in.adjacency.size());
    std::vector<int> shuffled(n);
    std::iota(shuffled.begin(), shuffled.end(), 0);
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    for (const auto& order : {shuffled, minHeapOrdering(in, 2.0), amdOrdering(in)}) {
      EXPECT_EQ(nnzL(in, order), bruteForceNnzL(in, order)) << "poses " << poses;
    }
  }
  EXPECT_THROW(choleskyColumnCounts({{1}, {0}}, {0, 0}), Error);
  EXPECT_THROW(choleskyColumnCounts({{1}, {0}}, {0}), Error);
}

// A 2D grid is the hard case for minimum degree; the approximate degree and
// both re-filing rules must stay close to AMD.
TEST(Orderings, GridFillCloseToAmd) {
  const int side = 40;
  OrderingInput in;
  in.adjacency.resize(side * side);
  in.positions.resize(side * side);
  for (int r = 0; r < side; ++r) {
    for (int c = 0; c < side; ++c) {
      const int id = r * side + c;
      in.positions[id] = Eigen::Vector2d(c, r);
      if (c > 0) addEdge(in, id - 1, id);
      if (r > 0) addEdge(in, id - side, id);
    }
  }
  const long amd = nnzL(in, amdOrdering(in));
  const long mh = nnzL(in, minHeapOrdering(in, 0.0));
  const long bh = nnzL(in, bhamdOrdering(in));
  std::printf("grid %dx%d nnz(L): amd %ld min-heap %ld bhamd %ld\n", side, side, amd, mh, bh);
  EXPECT_LT(mh, 1.3 * amd);
  EXPECT_LT(bh, 1.3 * amd);
}

// The node graph of a dataset: one node per variable, an edge between any
// two variables of a factor; positions from the file's initial values.
OrderingInput nodeGraph(const std::string& path) {
  Registry registry;
  registerBuiltins(registry);
  const Graph graph = readGraph(path, registry);
  const std::vector<Key> keys = graph.keys();
  std::map<Key, int> id;
  for (const Key& k : keys) id.emplace(k, static_cast<int>(id.size()));
  OrderingInput in;
  in.adjacency.resize(keys.size());
  in.positions.assign(keys.size(), Eigen::Vector2d::Zero());
  for (const FactorPtr& f : graph.factors) {
    for (std::size_t a = 0; a < f->keys().size(); ++a) {
      for (std::size_t b = a + 1; b < f->keys().size(); ++b) {
        addEdge(in, id.at(f->keys()[a]), id.at(f->keys()[b]));
      }
    }
  }
  Key newest;
  bool have_pose = false;
  for (const Key& k : keys) {
    if (graph.initial.contains(k)) {
      const double* d = graph.initial.data(k);
      in.positions[id.at(k)] = Eigen::Vector2d(d[0], d[1]);
    }
    if (k.kind() == kPoseKind && (!have_pose || newest < k)) {
      newest = k;
      have_pose = true;
    }
  }
  if (have_pose) in.newest = id.at(newest);
  return in;
}

struct FillReport {
  long natural, amd, min_heap, min_heap_r0, bhamd;
  double ms_amd, ms_min_heap, ms_bhamd;
};

FillReport measureFill(const OrderingInput& in, double radius) {
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  std::vector<int> natural(in.adjacency.size());
  std::iota(natural.begin(), natural.end(), 0);
  FillReport r{};
  r.natural = nnzL(in, natural);
  auto t0 = Clock::now();
  const std::vector<int> amd = amdOrdering(in);
  auto t1 = Clock::now();
  const std::vector<int> mh = minHeapOrdering(in, radius);
  auto t2 = Clock::now();
  const std::vector<int> bh = bhamdOrdering(in);
  auto t3 = Clock::now();
  r.ms_amd = ms(t0, t1);
  r.ms_min_heap = ms(t1, t2);
  r.ms_bhamd = ms(t2, t3);
  r.amd = nnzL(in, amd);
  r.min_heap = nnzL(in, mh);
  r.bhamd = nnzL(in, bh);
  r.min_heap_r0 = nnzL(in, minHeapOrdering(in, 0.0));
  return r;
}

void checkDataset(const std::string& name, const std::string& path, double radius) {
  const OrderingInput in = nodeGraph(path);
  ASSERT_GE(in.newest, 0);
  const FillReport r = measureFill(in, radius);
  std::printf(
      "%s: %zu nodes, nnz(L) blocks: natural %ld, amd %ld, min-heap(R_T=%g) %ld, min-heap(R_T=0) "
      "%ld, "
      "bhamd %ld; "
      "ordering ms: amd %.2f, min-heap %.2f, bhamd %.2f\n",
      name.c_str(), in.adjacency.size(), r.natural, r.amd, radius, r.min_heap, r.min_heap_r0,
      r.bhamd, r.ms_amd, r.ms_min_heap, r.ms_bhamd);
  EXPECT_LT(r.min_heap, 1.5 * r.amd);
  EXPECT_LT(r.bhamd, 1.5 * r.amd);
  EXPECT_LT(r.min_heap, r.natural / 5);
  EXPECT_LT(r.bhamd, r.natural / 5);
}

TEST(Orderings, FillOnM3500CloseToAmd) {
  HAMAL_REQUIRE_DATA(path, "M3500.toro");
  checkDataset("M3500", path, 5.0);
}

TEST(Orderings, FillOnCity10000CloseToAmd) {
  HAMAL_REQUIRE_DATA(path, "city10000.g2o");
  checkDataset("city10000", path, 5.0);
}

}  // namespace
}  // namespace hamal::aprilsam
