// The component-switch hook (MultiModal::mode, AprilSamBackend's
// ComponentSwitchHook, component_switch_hook.h): a max-mixture linearised with one component
// whose active component at the estimate changes after a late measurement
// gets its rows recomputed, so AprilSAM's incremental estimate equals the
// batch optimum of the same model that cholesky and ceres find (to 1e-6).
// The graphs: tests/aprilsam/component_switch_graph.h.
#include <gtest/gtest.h>

#include <iostream>
#include <memory>
#include <random>
#include <string>

#include "backends/builtins.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "factors/max_mixture_factor.h"
#include "protocol/thesis_protocol.h"
#include "tests/aprilsam/aprilsam_test_graphs.h"
#include "tests/aprilsam/component_switch_graph.h"

namespace hamal {
namespace {

using testing::kSwitchClosureStep;
using testing::kSwitchPoses;
using Scenario = testing::SwitchScenario;

class ComponentSwitch : public ::testing::TestWithParam<Scenario> {};

TEST_P(ComponentSwitch, AprilSamEndsAtTheBatchOptimumOfTheSameModel) {
  const Scenario& s = GetParam();
  Registry registry;
  registerBuiltins(registry);
  const auto mixture = testing::switchMixture(s);

  // The reference: cholesky solved to convergence on all factors at once,
  // the null hypothesis' term in its system.
  auto reference = registry.makeBackend("cholesky:function_tolerance=1e-15,dormant_scale=0");
  const Step all = testing::switchBatch(testing::switchSteps(s, mixture));
  ASSERT_TRUE(reference->update(all).status.ok());
  const Values& optimum = reference->estimate();
  EXPECT_EQ(mixture->activeComponent(optimum), s.final);

  // Incremental runs: AprilSAM never batching after the first step (so only
  // the hook can fix the mixture's rows), with exact back-substitution, and
  // its variants; cholesky and ceres re-solving at every step.
  const char* const specs[] = {
      "aprilsam:mode=incremental,backsolve_tolerance=0",
      "aprilsam:mode=incremental,backsolve_tolerance=0,factor_update=refactor",
      "aprilsam-fullsolve:mode=incremental",
      "aprilsam:backsolve_tolerance=0",
      // A batch at the GPS step: the switch it causes is found after the
      // batch's solve, with no switch pass before it.
      "aprilsam:mode=periodic,period=11,backsolve_tolerance=0",
      "cholesky:function_tolerance=1e-15",
      "ceres:function_tolerance=1e-15,parameter_tolerance=1e-14,gradient_tolerance=1e-16",
  };
  for (const char* spec : specs) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    std::size_t switches = 0, raised = 0;
    for (const Step& st : testing::switchSteps(s, mixture)) {
      const UpdateResult r = backend->update(st);
      ASSERT_TRUE(r.status.ok()) << "step " << st.index << ": " << r.status.message;
      if (st.index == static_cast<std::size_t>(kSwitchClosureStep))
        EXPECT_EQ(mixture->activeComponent(backend->estimate()), s.initial);
      if (r.reason.find("switched mode") != std::string::npos) ++switches;
      if (r.reason.find("nominal rows added") != std::string::npos) ++raised;
    }
    EXPECT_EQ(mixture->activeComponent(backend->estimate()), s.final);
    if (std::string(spec).rfind("aprilsam:mode=incremental", 0) == 0) {
      EXPECT_GE(switches, 1u) << "the hook never fired";
      // A null pair turning nominal takes the rank-update path (its nominal
      // added at the linearisation point); the other way relinearises.
      EXPECT_EQ(raised > 0, s.initial == 1 && s.final == 0) << raised << " raised switches";
    }
    for (int i = 0; i < kSwitchPoses; ++i)
      for (int t = 0; t < 3; ++t)
        EXPECT_NEAR(backend->estimate().data(X(i))[t], optimum.data(X(i))[t], 1e-6)
            << "x" << i << "[" << t << "]";
  }

  // The other component's optimum is far from this one: ending with the
  // mixture linearised in its first component would fail the check above.
  auto other = registry.makeBackend("cholesky:function_tolerance=1e-15");
  Step forced = all;
  for (auto& f : forced.new_factors)
    if (f == mixture) {
      // Only the first component (twice: a mixture needs two).
      const auto& c = mixture->components()[s.initial];
      f = std::make_shared<MaxMixtureFactor>(std::vector<MaxMixtureFactor::Component>{
          {c.factor, 0.5, c.information_scale}, {c.factor, 0.5, c.information_scale}});
    }
  ASSERT_TRUE(other->update(forced).status.ok());
  double differs = 0;
  for (int i = 0; i < kSwitchPoses; ++i)
    differs = std::max(differs, std::abs(other->estimate().pose(X(i)).x - optimum.pose(X(i)).x));
  EXPECT_GT(differs, 1e-4);
}

// Null -> nominal -> null: the first switch adds the nominal at the
// linearisation point (a raised switch), the second relinearises the
// factor's variables, which must take out the nominal R then holds, not the
// null mode its linearisation point shows; the estimate ends at the
// optimum of the same model.
TEST(ComponentSwitch, RaisedMixtureSwitchedOffAgainEndsAtTheOptimum) {
  Registry registry;
  registerBuiltins(registry);
  const Scenario s{"NullToNominalToNull", 7.0, 6.8, 1, 0, 1e-4};
  const auto mixture = MaxMixtureFactor::withNullHypothesis(
      std::make_shared<testing::LinearBetween>(X(0), X(kSwitchClosureStep),
                                               Eigen::Vector3d(s.closure_dx, 0, 0), 100.0),
      0.1, s.null_scale);
  std::vector<Step> all_steps = testing::switchSteps(s, mixture);
  for (int i = kSwitchPoses; i < kSwitchPoses + 2; ++i) {
    Step st;
    st.index = i;
    st.new_values.insert(X(i), Pose2(i + 0.3, 0.1, 0.0));
    st.new_factors.push_back(
        std::make_shared<testing::LinearBetween>(X(i - 1), X(i), Eigen::Vector3d(1, 0, 0), 100.0));
    // A second, stronger position of x5 where odometry puts it: the
    // closure is an outlier again.
    if (i == kSwitchPoses + 1)
      st.new_factors.push_back(std::make_shared<PositionFactor>(
          X(kSwitchClosureStep), Point2(5.0, 0.0), Eigen::Matrix2d::Identity() * 1e6));
    all_steps.push_back(st);
  }
  auto reference = registry.makeBackend("cholesky:function_tolerance=1e-15");
  Step all;
  for (const Step& st : all_steps) {
    for (const auto& [k, e] : st.new_values) all.new_values.insertEntry(k, e);
    all.new_factors.insert(all.new_factors.end(), st.new_factors.begin(), st.new_factors.end());
  }
  ASSERT_TRUE(reference->update(all).status.ok());
  const Values& optimum = reference->estimate();
  ASSERT_EQ(mixture->activeComponent(optimum), 1u);

  for (const char* spec :
       {"aprilsam:mode=incremental,backsolve_tolerance=0",
        "aprilsam:mode=incremental,backsolve_tolerance=0,factor_update=refactor"}) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    std::size_t raised = 0, relinearised = 0;
    for (const Step& st : all_steps) {
      const UpdateResult r = backend->update(st);
      ASSERT_TRUE(r.status.ok()) << "step " << st.index << ": " << r.status.message;
      if (r.reason.find("nominal rows added") != std::string::npos) ++raised;
      if (r.reason.find("relinearised") != std::string::npos) ++relinearised;
      if (st.index == static_cast<std::size_t>(testing::kSwitchGpsStep))
        EXPECT_EQ(mixture->activeComponent(backend->estimate()), 0u);
    }
    EXPECT_GE(raised, 1u);
    EXPECT_GE(relinearised, 1u);
    EXPECT_EQ(mixture->activeComponent(backend->estimate()), 1u);
    for (int i = 0; i < kSwitchPoses + 2; ++i)
      for (int t = 0; t < 3; ++t)
        EXPECT_NEAR(backend->estimate().data(X(i))[t], optimum.data(X(i))[t], 1e-6)
            << "x" << i << "[" << t << "]";
  }
}

// A nonlinear pose graph whose loop closures are mixtures, with false ones
// among them: under the thesis protocol AprilSAM switches off the same edges
// as a converged cholesky batch solve, and ends at its chi2 (AprilSAM takes
// one Gauss-Newton step per batch, so to 1e-3 relative, not 1e-6).
TEST(ComponentSwitch, FalseLoopClosuresAreSwitchedOffAsInTheBatchOptimum) {
  Registry registry;
  registerBuiltins(registry);
  aprilsam::testing::RandomGraphOptions options;
  options.poses = 120;
  Graph g = aprilsam::testing::randomGraph(options);
  std::vector<const MaxMixtureFactor*> true_edges, false_edges;
  for (FactorPtr& f : g.factors)
    if (f->keys()[1].index() - f->keys()[0].index() != 1) {
      f = MaxMixtureFactor::withNullHypothesis(f, 0.01, 1e-9);
      true_edges.push_back(static_cast<const MaxMixtureFactor*>(f.get()));
    }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int n = 0; n < 15; ++n) {
    const int a = static_cast<int>(rng() % 110), b = a + 5 + static_cast<int>(rng() % 5);
    g.add(MaxMixtureFactor::withNullHypothesis(
        std::make_shared<BetweenFactor>(X(a), X(b), Pose2(u(rng), u(rng), u(rng)),
                                        Eigen::Vector3d(100, 50, 400).asDiagonal()),
        0.01, 1e-9));
    false_edges.push_back(static_cast<const MaxMixtureFactor*>(g.factors.back().get()));
  }
  ASSERT_GT(true_edges.size(), 20u);
  const ThesisProtocol protocol(g);
  auto reference = registry.makeBackend("cholesky:function_tolerance=1e-12");
  ASSERT_TRUE(reference->update(protocol.batch()).status.ok());
  const double best = chi2(g.factors, reference->estimate());
  for (const auto* f : false_edges) EXPECT_EQ(f->activeComponent(reference->estimate()), 1u);
  for (const auto* f : true_edges) EXPECT_EQ(f->activeComponent(reference->estimate()), 0u);

  // Without any batch AprilSAM never relinearises the rest of the graph:
  // its chi2 is further off, whatever the mixtures do.
  const std::pair<const char*, double> runs[] = {
      {"aprilsam", 1e-3}, {"aprilsam-periodic", 1e-3}, {"aprilsam:mode=incremental", 1e-2}};
  for (const auto& [spec, tolerance] : runs) {
    SCOPED_TRACE(spec);
    auto backend = registry.makeBackend(spec);
    for (std::size_t i = 0; i < protocol.size(); ++i)
      ASSERT_TRUE(backend->update(protocol.step(i, backend->estimate())).status.ok()) << i;
    const Values& end = backend->estimate();
    for (const auto* f : false_edges) EXPECT_EQ(f->activeComponent(end), 1u);
    for (const auto* f : true_edges) EXPECT_EQ(f->activeComponent(end), 0u);
    EXPECT_NEAR(chi2(g.factors, end), best, tolerance * best);
  }
}

// A dormant mixture (its null hypothesis active, information scale below
// dormant_scale) is out of the system: a graph with 1000 random false loop
// closures as dormant mixtures has the same R, entry for entry in number, as
// the graph without them, and the same estimate; with dormant_scale=0 the
// same mixtures fill R in.
TEST(ComponentSwitch, DormantMixturesAddNoFill) {
  Registry registry;
  registerBuiltins(registry);
  aprilsam::testing::RandomGraphOptions options;
  options.poses = 150;
  options.loop_probability = 0.02;  // a sparse R, so that fill shows
  const Graph clean = aprilsam::testing::randomGraph(options);
  Graph spoiled = clean;
  testing::addFalseLoopClosures(&spoiled, options.poses, 1000, 7, 1e-12);
  struct Run {
    std::size_t stored = 0;
    long columns = 0, dormant = 0;
    int batches = 0;
    Values estimate;
  };
  auto run = [&](const Graph& g, const std::string& spec) {
    const ThesisProtocol protocol(g);
    auto backend = registry.makeBackend(spec);
    for (std::size_t i = 0; i < protocol.size(); ++i) {
      const UpdateResult r = backend->update(protocol.step(i, backend->estimate()));
      EXPECT_TRUE(r.status.ok()) << spec << " step " << i << ": " << r.status.message;
    }
    const auto& a = dynamic_cast<const AprilSamBackend&>(*backend);
    return Run{a.factor().storedValues(), a.factor().columnsTotal(), a.dormantFactors(),
               a.batches(), backend->estimate()};
  };
  const Run plain = run(clean, "aprilsam");
  const Run dormant = run(spoiled, "aprilsam");
  const Run kept = run(spoiled, "aprilsam:dormant_scale=0");
  EXPECT_EQ(dormant.dormant, 1000);
  EXPECT_EQ(kept.dormant, 0);
  EXPECT_EQ(dormant.stored, plain.stored);
  EXPECT_EQ(dormant.columns, plain.columns);
  EXPECT_EQ(dormant.batches, plain.batches);
  std::cout << "R's stored values: " << plain.stored << " clean, " << dormant.stored
            << " with 1000 dormant mixtures, " << kept.stored << " with them in R\n";
  EXPECT_GT(kept.stored, 2 * plain.stored) << "the mixtures in R should have filled it in";
  for (int i = 0; i < options.poses; ++i)
    for (int t = 0; t < 3; ++t)
      EXPECT_NEAR(dormant.estimate.data(X(i))[t], plain.estimate.data(X(i))[t], 1e-9)
          << "x" << i << "[" << t << "]";
}

INSTANTIATE_TEST_SUITE_P(Scenarios, ComponentSwitch,
                         ::testing::Values(
                             // The closure agrees with odometry when it arrives; the GPS then puts
                             // x5 2 m further: the closure becomes an outlier (nominal -> null).
                             Scenario{"NominalToNull", 5.0, 7.0, 0, 1, 1e-4},
                             // The closure disagrees with odometry when it arrives; the GPS then
                             // nearly confirms it (null -> nominal).
                             Scenario{"NullToNominal", 7.0, 6.8, 1, 0, 1e-4},
                             // The same with a null hypothesis below the dormant_scale of
                             // AprilSAM and cholesky: the mixture leaves their system when it
                             // switches off and enters it when it switches on; its null term,
                             // which the reference and ceres keep, moves the optimum by ~1e-9 of
                             // the nominal's pull.
                             Scenario{"NominalToDormant", 5.0, 7.0, 0, 1, 1e-9},
                             Scenario{"DormantToNominal", 7.0, 6.8, 1, 0, 1e-9}),
                         [](const ::testing::TestParamInfo<Scenario>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace hamal
