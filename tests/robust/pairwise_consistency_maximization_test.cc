// Pairwise Consistency Maximization (backends/robust/): igraph's maximum
// clique and its budget, batch PCM on a small spoiled world (every false
// edge rejected, the true ones kept), incremental PCM's bounded step, and
// the options' errors.
#include "backends/robust/pairwise_consistency_maximization.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "apps/generator/manhattan_world.h"
#include "apps/robust/false_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/incremental_pairwise_consistency_maximization.h"
#include "backends/robust/loop_closure.h"
#include "backends/robust/maximum_clique.h"
#include "core/error.h"

namespace hamal::robust {
namespace {

bool isClique(const ConsistencyGraph& g, const std::vector<int>& members) {
  std::set<std::pair<int, int>> e(g.edges.begin(), g.edges.end());
  for (std::size_t a = 0; a < members.size(); ++a)
    for (std::size_t b = a + 1; b < members.size(); ++b)
      if (!e.count({members[a], members[b]}) && !e.count({members[b], members[a]})) return false;
  return true;
}

TEST(MaximumClique, FindsTheLargestAndPrefersWhatWasAccepted) {
  // Two triangles {0,1,2} and {3,4,5} joined by the edge 2-3, and a 4-clique {5,6,7,8}.
  ConsistencyGraph g{9,
                     {{0, 1},
                      {0, 2},
                      {1, 2},
                      {2, 3},
                      {3, 4},
                      {3, 5},
                      {4, 5},
                      {5, 6},
                      {5, 7},
                      {5, 8},
                      {6, 7},
                      {6, 8},
                      {7, 8}}};
  const CliqueResult r = maximumClique(g);
  EXPECT_TRUE(r.exact);
  EXPECT_EQ(r.members, (std::vector<int>{5, 6, 7, 8}));
  g.edges.emplace_back(0, 3);
  g.edges.emplace_back(1, 3);  // {0,1,2,3} is a 4-clique too
  std::vector<bool> preferred(9, false);
  preferred[0] = preferred[1] = true;
  EXPECT_EQ(maximumClique(g, preferred).members, (std::vector<int>{0, 1, 2, 3}));
  preferred.assign(9, false);
  preferred[6] = true;
  EXPECT_EQ(maximumClique(g, preferred).members, (std::vector<int>{5, 6, 7, 8}));
  EXPECT_EQ(largestCliques(g).size(), 2u);
  EXPECT_TRUE(maximumClique(ConsistencyGraph{}).members.empty());
  EXPECT_EQ(maximumClique(ConsistencyGraph{3, {}}).members.size(), 1u);
  EXPECT_THROW(maximumClique(ConsistencyGraph{2, {{0, 2}}}), Error);
}

TEST(MaximumClique, DenseGraphsSplitByTheirComplementGiveTheSameSize) {
  // Almost complete graphs take the complement's components apart; the
  // size must be what igraph_largest_cliques finds on the whole graph.
  std::mt19937_64 rng(2);
  for (double density : {0.9, 0.95, 0.98}) {
    std::bernoulli_distribution edge(density);
    ConsistencyGraph g{36, {}};
    for (int a = 0; a < g.vertices; ++a)
      for (int b = a + 1; b < g.vertices; ++b)
        if (edge(rng)) g.edges.emplace_back(a, b);
    const CliqueResult r = maximumClique(g);
    EXPECT_TRUE(r.exact);
    EXPECT_TRUE(isClique(g, r.members));
    EXPECT_EQ(r.members.size(), largestCliques(g).front().size()) << density;
  }
}

TEST(MaximumClique, ABudgetThatRunsOutSaysSoAndOneThatDoesNotIsExact) {
  // A dense random graph whose exact search takes far longer than 50 ms.
  std::mt19937_64 rng(1);
  std::bernoulli_distribution edge(0.9);
  ConsistencyGraph g{300, {}};
  for (int a = 0; a < g.vertices; ++a)
    for (int b = a + 1; b < g.vertices; ++b)
      if (edge(rng)) g.edges.emplace_back(a, b);
  const CliqueResult r = maximumClique(g, {}, 0.05);
  EXPECT_FALSE(r.exact);
  EXPECT_TRUE(r.members.empty());
  EXPECT_LT(r.seconds, 2.0);
  // A small one: the budgeted search is the exact one.
  ConsistencyGraph small{30, {}};
  for (int a = 0; a < small.vertices; ++a)
    for (int b = a + 1; b < small.vertices; ++b)
      if (edge(rng)) small.edges.emplace_back(a, b);
  const CliqueResult budgeted = maximumClique(small, {}, 10);
  EXPECT_TRUE(budgeted.exact);
  EXPECT_EQ(budgeted.members, maximumClique(small).members);
  EXPECT_TRUE(isClique(small, budgeted.members));
  EXPECT_THROW(maximumClique(ConsistencyGraph{2, {{0, 2}}}, {}, 10), Error);
}

struct SpoiledWorld {
  OdometryChain chain;
  std::vector<LoopClosure> closures;
  std::vector<bool> is_false;
};

SpoiledWorld spoiledWorld(std::size_t outliers, apps::SpoilPolicy policy, int poses = 400) {
  apps::ManhattanWorldOptions w;
  w.poses = poses;
  w.seed = 3;
  const Graph clean = apps::generateManhattanWorld(w).graph;
  apps::SpoilOptions o;
  o.outliers = outliers;
  o.seed = 5;
  o.policy = policy;
  const apps::SpoiledGraph spoiled = apps::spoilGraph(clean, o);
  SpoiledWorld s;
  for (std::size_t f = 0; f < spoiled.graph.factors.size(); ++f) {
    const Factor& factor = *spoiled.graph.factors[f];
    if (OdometryChain::isOdometry(factor)) s.chain.add(factor);
    if (!isLoopClosure(factor)) continue;
    s.closures.push_back(loopClosureOf(factor));
    s.is_false.push_back(f >= clean.factors.size());
  }
  return s;
}

struct Tally {
  std::size_t false_accepted = 0, true_rejected = 0, trues = 0;
};
Tally tally(const SpoiledWorld& s, const std::vector<bool>& accepted) {
  Tally t;
  for (std::size_t c = 0; c < accepted.size(); ++c) {
    t.trues += !s.is_false[c];
    if (s.is_false[c] && accepted[c]) ++t.false_accepted;
    if (!s.is_false[c] && !accepted[c]) ++t.true_rejected;
  }
  return t;
}

TEST(PairwiseConsistencyMaximization, BatchRejectsEveryFalseEdgeAndKeepsTheTrue) {
  for (auto policy : {apps::SpoilPolicy::kRandom, apps::SpoilPolicy::kRandomGroup}) {
    const SpoiledWorld s = spoiledWorld(40, policy);
    const PcmResult r = pairwiseConsistencyMaximization(s.chain, s.closures, defaultPcmOptions());
    EXPECT_TRUE(r.exact);
    const Tally t = tally(s, r.accepted);
    EXPECT_EQ(t.false_accepted, 0u) << apps::spoilPolicyName(policy);
    EXPECT_LE(t.true_rejected, t.trues / 50) << apps::spoilPolicyName(policy) << " of " << t.trues;
    // One test per other closure: looser than incremental PCM's 40 tests.
    EXPECT_DOUBLE_EQ(r.threshold, pcmThreshold(defaultPcmOptions(), s.closures.size() - 1));
    EXPECT_GT(r.threshold, defaultPcmOptions().threshold);
  }
  PcmOptions given = defaultPcmOptions();
  given.threshold = 15;
  given.threshold_given = true;
  const SpoiledWorld s = spoiledWorld(40, apps::SpoilPolicy::kRandom);
  EXPECT_DOUBLE_EQ(pairwiseConsistencyMaximization(s.chain, s.closures, given).threshold, 15);
}

TEST(PairwiseConsistencyMaximization, ABudgetThatRunsOutFallsBackToIncremental) {
  const SpoiledWorld s = spoiledWorld(40, apps::SpoilPolicy::kRandom);
  PcmOptions o = defaultPcmOptions();
  o.clique_seconds = 1e-6;
  const PcmResult r = pairwiseConsistencyMaximization(s.chain, s.closures, o);
  EXPECT_FALSE(r.exact);
  EXPECT_GT(r.fallback_seconds, 0);
  const Tally t = tally(s, r.accepted);
  EXPECT_EQ(t.false_accepted, 0u);
  EXPECT_LE(t.true_rejected, t.trues / 20) << " of " << t.trues;
}

TEST(PairwiseConsistencyMaximization, IncrementalStepsAreBoundedAndRejectFalseEdges) {
  const SpoiledWorld s = spoiledWorld(40, apps::SpoilPolicy::kRandom);
  PcmOptions o = defaultPcmOptions();
  o.window = 10;
  o.sample = 10;
  IncrementalPairwiseConsistencyMaximization pcm(o);
  // Closures in the order of their later pose, as the thesis protocol brings them.
  std::vector<std::size_t> order(s.closures.size());
  for (std::size_t c = 0; c < order.size(); ++c) order[c] = c;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::max(s.closures[a].from, s.closures[a].to) <
           std::max(s.closures[b].from, s.closures[b].to);
  });
  SpoiledWorld sorted;
  std::size_t searches = 0;
  const std::size_t v = o.window + o.sample + 1;
  for (std::size_t c : order) {
    pcm.add(s.chain, s.closures[c]);
    sorted.is_false.push_back(s.is_false[c]);
    EXPECT_LE(pcm.last().vertices, v);
    EXPECT_LE(pcm.last().tests, v * (v - 1) / 2);
    searches += pcm.last().searched;
  }
  EXPECT_GT(searches, 0u);
  const Tally t = tally(sorted, pcm.accepted());
  EXPECT_EQ(t.false_accepted, 0u);
  EXPECT_LE(t.true_rejected, t.trues / 20) << " of " << t.trues;
}

// Incremental PCM's true rejections on a clean world of many closures, in
// the order the thesis protocol brings them.
Tally incrementalOnClean(const SpoiledWorld& s, const PcmOptions& o) {
  IncrementalPairwiseConsistencyMaximization pcm(o);
  for (const LoopClosure& c : s.closures) pcm.add(s.chain, c);
  return tally(s, pcm.accepted());
}

TEST(PairwiseConsistencyMaximization, ATrueClosurePassesAllItsTestsWithTheStatedProbability) {
  const SpoiledWorld s = spoiledWorld(0, apps::SpoilPolicy::kRandom, 2000);
  const Tally t = incrementalOnClean(s, defaultPcmOptions());
  ASSERT_GT(t.trues, 300u);
  EXPECT_LE(t.true_rejected, t.trues / 100) << " of " << t.trues;
  // The probability per test instead: one failed test of 41 drops a closure.
  PcmOptions per_test = defaultPcmOptions();
  per_test.threshold = chiSquareQuantile(3, per_test.probability);
  per_test.threshold_given = true;
  EXPECT_GT(incrementalOnClean(s, per_test).true_rejected, t.trues / 100);
}

TEST(PairwiseConsistencyMaximization, OptionsAndTheirErrors) {
  std::vector<std::string> names;
  for (const auto& o : pcmOptionSpecs()) names.push_back(o.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"pcm_probability", "pcm_threshold", "pcm_clique_seconds",
                                      "pcm_window", "pcm_sample", "pcm_seed", "pcm_covariance"}));
  const auto from = [](std::map<std::string, std::string> given) {
    return pcmOptionsFrom(Options("cholesky", pcmOptionSpecs(), given));
  };
  // The probability is a true closure's over its tests: half of 1% for the
  // estimate's one, half for the 20 + 20 pairwise ones.
  EXPECT_NEAR(from({}).threshold, 20.6407, 1e-4);
  EXPECT_NEAR(from({}).estimate_threshold, 12.8382, 1e-4);
  EXPECT_NEAR(from({{"pcm_probability", "0.95"}}).threshold, 17.2595, 1e-4);
  EXPECT_NEAR(from({{"pcm_window", "5"}, {"pcm_sample", "4"}}).threshold, 17.5079, 1e-4);
  EXPECT_DOUBLE_EQ(from({{"pcm_threshold", "5"}}).threshold, 5);
  EXPECT_DOUBLE_EQ(from({{"pcm_threshold", "5"}}).estimate_threshold, 5);
  EXPECT_DOUBLE_EQ(pcmThreshold(from({{"pcm_threshold", "5"}}), 1000), 5);
  EXPECT_NEAR(defaultPcmOptions().threshold, from({}).threshold, 1e-12);
  EXPECT_NEAR(defaultPcmOptions().estimate_threshold, from({}).estimate_threshold, 1e-12);
  const auto fails = [&](std::map<std::string, std::string> given, const std::string& name) {
    try {
      from(given);
      ADD_FAILURE() << name << ": no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  fails({{"pcm_threshold", "0"}}, "pcm_threshold");
  fails({{"pcm_threshold", "-3"}}, "pcm_threshold");
  fails({{"pcm_probability", "1"}}, "pcm_probability");
  fails({{"pcm_probability", "0"}}, "pcm_probability");
  fails({{"pcm_probability", "1.5"}}, "pcm_probability");
  fails({{"pcm_clique_seconds", "-1"}}, "pcm_clique_seconds");
  fails({{"pcm_window", "0"}}, "pcm_window");
  fails({{"pcm_sample", "-1"}}, "pcm_sample");
  fails({{"pcm_covariance", "marginal"}}, "pcm_covariance");
  EXPECT_EQ(from({}).covariance, PcmOptions::Covariance::kEstimate);
  EXPECT_EQ(from({{"pcm_covariance", "odometry"}}).covariance, PcmOptions::Covariance::kOdometry);
  PcmOptions zero = defaultPcmOptions();
  zero.threshold = 0;
  EXPECT_THROW(IncrementalPairwiseConsistencyMaximization{zero}, Error);
}

}  // namespace
}  // namespace hamal::robust
