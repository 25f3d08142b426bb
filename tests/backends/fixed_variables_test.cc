// Fixed variables (core/step.h, Step::fixed) in every back-end: ceres
// (SetParameterBlockConstant), cholesky and the AprilSAM variants (no column)
// and the example plugin's dense Gauss-Newton. A fixed variable never moves,
// in a batch and at every step of the thesis protocol, also when it is fixed
// after it was added; a graph that fixes a pose needs no prior; its optimum
// equals the optimum with a strong prior on that pose; and a fixed key that
// names no variable is an Error. The world is the conformance suite's
// (conformance/small_world.h), which holds the contract for ceres, cholesky
// and the plugin's back-end on their own; here it holds for the AprilSAM
// variants too, and the back-ends agree with each other.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "backends/builtins.h"
#include "conformance/small_world.h"
#include "core/error.h"
#include "core/graph.h"
#include "core/metrics.h"
#include "core/plugin.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "protocol/thesis_protocol.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

// Tolerances tight enough that solvers agree to 1e-6 where they converge.
const char* const kBackends[] = {
    "ceres:function_tolerance=1e-14,parameter_tolerance=1e-12",
    "cholesky:function_tolerance=1e-14",
    "aprilsam:batch_iterations=10",
    "aprilsam-periodic",
    "aprilsam-nopredictive",
    "aprilsam-fullsolve",
    "dense-gauss-newton:tolerance=1e-12",
};
// Those that iterate to convergence in one update (the AprilSAM variants take
// one Gauss-Newton step per batch, as the thesis does).
const char* const kConverging[] = {kBackends[0], kBackends[1], kBackends[2], kBackends[6]};

Registry registryWithPlugin() {
  Registry r;
  registerBuiltins(r);
  loadPlugin(testing::buildPath("plugins/libhamal_example_plugin.so"), r);
  return r;
}

void expectSameEntry(const Values& a, const Values& b, Key k, const std::string& what) {
  for (int t = 0; t < a.dim(k); ++t)
    EXPECT_EQ(a.data(k)[t], b.data(k)[t]) << what << ": " << k << "[" << t << "] moved";
}

TEST(FixedVariables, NeverMoveInABatchAndNeedNoPrior) {
  const Registry registry = registryWithPlugin();
  Graph g = testing::smallWorld();
  g.fixed = {X(0), X(9), L(2)};
  const ThesisProtocol protocol(g);
  EXPECT_EQ(protocol.prior(), nullptr) << "a fixed pose fixes the gauge";
  const Step batch = protocol.batch();
  ASSERT_EQ(batch.fixed.size(), 3u);
  auto reference = registry.makeBackend(kBackends[1]);
  ASSERT_TRUE(reference->update(batch).status.ok());
  for (const char* spec : kBackends) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    const UpdateResult r = backend->update(batch);
    EXPECT_TRUE(r.status.ok()) << r.status.message;
    for (Key k : g.fixed) expectSameEntry(backend->estimate(), batch.new_values, k, spec);
    // The free variables did move: the solve did something.
    EXPECT_NE(backend->estimate().pose(X(5)).x, batch.new_values.pose(X(5)).x);
  }
  // And they moved to the same optimum.
  for (const char* spec : kConverging) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    ASSERT_TRUE(backend->update(batch).status.ok());
    for (Key k : reference->estimate().keys())
      for (int t = 0; t < reference->estimate().dim(k); ++t)
        EXPECT_NEAR(backend->estimate().data(k)[t], reference->estimate().data(k)[t], 1e-6)
            << k << "[" << t << "]";
  }
}

TEST(FixedVariables, NeverMoveAtAnyStepOfTheThesisProtocol) {
  const Registry registry = registryWithPlugin();
  Graph g = testing::smallWorld();
  g.fixed = {X(0), X(13), L(1)};
  const ThesisProtocol protocol(g);
  for (const char* spec : kBackends) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    Values entered;  // each fixed variable's value in the step that added it
    for (std::size_t i = 0; i < protocol.size(); ++i) {
      const Step step = protocol.step(i, backend->estimate());
      for (Key k : step.fixed) entered.insertEntry(k, step.new_values.entry(k));
      const UpdateResult r = backend->update(step);
      ASSERT_TRUE(r.status.ok()) << "step " << i << ": " << r.status.message;
      for (Key k : entered.keys())
        expectSameEntry(backend->estimate(), entered, k, "step " + std::to_string(i));
    }
    EXPECT_EQ(entered.size(), g.fixed.size());
    // Fixed poses enter at the graph's value.
    expectSameEntry(entered, g.initial, X(13), spec);
  }
}

// Fixing a variable some steps after it was added: from then on it keeps
// the value it had.
TEST(FixedVariables, AKnownVariableFixedLaterKeepsItsValue) {
  const Registry registry = registryWithPlugin();
  Graph g = testing::smallWorld();
  const ThesisProtocol protocol(g);
  const Key late = X(4);
  const std::size_t fix_at = 10;
  for (const char* spec : kBackends) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    Values held;
    for (std::size_t i = 0; i < protocol.size(); ++i) {
      Step step = protocol.step(i, backend->estimate());
      if (i == fix_at) step.fixed.push_back(late);
      const Values before = backend->estimate();
      const UpdateResult r = backend->update(step);
      ASSERT_TRUE(r.status.ok()) << "step " << i << ": " << r.status.message;
      if (i == fix_at) held.insertEntry(late, before.entry(late));
      if (i >= fix_at)
        expectSameEntry(backend->estimate(), held, late, "step " + std::to_string(i));
    }
  }
}

// Pose 0 fixed and pose 0 held by a strong prior at the same value: the same
// optimum (a pose graph's optimum moves with its gauge, so the prior is met
// exactly), on every back-end, to 1e-6.
TEST(FixedVariables, PoseZeroFixedGivesTheOptimumOfAStrongPrior) {
  const Registry registry = registryWithPlugin();
  Graph fixed = testing::smallWorld();
  fixed.fixed = {X(0)};
  const Graph prior = testing::smallWorld();
  ThesisProtocol::Options strong;
  strong.prior_information = Eigen::Vector3d(1e8, 1e8, 1e8);
  const ThesisProtocol with_fix(fixed), with_prior(prior, strong);
  ASSERT_EQ(with_fix.prior(), nullptr);
  ASSERT_NE(with_prior.prior(), nullptr);
  auto reference = registry.makeBackend(kBackends[1]);
  ASSERT_TRUE(reference->update(with_prior.batch()).status.ok());
  for (const char* spec : kConverging) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    const UpdateResult r = backend->update(with_fix.batch());
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    for (Key k : reference->estimate().keys())
      for (int t = 0; t < reference->estimate().dim(k); ++t)
        EXPECT_NEAR(backend->estimate().data(k)[t], reference->estimate().data(k)[t], 1e-6)
            << k << "[" << t << "]";
  }
}

TEST(FixedVariables, AFixedKeyThatNamesNoVariableIsAnError) {
  const Registry registry = registryWithPlugin();
  const Graph g = testing::smallWorld();
  const ThesisProtocol protocol(g);
  for (const char* spec : kBackends) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    Step step = protocol.step(0, backend->estimate());
    step.fixed.push_back(X(99));
    try {
      backend->update(step);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("x99"), std::string::npos) << e.what();
    }
    // Nothing was recorded: the same step without the bad key goes through.
    step.fixed.clear();
    EXPECT_TRUE(backend->update(step).status.ok());
  }
}

TEST(FixedVariables, EverythingFixedIsNoWorkAndNoFailure) {
  const Registry registry = registryWithPlugin();
  Graph g;
  g.source = "two fixed poses";
  g.initial.insert(X(0), Pose2(0, 0, 0));
  g.initial.insert(X(1), Pose2(1, 0.2, 0.1));
  g.add(std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), Eigen::Matrix3d::Identity()));
  g.fixed = {X(0), X(1)};
  const ThesisProtocol protocol(g);
  for (const char* spec : kBackends) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    const UpdateResult r = backend->update(protocol.batch());
    EXPECT_TRUE(r.status.ok()) << r.status.message;
    for (Key k : g.fixed) expectSameEntry(backend->estimate(), g.initial, k, spec);
  }
}

}  // namespace
}  // namespace hamal
