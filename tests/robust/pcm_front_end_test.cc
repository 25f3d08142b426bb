// PcmFrontEnd (backends/robust/pcm_front_end.h): PCM in front of cholesky
// (one batch step) and aprilsam (the thesis protocol, one step per pose) on
// a spoiled world ends at the clean graph's optimum, holding back and
// reporting every false edge; bad steps and candidates are errors.
#include "backends/robust/pcm_front_end.h"

#include <gtest/gtest.h>

#include "apps/bench/bench_runner.h"
#include "backends/robust/loop_closure.h"
#include "core/error.h"
#include "core/metrics.h"
#include "factors/position_factor.h"
#include "tests/robust/spoiled_world.h"

namespace hamal::robust {
namespace {

using World = testing::SpoiledWorld;

// 300 poses, 30 random false loop closures. Loop closures as uncertain as
// M3500's next to the odometry (1/100 of the generator's information, as
// tests/robust/robust_loop_closures_test has them): every pair of true ones
// agrees, so PCM keeps them all and the clean optimum is reachable. With the
// generator's exact noise about 1% of true pairs fail the 0.99 quantile and
// the maximum clique drops a closure of each
// (pairwise_consistency_maximization_test bounds that).
const World& world() {
  static const World w = [] {
    testing::SpoiledWorldOptions o;
    o.information_scale = 0.01;
    o.scaled = testing::ScaledFactors::kLoopClosures;
    return testing::makeSpoiledWorld(o);
  }();
  return w;
}

bool isCandidate(const Factor& f) { return isLoopClosure(f); }

// Every false edge rejected and never passed on, every true one accepted.
void expectDecisions(const PcmFrontEnd& pcm, const World& w) {
  const std::size_t clean = w.clean.factors.size();
  std::size_t false_seen = 0;
  const auto decisions = pcm.decisions();
  for (std::size_t i = 0; i < decisions.size(); ++i) {
    const auto& [factor, accepted] = decisions[i];
    std::size_t index = 0;
    while (w.spoiled.graph.factors[index].get() != factor) ++index;
    const bool is_false = index >= clean;
    false_seen += is_false;
    EXPECT_EQ(accepted, !is_false) << "factor " << index;
    EXPECT_EQ(pcm.inInner(i), !is_false) << "factor " << index;
  }
  EXPECT_EQ(false_seen, 30u);
  EXPECT_EQ(pcm.keptRejected(), 0u);
}

TEST(PcmFrontEnd, BatchCholeskyEndsAtTheCleanOptimum) {
  const World& w = world();
  PcmFrontEnd pcm(w.registry.makeBackend("cholesky:max_iterations=100"), isCandidate);
  const UpdateResult r = pcm.update(ThesisProtocol(w.spoiled.graph).batch());
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_TRUE(pcm.exact());
  expectDecisions(pcm, w);
  EXPECT_LT(absoluteTrajectoryError(pcm.estimate(), w.clean_optimum).translation_rmse, 1e-6);
}

TEST(PcmFrontEnd, IncrementalAprilsamEndsAtTheCleanOptimum) {
  const World& w = world();
  PcmFrontEnd pcm(w.registry.makeBackend("aprilsam"), isCandidate);
  apps::RunOptions options;
  options.chi2_every = 0;
  const apps::RunResult run =
      apps::runThesisProtocol(ThesisProtocol(w.spoiled.graph), pcm, "pcm+aprilsam", options);
  expectDecisions(pcm, w);
  EXPECT_LT(absoluteTrajectoryError(pcm.estimate(), w.clean_optimum).translation_rmse, 1e-3);
}

TEST(PcmFrontEnd, AFactorAcceptedEarlyAndRejectedLaterStaysAndIsReported) {
  // Step 1 brings the odometry and one false loop closure: alone, it is a
  // maximum clique and goes to the back-end. Step 2 brings the true closures,
  // which agree with each other and not with it.
  const World& w = world();
  const ThesisProtocol protocol(w.spoiled.graph);
  Step first, second;
  first.new_values = protocol.initialValues();
  first.new_factors.push_back(protocol.prior());
  const std::size_t clean = w.clean.factors.size();
  for (std::size_t f = 0; f < clean; ++f)
    (isLoopClosure(*w.spoiled.graph.factors[f]) ? second : first)
        .new_factors.push_back(w.spoiled.graph.factors[f]);
  const FactorPtr wrong = w.spoiled.graph.factors[w.spoiled.false_edges[0].factor];
  first.new_factors.push_back(wrong);
  second.index = 1;
  PcmFrontEnd pcm(w.registry.makeBackend("cholesky"), isCandidate);
  pcm.update(first);
  ASSERT_EQ(pcm.decisions().size(), 1u);
  EXPECT_TRUE(pcm.decisions()[0].second);
  EXPECT_EQ(pcm.keptRejected(), 0u);
  pcm.update(second);
  const auto decisions = pcm.decisions();
  ASSERT_EQ(decisions.size(), 1 + second.new_factors.size());
  EXPECT_EQ(decisions[0].first, wrong.get());
  EXPECT_FALSE(decisions[0].second);
  EXPECT_TRUE(pcm.inInner(0));
  EXPECT_EQ(pcm.keptRejected(), 1u);
  for (std::size_t i = 1; i < decisions.size(); ++i) {
    EXPECT_TRUE(decisions[i].second) << i;
    EXPECT_TRUE(pcm.inInner(i)) << i;
  }
}

TEST(PcmFrontEnd, BadCandidatesAndStepsAreErrors) {
  const World& w = world();
  EXPECT_THROW(PcmFrontEnd(nullptr, isCandidate), Error);
  EXPECT_THROW(PcmFrontEnd(w.registry.makeBackend("cholesky"), nullptr), Error);
  // A candidate with no relative pose: an error naming it, nothing recorded.
  PcmFrontEnd pcm(w.registry.makeBackend("cholesky"), [](const Factor&) { return true; });
  Step step;
  step.new_values.set(X(0), Pose2());
  step.new_factors.push_back(
      std::make_shared<PositionFactor>(X(0), Point2(1, 2), Eigen::Matrix2d::Identity()));
  try {
    pcm.update(step);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("x0"), std::string::npos) << e.what();
  }
  EXPECT_EQ(pcm.estimate().size(), 0u);
  // A factor on an unknown variable: checkStep's error.
  Step bad;
  bad.new_factors.push_back(
      std::make_shared<PositionFactor>(X(3), Point2(1, 2), Eigen::Matrix2d::Identity()));
  EXPECT_THROW(pcm.update(bad), Error);
}

}  // namespace
}  // namespace hamal::robust
