// The built-in batch back-ends through the conformance suite every plugin
// author runs (conformance/backend_conformance.h): cholesky, which defines
// the suite's optimum, and ceres at tolerances tight enough to reach it.
// And the suite is not a formality: back-ends broken in the ways it guards
// against (swallowing bad steps, moving fixed variables, calling a failure
// ok, stopping short of the optimum) fail it, each where it should.
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "conformance/backend_conformance.h"
#include "core/error.h"
#include "testing/command.h"
#include "testing/test_data.h"

HAMAL_BACKEND_CONFORMANCE(
    Builtin, hamal::testing::registered("cholesky:rel_tolerance=1e-14"),
    hamal::testing::registered("ceres:function_tolerance=1e-14,parameter_tolerance=1e-12"));

namespace hamal {
namespace {

// Cholesky with one flaw.
class Flawed : public Backend {
 public:
  enum Flaw { kSwallowsBadSteps, kIgnoresFixed, kCallsEverythingOk };
  Flawed(const std::string& spec, Flaw flaw)
      : inner_(testing::registered(spec).make()), flaw_(flaw) {}

  UpdateResult update(const Step& step) override {
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
    UpdateResult r = inner_->update(step);
    r.status = Status();
    return r;
  }
  const Values& estimate() const override { return inner_->estimate(); }

 private:
  std::unique_ptr<Backend> inner_;
  Flaw flaw_;
};

testing::Conformance flawed(const std::string& name, const std::string& spec, Flawed::Flaw flaw) {
  return {name, [spec, flaw] { return std::make_unique<Flawed>(spec, flaw); }};
}

// Instantiated only in the child process that CatchesBrokenBackends starts.
std::vector<testing::Conformance> broken() {
  if (!std::getenv("HAMAL_CONFORMANCE_BROKEN")) return {};
  const std::string tight = "cholesky:rel_tolerance=1e-14";
  return {flawed("swallows_bad_steps", tight, Flawed::kSwallowsBadSteps),
          flawed("ignores_fixed", tight, Flawed::kIgnoresFixed),
          flawed("calls_everything_ok", tight, Flawed::kCallsEverythingOk),
          flawed("stops_short", "cholesky:max_iterations=1", Flawed::kCallsEverythingOk)};
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
INSTANTIATE_TEST_SUITE_P(Broken, Protocol, ::testing::ValuesIn(broken()), conformanceName);
}  // namespace testing

}  // namespace hamal
