// The built-in batch back-ends through the conformance suite every plugin
// author runs (conformance/backend_conformance.h): cholesky, which defines
// the suite's optimum, and ceres at tolerances tight enough to reach it.
// And the suite is not a formality: back-ends broken in the ways it guards
// against (swallowing bad steps, moving fixed variables, calling a failure
// ok, stopping short of the optimum, dropping robust losses, throwing on a
// graph nothing anchors, writing NaN into the estimate on a failure) fail
// it, each where it should.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "backends/builtins.h"
#include "conformance/backend_conformance.h"
#include "core/error.h"
#include "core/gauge_freedom.h"
#include "core/registry.h"
#include "testing/command.h"
#include "testing/test_data.h"

HAMAL_BACKEND_CONFORMANCE(
    Builtin, hamal::testing::registered("cholesky:function_tolerance=1e-14"),
    hamal::testing::registered("ceres:function_tolerance=1e-14,parameter_tolerance=1e-12"));

namespace hamal {

namespace testing {
namespace {
// Every built-in back-end, AprilSAM's variants included, at its defaults.
std::vector<Conformance> everyBuiltin() {
  Registry registry;
  registerBuiltins(registry);
  std::vector<Conformance> all;
  for (const BackendInfo* info : registry.backends()) all.push_back(registered(info->name));
  return all;
}
}  // namespace
INSTANTIATE_TEST_SUITE_P(EveryBuiltin, Losses, ::testing::ValuesIn(everyBuiltin()),
                         conformanceName);
INSTANTIATE_TEST_SUITE_P(EveryBuiltin, Gauge, ::testing::ValuesIn(everyBuiltin()), conformanceName);
}  // namespace testing

namespace {

// Cholesky with one flaw.
class Flawed : public Backend {
 public:
  enum Flaw {
    kSwallowsBadSteps,
    kIgnoresFixed,
    kCallsEverythingOk,
    kIgnoresLosses,
    kThrowsWithoutAnchor,
    kNanOnFailure
  };
  Flawed(const std::string& spec, Flaw flaw)
      : inner_(testing::registered(spec).make()), flaw_(flaw) {}

  UpdateResult update(const Step& step) override {
    UpdateResult r = flawedUpdate(step);
    estimate_ = inner_->estimate();
    if (flaw_ == kNanOnFailure && !r.status.ok())
      for (Key k : estimate_.keys())
        for (int t = 0; t < estimate_.dim(k); ++t) estimate_.data(k)[t] = std::nan("");
    return r;
  }
  const Values& estimate() const override { return estimate_; }

 private:
  UpdateResult flawedUpdate(const Step& step) {
    if (flaw_ == kSwallowsBadSteps) {
      try {
        return inner_->update(step);
      } catch (const Error&) {
        return UpdateResult();
      }
    }
    if (flaw_ == kIgnoresFixed) {
      Step free = step;
      free.fixed.clear();
      return inner_->update(free);
    }
    if (flaw_ == kIgnoresLosses) {
      // As a back-end that never reads Factor::lossFunction (the step's
      // factors are the test's own, used after this only by this back-end).
      for (const FactorPtr& f : step.new_factors)
        if (f) f->setLoss(nullptr);
      return inner_->update(step);
    }
    // (Judged on a first step alone, where the step is the whole graph.)
    if (flaw_ == kThrowsWithoutAnchor && inner_->estimate().size() == 0 &&
        unanchoredVariable(step.new_values.keys(), step.new_factors, step.fixed))
      throw std::runtime_error("indeterminant linear system");
    UpdateResult r = inner_->update(step);
    if (flaw_ == kCallsEverythingOk) r.status = Status();
    return r;
  }

  std::unique_ptr<Backend> inner_;
  Flaw flaw_;
  Values estimate_;
};

testing::Conformance flawed(const std::string& name, const std::string& spec, Flawed::Flaw flaw) {
  return {name, [spec, flaw] { return std::make_unique<Flawed>(spec, flaw); }};
}

// Instantiated only in the child process that CatchesBrokenBackends starts.
std::vector<testing::Conformance> broken() {
  if (!std::getenv("HAMAL_CONFORMANCE_BROKEN")) return {};
  const std::string tight = "cholesky:function_tolerance=1e-14";
  return {flawed("swallows_bad_steps", tight, Flawed::kSwallowsBadSteps),
          flawed("ignores_fixed", tight, Flawed::kIgnoresFixed),
          flawed("calls_everything_ok", tight, Flawed::kCallsEverythingOk),
          flawed("stops_short", "cholesky:max_iterations=1", Flawed::kCallsEverythingOk),
          flawed("ignores_losses", tight, Flawed::kIgnoresLosses),
          flawed("throws_without_anchor", tight, Flawed::kThrowsWithoutAnchor),
          flawed("nan_on_failure", tight, Flawed::kNanOnFailure)};
}

TEST(Conformance, CatchesBrokenBackends) {
  const testing::CommandResult run = testing::runCommand(
      "HAMAL_CONFORMANCE_BROKEN=1 " + testing::buildPath("tests/test_backends") +
      " --gtest_filter='Broken/*' --gtest_brief=1");
  EXPECT_NE(run.status, 0) << run.output;
  EXPECT_EQ(run.signal, 0) << run.output;
  for (const char* failed : {
           "Broken/BadSteps.ThrowAndLeaveTheBackendAsItWas/swallows_bad_steps",
           "Broken/Fixed.NeverMoveInABatchAndNeedNoPrior/ignores_fixed",
           "Broken/Fixed.NeverMoveAtAnyStepOfTheThesisProtocol/ignores_fixed",
           "Broken/Fixed.AKnownVariableFixedLaterKeepsItsValue/ignores_fixed",
           "Broken/BadNumbers.ANonFiniteMeasurementIsNeverOk/calls_everything_ok",
           "Broken/BadNumbers.AnAbsurdMeasurementIsNeverOk/calls_everything_ok",
           "Broken/Protocol.ABatchSolveReachesCholeskysOptimum/stops_short",
           "Broken/Losses.ARobustLossIsPartOfTheCost/ignores_losses",
           "Broken/Gauge.NothingAnchoredIsANumericalFailureThatLosesNothing/throws_without_anchor",
           "Broken/Gauge.NothingAnchoredIsANumericalFailureThatLosesNothing/nan_on_failure",
           "Broken/BadNumbers.AFailureLeavesTheEstimateAsItWas/nan_on_failure",
       })
    EXPECT_NE(run.output.find(std::string("[  FAILED  ] ") + failed), std::string::npos)
        << failed << " passed:\n"
        << run.output;
  // Each flaw fails where it is, not everywhere: the tests it does not touch
  // pass.
  for (const char* passed : {
           "Broken/Protocol.EveryStepIsOkAndTheLastEndsAtCholeskysOptimum/swallows_bad_steps",
           "Broken/Protocol.EveryStepIsOkAndTheLastEndsAtCholeskysOptimum/ignores_fixed",
           "Broken/Fixed.NeverMoveAtAnyStepOfTheThesisProtocol/calls_everything_ok",
           "Broken/BadSteps.ThrowAndLeaveTheBackendAsItWas/calls_everything_ok",
           "Broken/Protocol.EveryStepIsOkAndTheLastEndsAtCholeskysOptimum/ignores_losses",
           "Broken/Protocol.EveryStepIsOkAndTheLastEndsAtCholeskysOptimum/throws_without_anchor",
           "Broken/Protocol.EveryStepIsOkAndTheLastEndsAtCholeskysOptimum/nan_on_failure",
           "Broken/Gauge.NothingAnchoredIsANumericalFailureThatLosesNothing/ignores_losses",
       })
    EXPECT_EQ(run.output.find(std::string("[  FAILED  ] ") + passed), std::string::npos)
        << passed << " failed:\n"
        << run.output;
}

}  // namespace

namespace testing {
INSTANTIATE_TEST_SUITE_P(Broken, BadSteps, ::testing::ValuesIn(broken()), conformanceName);
INSTANTIATE_TEST_SUITE_P(Broken, BadNumbers, ::testing::ValuesIn(broken()), conformanceName);
INSTANTIATE_TEST_SUITE_P(Broken, Fixed, ::testing::ValuesIn(broken()), conformanceName);
INSTANTIATE_TEST_SUITE_P(Broken, Losses, ::testing::ValuesIn(broken()), conformanceName);
INSTANTIATE_TEST_SUITE_P(Broken, Gauge, ::testing::ValuesIn(broken()), conformanceName);
INSTANTIATE_TEST_SUITE_P(Broken, Protocol, ::testing::ValuesIn(broken()), conformanceName);
}  // namespace testing

}  // namespace hamal
