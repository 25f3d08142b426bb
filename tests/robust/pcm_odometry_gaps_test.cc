// PCM where the odometry has a gap or the graph several components
// (pairwise_consistency_maximization.h, "Pairs the odometry cannot test"):
// closures across the same gap are tested against each other through the
// odometry on both sides, pairs no odometry joins are neither tested nor in
// conflict (counted), the false closure is still rejected, and the front
// end takes such graphs in batch and step by step instead of refusing them.
#include <gtest/gtest.h>

#include <algorithm>

#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "backends/robust/incremental_pairwise_consistency_maximization.h"
#include "backends/robust/loop_closure.h"
#include "backends/robust/loop_closure_consistency.h"
#include "backends/robust/pairwise_consistency_maximization.h"
#include "backends/robust/pcm_front_end.h"
#include "core/error.h"
#include "core/metrics.h"
#include "factors/between_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal::robust {
namespace {

// Poses on a circle of radius 3, 20 of them, noise-free measurements.
Pose2 truth(std::uint64_t i) {
  const double a = 2 * M_PI * double(i) / 20;
  return {3 * std::cos(a), 3 * std::sin(a), wrapAngle(a + M_PI / 2)};
}

const Eigen::Matrix3d kInfo = 1e4 * Eigen::Matrix3d::Identity();  // 1 cm, 0.01 rad

FactorPtr between(std::uint64_t a, std::uint64_t b, double off = 0) {
  const Pose2 z = truth(a).between(truth(b));
  return std::make_shared<BetweenFactor>(X(a), X(b), Pose2(z.x + off, z.y, z.theta), kInfo);
}

// Odometry 0..19 but for the links whose later pose is in `missing`.
OdometryChain chainWithout(const std::vector<std::uint64_t>& missing) {
  OdometryChain chain;
  for (std::uint64_t i = 1; i < 20; ++i)
    if (std::find(missing.begin(), missing.end(), i) == missing.end())
      chain.add(*between(i - 1, i));
  return chain;
}

TEST(PcmOdometryGaps, JoinedIsOneSegment) {
  const OdometryChain chain = chainWithout({10});
  EXPECT_TRUE(chain.joined(0, 9));
  EXPECT_TRUE(chain.joined(10, 19));
  EXPECT_FALSE(chain.joined(9, 10));
  EXPECT_FALSE(chain.joined(3, 15));
  EXPECT_FALSE(chain.joined(3, 25));  // beyond the last link
}

TEST(PcmOdometryGaps, ClosuresAcrossOneGapAreTestedEitherWayRound) {
  const OdometryChain chain = chainWithout({10});
  const LoopClosure a = loopClosureOf(*between(2, 14)), b = loopClosureOf(*between(4, 16));
  const LoopClosure b_back = loopClosureOf(*between(16, 4));  // x16 -> x4
  const LoopClosure wrong = loopClosureOf(*between(5, 13, 1.0));
  for (const LoopClosure& other : {b, b_back}) {
    const auto cycle = cycleThroughOdometry(chain, a, other);
    ASSERT_TRUE(cycle.has_value());
    EXPECT_LT(cycle->mahalanobis2, 1e-9);
  }
  const auto cycle = cycleThroughOdometry(chain, a, wrong);
  ASSERT_TRUE(cycle.has_value());
  EXPECT_GT(cycle->mahalanobis2, 100.0);
  // One each side, or one across and one beside the gap: nothing to test.
  EXPECT_FALSE(
      cycleThroughOdometry(chain, loopClosureOf(*between(0, 5)), loopClosureOf(*between(12, 18)))
          .has_value());
  EXPECT_FALSE(cycleThroughOdometry(chain, a, loopClosureOf(*between(12, 18))).has_value());
  // The old test still refuses such a pair.
  EXPECT_THROW(cycleError(chain, a, b_back), Error);
}

struct Case {
  std::vector<FactorPtr> closures;
  std::vector<bool> is_true;
};

std::vector<LoopClosure> closuresOf(const Case& c) {
  std::vector<LoopClosure> out;
  for (const auto& f : c.closures) out.push_back(loopClosureOf(*f));
  return out;
}

TEST(PcmOdometryGaps, AGapKeepsTheTrueClosuresOfBothSidesAndRejectsTheFalse) {
  const OdometryChain chain = chainWithout({10});
  // Two across the gap, two on each side, one false across it.
  const Case c{{between(2, 14), between(4, 16), between(0, 6), between(1, 8), between(11, 18),
                between(12, 19), between(5, 13, 1.0)},
               {true, true, true, true, true, true, false}};
  const PcmResult r = pairwiseConsistencyMaximization(chain, closuresOf(c), defaultPcmOptions());
  EXPECT_EQ(r.accepted, c.is_true);
  // Untested: each side's closures against the other side's (2 x 2 = 4
  // pairs) and the four beside the gap against the three across it (12).
  EXPECT_EQ(r.unchecked_pairs, 16u);
  EXPECT_EQ(std::count(r.unchecked.begin(), r.unchecked.end(), true), 7);
  // Incrementally, one at a time, the same decisions.
  IncrementalPairwiseConsistencyMaximization pcm(defaultPcmOptions());
  for (const LoopClosure& l : closuresOf(c)) pcm.add(chain, l);
  EXPECT_EQ(pcm.accepted(), c.is_true);
  EXPECT_EQ(pcm.uncheckedPairs(), 16u);
}

TEST(PcmOdometryGaps, TwoComponentsKeepTheTrueClosuresOfEach) {
  // Components 0..9 and 10..19: no link and no closure between them.
  const OdometryChain chain = chainWithout({10});
  const Case c{{between(0, 6), between(1, 8), between(2, 9), between(11, 18), between(12, 19),
                between(10, 17, 1.0)},
               {true, true, true, true, true, false}};
  const PcmResult r = pairwiseConsistencyMaximization(chain, closuresOf(c), defaultPcmOptions());
  // Unknown pairs as conflicts would keep one component's closures only.
  EXPECT_EQ(r.accepted, c.is_true);
  EXPECT_EQ(r.unchecked_pairs, 9u);
}

// The front end on a graph with an odometry gap and on one of two
// components, as one batch step and under the thesis protocol: it no longer
// refuses the graph, and it ends at the truth without the false closure.
Graph gapGraph(bool two_components) {
  Graph g;
  for (std::uint64_t i = 0; i < 20; ++i) g.initial.insert(X(i), truth(i));
  for (std::uint64_t i = 1; i < 20; ++i)
    if (i != 10) g.factors.push_back(between(i - 1, i));
  if (two_components) {
    g.fixed = {X(0), X(10)};
  } else {
    g.factors.push_back(between(8, 10));  // the closure that bridges the gap
    g.factors.push_back(between(2, 14));
  }
  for (const auto& f : {between(0, 6), between(1, 8), between(11, 18), between(12, 19)})
    g.factors.push_back(f);
  g.factors.push_back(between(13, 19, 1.0));  // false
  return g;
}

TEST(PcmOdometryGaps, TheFrontEndTakesAGapAndTwoComponents) {
  Registry registry;
  apps::setUpRegistry(registry, {});
  for (const bool two : {false, true}) {
    const Graph g = gapGraph(two);
    const ThesisProtocol protocol(g);
    for (const char* spec : {"cholesky", "aprilsam"}) {
      SCOPED_TRACE(std::string(spec) + (two ? ", two components" : ", a gap"));
      PcmFrontEnd pcm(registry.makeBackend(spec), isLoopClosure);
      const bool batch = std::string(spec) == "cholesky";
      if (batch) {
        Step all;
        all.new_values = g.initial;
        all.new_factors = g.factors;
        all.fixed.assign(g.fixed.begin(), g.fixed.end());
        if (g.fixed.empty()) all.fixed = {X(0)};
        ASSERT_TRUE(pcm.update(all).status.ok());
      } else {
        for (std::size_t s = 0; s < protocol.size(); ++s)
          ASSERT_TRUE(pcm.update(protocol.step(s, pcm.estimate())).status.ok()) << "step " << s;
      }
      for (const auto& [factor, accepted] : pcm.decisions()) {
        const bool is_false = factor == g.factors.back().get();
        EXPECT_EQ(accepted, !is_false) << factor->keys()[0].str() << "-" << factor->keys()[1].str();
      }
      EXPECT_GT(pcm.uncheckedPairs(), 0u);
      EXPECT_LT(absoluteTrajectoryError(pcm.estimate(), g.initial, !two).translation_rmse, 1e-6);
    }
  }
}

}  // namespace
}  // namespace hamal::robust
