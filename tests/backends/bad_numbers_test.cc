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
