// The back-end conformance suite's tests: see backend_conformance.h.
#include "conformance/backend_conformance.h"

#include <ceres/loss_function.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <limits>

#include "backends/builtins.h"
#include "conformance/bad_step_table.h"
#include "conformance/small_world.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/plugin.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/prior_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal::testing {

void PrintTo(const Conformance& c, std::ostream* os) { *os << c.name; }

Conformance registered(const std::string& spec, const std::vector<std::string>& plugins,
                       double optimum_tolerance) {
  Conformance c;
  c.name = spec.substr(0, spec.find(':'));
  c.optimum_tolerance = optimum_tolerance;
  c.make = [spec, plugins]() {
    // The registry outlives the back-end: a plugin's code stays loaded.
    static std::vector<std::unique_ptr<Registry>> registries;
    auto registry = std::make_unique<Registry>();
    registerBuiltins(*registry);
    for (const std::string& path : plugins) loadPlugin(path, *registry);
    std::unique_ptr<Backend> backend = registry->makeBackend(spec);
    registries.push_back(std::move(registry));
    return backend;
  };
  return c;
}

std::string conformanceName(const ::testing::TestParamInfo<Conformance>& info) {
  std::string s = info.param.name;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

bool conformanceLinked() { return true; }

// A test binary may instantiate a part of the suite (tests/plugins runs the
// bad-step table alone through every registered back-end).
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(BadSteps);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(BadNumbers);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(Fixed);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(Losses);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(Gauge);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(Protocol);

namespace {

// The optimum every back-end is compared with.
Values choleskyOptimum(const Step& batch) {
  auto cholesky = registered("cholesky:function_tolerance=1e-14").make();
  const UpdateResult r = cholesky->update(batch);
  EXPECT_TRUE(r.status.ok()) << "cholesky: " << r.status.message;
  return cholesky->estimate();
}

void expectNear(const Values& got, const Values& want, double tolerance, const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  for (Key k : want.keys()) {
    ASSERT_TRUE(got.contains(k)) << what << ": no " << k;
    for (int t = 0; t < want.dim(k); ++t)
      EXPECT_NEAR(got.data(k)[t], want.data(k)[t], tolerance)
          << what << ": " << k << "[" << t << "]";
  }
}

void expectUnmoved(const Values& got, const Values& held, const std::string& what) {
  for (Key k : held.keys())
    for (int t = 0; t < held.dim(k); ++t)
      EXPECT_EQ(got.data(k)[t], held.data(k)[t])
          << what << ": fixed " << k << "[" << t << "] moved";
}

bool finite(const Values& values) {
  for (const auto& [key, entry] : values)
    for (double d : entry.data)
      if (!std::isfinite(d)) return false;
  return true;
}

// What an update on bad numbers may do: refuse the step as bad input, or
// report a failure that says what; if it says ok, its estimate and chi2 must
// be finite. Any other exception, or an abort, fails.
void expectNeverNonFiniteOk(Backend& backend, const Step& step) {
  UpdateResult r;
  try {
    r = backend.update(step);
  } catch (const Error&) {
    return;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "threw something other than hamal::Error: " << e.what();
    return;
  }
  if (!r.status.ok()) {
    EXPECT_FALSE(r.status.message.empty()) << "a failure that says nothing";
    return;
  }
  double total = 0;
  for (const FactorPtr& f : step.new_factors) total += f->chi2(backend.estimate());
  EXPECT_TRUE(finite(backend.estimate())) << "ok with a non-finite estimate";
  EXPECT_TRUE(std::isfinite(total)) << "ok with chi2 " << total;
}

double largestDifference(const Values& a, const Values& b) {
  double d = 0;
  for (Key k : a.keys())
    for (int t = 0; t < a.dim(k); ++t) d = std::max(d, std::abs(a.data(k)[t] - b.data(k)[t]));
  return d;
}

// What a failed update may leave: the estimate of before, every variable
// that existed then at its value (fixed ones included), the step's new ones
// at their guesses.
void expectAsItWas(const Values& got, const Values& before, const Step& step,
                   const std::string& what) {
  ASSERT_EQ(got.size(), before.size() + step.new_values.size()) << what;
  for (const Values* held : {&before, &step.new_values})
    for (Key k : held->keys()) {
      ASSERT_TRUE(got.contains(k)) << what << ": no " << k;
      for (int t = 0; t < held->dim(k); ++t)
        EXPECT_EQ(got.data(k)[t], held->data(k)[t]) << what << ": " << k << "[" << t << "] moved";
    }
}

// Four poses round a loop, joined by relative measurements only.
Step unanchoredLoop() {
  Step s;
  for (int i = 0; i < 4; ++i) s.new_values.insert(X(i), Pose2(1.1 * i, 0.1 * i, 0.05 * i));
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i)
    s.new_factors.push_back(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0), info));
  s.new_factors.push_back(std::make_shared<BetweenFactor>(X(0), X(3), Pose2(3, 0.2, 0), info));
  return s;
}

FactorPtr closure(const Pose2& z) {
  return std::make_shared<BetweenFactor>(X(0), X(5), z, Eigen::Matrix3d::Identity());
}

}  // namespace

TEST_P(BadSteps, ThrowAndLeaveTheBackendAsItWas) {
  const Conformance& c = GetParam();
  auto reference = c.make();
  reference->update(firstGoodStep());
  reference->update(secondGoodStep());
  ASSERT_TRUE(reference->update(goodStepAfter()).status.ok());

  for (const BadStep& bad : badSteps()) {
    SCOPED_TRACE(bad.name);
    auto backend = c.make();
    backend->update(firstGoodStep());
    backend->update(secondGoodStep());
    const Values before = backend->estimate();
    try {
      backend->update(bad.make());
      ADD_FAILURE() << c.name << " accepted a bad step";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad.says), std::string::npos) << e.what();
    }
    ASSERT_EQ(backend->estimate().size(), before.size());
    for (const auto& [key, entry] : before)
      EXPECT_EQ(backend->estimate().entry(key).data, entry.data) << key.str();

    const UpdateResult next = backend->update(goodStepAfter());
    EXPECT_TRUE(next.status.ok()) << next.status.message;
    expectNear(backend->estimate(), reference->estimate(), 1e-12, "after the bad step");
  }
}

TEST_P(BadNumbers, ANonFiniteMeasurementIsNeverOk) {
  const double inf = std::numeric_limits<double>::infinity();
  for (const Pose2& z : {Pose2(std::nan(""), 0, 0), Pose2(0, inf, 0), Pose2(5, 0, -inf)}) {
    SCOPED_TRACE("measurement " + std::to_string(z.x) + " " + std::to_string(z.y) + " " +
                 std::to_string(z.theta));
    auto backend = GetParam().make();
    expectNeverNonFiniteOk(*backend, chainStep(6, {closure(z)}));
  }
}

TEST_P(BadNumbers, AnAbsurdMeasurementIsNeverOk) {
  // No estimate gives this loop closure a finite chi2.
  auto backend = GetParam().make();
  const Step s = chainStep(6, {closure(Pose2(1e300, 0, 0))});
  const UpdateResult r = backend->update(s);
  EXPECT_FALSE(r.status.ok()) << "ok with chi2 " << chi2(s.new_factors, backend->estimate());
  EXPECT_FALSE(r.status.message.empty());
}

TEST_P(BadNumbers, ACostThatOverflowsIsNeverOk) {
  // Two priors 20 m apart with information 1e306: each term is finite where
  // the solve starts and their sum is not. Solving it (the midpoint is
  // finite) or refusing it are both right; an infinite chi2 called ok is not.
  const Eigen::Matrix3d huge = 1e306 * Eigen::Matrix3d::Identity();
  auto backend = GetParam().make();
  expectNeverNonFiniteOk(
      *backend, chainStep(3, {std::make_shared<PriorFactor>(X(2), Pose2(12, 0, 0), huge),
                              std::make_shared<PriorFactor>(X(2), Pose2(-8, 0, 0), huge)}));
}

TEST_P(BadNumbers, TheBackendGoesOnAfterAFailure) {
  auto backend = GetParam().make();
  Step bad = chainStep(6, {closure(Pose2(std::nan(""), 0, 0))});
  try {
    backend->update(bad);
  } catch (const Error&) {
    return;  // refused as bad input: nothing was recorded
  }
  // The failed update leaves an estimate the next step can start from.
  Step next;
  next.index = 1;
  next.new_values.insert(X(6), Pose2(6, 0, 0));
  next.new_factors = {
      std::make_shared<BetweenFactor>(X(5), X(6), Pose2(1, 0, 0), Eigen::Matrix3d::Identity())};
  UpdateResult r;
  EXPECT_NO_THROW(r = backend->update(next));
  if (r.status.ok()) {
    EXPECT_TRUE(finite(backend->estimate()));
  }
}

TEST_P(BadNumbers, AFailureLeavesTheEstimateAsItWas) {
  // A known chain with a fixed pose, then a step that no estimate makes
  // finite: whatever the back-end tried on the way to its failure, the
  // estimate it then holds is the one it had, not a half-made or NaN one.
  auto backend = GetParam().make();
  Step first = chainStep(6);
  first.fixed = {X(2)};
  ASSERT_TRUE(backend->update(first).status.ok());
  const Values before = backend->estimate();
  Step bad;
  bad.index = 1;
  bad.new_values.insert(X(6), Pose2(6, 0, 0));
  bad.new_factors = {
      std::make_shared<BetweenFactor>(X(5), X(6), Pose2(1, 0, 0), Eigen::Matrix3d::Identity()),
      std::make_shared<BetweenFactor>(X(0), X(6), Pose2(1e300, 0, 0), Eigen::Matrix3d::Identity())};
  UpdateResult r;
  try {
    r = backend->update(bad);
  } catch (const Error&) {
    return;  // refused as bad input: nothing was recorded
  }
  ASSERT_FALSE(r.status.ok()) << "ok with an absurd loop closure";
  if (r.status.code == Status::kNumericalFailure)
    expectAsItWas(backend->estimate(), before, bad, "after the failure");
  else
    EXPECT_TRUE(finite(backend->estimate())) << toString(r.status.code);
}

TEST_P(Losses, ARobustLossIsPartOfTheCost) {
  // A loop closure 3 m and 0.8 rad off the chain's odometry: least squares
  // bends the chain about a third of the way to it, a Cauchy loss of scale
  // 0.1 keeps it nearly straight.
  const auto far = [](bool robust) {
    auto f = std::make_shared<BetweenFactor>(X(0), X(5), Pose2(5, 3, 0.8),
                                             0.1 * Eigen::Matrix3d::Identity());
    if (robust) f->setLoss(std::make_shared<ceres::CauchyLoss>(0.1));
    return f;
  };
  const Step robust = chainStep(6, {far(true)});
  const Values optimum = choleskyOptimum(robust);
  const Values plain = choleskyOptimum(chainStep(6, {far(false)}));
  const double apart = largestDifference(optimum, plain);
  ASSERT_GT(apart, 0.5) << "the loss changes nothing here";

  // A back-end at its default tolerances stops short of the optimum; one
  // that drops the loss stops at the other.
  auto backend = GetParam().make();
  const UpdateResult r = backend->update(robust);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  expectNear(backend->estimate(), optimum, std::max(GetParam().optimum_tolerance, 0.05 * apart),
             "robust batch");
}

TEST_P(Gauge, NothingAnchoredIsANumericalFailureThatLosesNothing) {
  auto backend = GetParam().make();
  const Step loop = unanchoredLoop();
  UpdateResult r;
  try {
    r = backend->update(loop);
  } catch (const std::exception& e) {
    FAIL() << "threw on a graph with no prior: " << e.what();
  }
  EXPECT_EQ(r.status.code, Status::kNumericalFailure)
      << toString(r.status.code) << ": " << r.status.message;
  EXPECT_FALSE(r.status.message.empty());
  EXPECT_FALSE(r.status.keys.empty()) << "names no variable";
  expectAsItWas(backend->estimate(), Values(), loop, "unanchored");

  // The factors were kept: a prior in the next step makes the graph whole.
  Step anchor;
  anchor.index = 1;
  anchor.new_factors = {std::make_shared<PriorFactor>(X(0), Pose2(), Eigen::Matrix3d::Identity())};
  const UpdateResult next = backend->update(anchor);
  ASSERT_TRUE(next.status.ok()) << next.status.message;
  Step whole = loop;
  whole.new_factors.push_back(anchor.new_factors.front());
  const Values optimum = choleskyOptimum(whole);
  // Within a twentieth of the way from the guesses, for a back-end at its
  // default tolerances (the guesses are 0.3 m from the optimum).
  expectNear(
      backend->estimate(), optimum,
      std::max(GetParam().optimum_tolerance, 0.05 * largestDifference(optimum, loop.new_values)),
      "anchored later");
}

TEST_P(Fixed, NeverMoveInABatchAndNeedNoPrior) {
  Graph g = smallWorld();
  g.fixed = {X(0), X(9), L(2)};
  const ThesisProtocol protocol(g);
  ASSERT_EQ(protocol.prior(), nullptr) << "a fixed pose fixes the gauge";
  const Step batch = protocol.batch();
  const Values optimum = choleskyOptimum(batch);
  Values held;
  for (Key k : g.fixed) held.insertEntry(k, batch.new_values.entry(k));

  auto backend = GetParam().make();
  const UpdateResult r = backend->update(batch);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  expectUnmoved(backend->estimate(), held, "batch");
  expectNear(backend->estimate(), optimum, GetParam().optimum_tolerance, "batch");
}

TEST_P(Fixed, NeverMoveAtAnyStepOfTheThesisProtocol) {
  Graph g = smallWorld();
  g.fixed = {X(0), X(13), L(1)};
  const ThesisProtocol protocol(g);
  auto backend = GetParam().make();
  Values entered;  // each fixed variable's value in the step that added it
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const Step step = protocol.step(i, backend->estimate());
    for (Key k : step.fixed) entered.insertEntry(k, step.new_values.entry(k));
    const UpdateResult r = backend->update(step);
    ASSERT_TRUE(r.status.ok()) << "step " << i << ": " << r.status.message;
    expectUnmoved(backend->estimate(), entered, "step " + std::to_string(i));
  }
  EXPECT_EQ(entered.size(), g.fixed.size());
}

TEST_P(Fixed, AKnownVariableFixedLaterKeepsItsValue) {
  const ThesisProtocol protocol(smallWorld());
  const std::size_t fix_at = 10;
  auto backend = GetParam().make();
  Values held;
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    Step step = protocol.step(i, backend->estimate());
    if (i == fix_at) {
      step.fixed.push_back(X(4));
      held.insertEntry(X(4), backend->estimate().entry(X(4)));
    }
    const UpdateResult r = backend->update(step);
    ASSERT_TRUE(r.status.ok()) << "step " << i << ": " << r.status.message;
    expectUnmoved(backend->estimate(), held, "step " + std::to_string(i));
  }
}

TEST_P(Fixed, EverythingFixedIsNoWorkAndNoFailure) {
  Graph g;
  g.source = "two fixed poses";
  g.initial.insert(X(0), Pose2(0, 0, 0));
  g.initial.insert(X(1), Pose2(1, 0.2, 0.1));
  g.add(std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), Eigen::Matrix3d::Identity()));
  g.fixed = {X(0), X(1)};
  auto backend = GetParam().make();
  const UpdateResult r = backend->update(ThesisProtocol(g).batch());
  EXPECT_TRUE(r.status.ok()) << r.status.message;
  expectUnmoved(backend->estimate(), g.initial, "all fixed");
}

TEST_P(Protocol, EveryStepIsOkAndTheLastEndsAtCholeskysOptimum) {
  const ThesisProtocol protocol(smallWorld());
  const Values optimum = choleskyOptimum(protocol.batch());
  auto backend = GetParam().make();
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const UpdateResult r = backend->update(protocol.step(i, backend->estimate()));
    ASSERT_TRUE(r.status.ok()) << "step " << i << ": " << r.status.message;
    ASSERT_TRUE(finite(backend->estimate())) << "step " << i;
    EXPECT_EQ(r.variables, backend->estimate().size()) << "step " << i;
  }
  expectNear(backend->estimate(), optimum, GetParam().optimum_tolerance, "last step");
}

TEST_P(Protocol, ABatchSolveReachesCholeskysOptimum) {
  const ThesisProtocol protocol(smallWorld());
  const Step batch = protocol.batch();
  auto backend = GetParam().make();
  const UpdateResult r = backend->update(batch);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_GE(r.time.total(), 0.0);
  expectNear(backend->estimate(), choleskyOptimum(batch), GetParam().optimum_tolerance, "batch");
}

}  // namespace hamal::testing
