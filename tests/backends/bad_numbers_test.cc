// Bad numbers through every built-in back-end: the conformance suite's
// (conformance/backend_conformance.h: a NaN, infinite or absurd measurement
// or an overflowing cost is never "ok"; a factor that names one variable
// twice and a guess that is not finite are in its bad-step table, run by
// tests/plugins/bad_step_test.cc), and cholesky tells ill-conditioning (one
// factor's information far above the others') from a direction nothing
// constrains.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "backends/builtins.h"
#include "conformance/backend_conformance.h"
#include "conformance/small_world.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/prior_factor.h"

namespace hamal {
namespace {

using testing::chainStep;

Registry builtins() {
  Registry r;
  registerBuiltins(r);
  return r;
}

std::vector<testing::Conformance> everyBuiltin() {
  std::vector<testing::Conformance> all;
  const Registry registry = builtins();
  for (const BackendInfo* info : registry.backends())
    all.push_back(testing::registered(info->name));
  return all;
}

bool contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

}  // namespace

namespace testing {
INSTANTIATE_TEST_SUITE_P(EveryBuiltin, BadNumbers, ::testing::ValuesIn(everyBuiltin()),
                         conformanceName);
}  // namespace testing

namespace {

TEST(BadNumbers, ACostBeyondWhatRoundingResolvesIsNeverOk) {
  // Finite, but no estimate is resolved: a loop closure of 1e151 m over
  // 1 m odometry (the optimum's chi2 is 3.3e301), and one of 3 m with
  // information 1e150 (the rounding of its residual alone is 1e59 sigma).
  // Ceres and AprilSAM called both converged; cholesky refuses its
  // singular system.
  const Registry registry = builtins();
  const Eigen::Matrix3d unit = Eigen::Matrix3d::Identity();
  const std::vector<FactorPtr> absurd = {
      std::make_shared<BetweenFactor>(X(0), X(2), Pose2(1e151, 0, 0), unit),
      std::make_shared<BetweenFactor>(X(0), X(2), Pose2(0, 0, 3), 1e150 * unit)};
  std::vector<std::string> names;
  for (const BackendInfo* info : registry.backends()) names.push_back(info->name);
  names.push_back("ceres:linear_solver=dense_qr");
  for (const std::string& name : names) {
    for (const FactorPtr& f : absurd) {
      SCOPED_TRACE(name + " " + std::to_string(f->chi2(chainStep(3, {}).new_values)));
      auto backend = registry.makeBackend(name);
      const UpdateResult r = backend->update(chainStep(3, {f}));
      EXPECT_EQ(r.status.code, Status::kNumericalFailure) << r.status.message;
      EXPECT_FALSE(r.status.keys.empty()) << r.status.message;
    }
  }
  auto ceres = registry.makeBackend("ceres");
  const UpdateResult r = ceres->update(chainStep(3, {absurd[0]}));
  // The 1e151 m spread over three edges: each is 1.1e301.
  EXPECT_TRUE(contains(r.status.message,
                       "has chi2 1.11e+301 at the estimate, a residual beyond "
                       "1/eps (4.5e+15) standard deviations"))
      << r.status.message;
  // The bound is far above any chi2 a sane graph reaches: a loop closure
  // 1e6 standard deviations off is still solved and ok.
  auto fine = registry.makeBackend("ceres");
  const UpdateResult off = fine->update(
      chainStep(3, {std::make_shared<BetweenFactor>(X(0), X(2), Pose2(2, 0, 0), 1e12 * unit)}));
  EXPECT_TRUE(off.status.ok()) << off.status.message;
}

TEST(BadNumbers, CholeskyNamesTheFactorThatMakesTheSystemIllConditioned) {
  // A loop closure with information 1e12 over odometry with 1: every
  // direction is constrained, the pivots are lost to rounding.
  const Registry registry = builtins();
  auto backend = registry.makeBackend("cholesky");
  const Eigen::Matrix3d strong = 1e12 * Eigen::Matrix3d::Identity();
  const UpdateResult r = backend->update(
      chainStep(50, {std::make_shared<BetweenFactor>(X(0), X(49), Pose2(49.5, 0.3, 0.1), strong)}));
  ASSERT_FALSE(r.status.ok());
  EXPECT_TRUE(contains(r.status.message, "ill-conditioned")) << r.status.message;
  EXPECT_TRUE(contains(r.status.message, "factor EDGE_SE2 on x0, x49")) << r.status.message;
  EXPECT_TRUE(contains(r.status.message, "condition estimate")) << r.status.message;
  EXPECT_FALSE(contains(r.status.message, "nothing constrains")) << r.status.message;
}

TEST(BadNumbers, CholeskyStillSaysWhenNothingConstrainsAVariable) {
  // x2 hangs on nothing but its initial value: a missing constraint, with
  // factors of alike scales, keeps the old diagnosis.
  const Registry registry = builtins();
  auto backend = registry.makeBackend("cholesky");
  Step s = chainStep(2, {});
  s.new_values.insert(X(2), Pose2(5, 0, 0));
  const UpdateResult r = backend->update(s);
  ASSERT_FALSE(r.status.ok());
  EXPECT_TRUE(contains(r.status.message, "x2")) << r.status.message;
  EXPECT_TRUE(contains(r.status.message, "nothing constrains it")) << r.status.message;
}

}  // namespace
}  // namespace hamal
