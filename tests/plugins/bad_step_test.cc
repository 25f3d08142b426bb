// The one input contract of every back-end (core/step.h, core/backend.h): a
// bad step throws hamal::Error and leaves the back-end as it was, so the
// next good step gives what it gives on a back-end that never saw the bad
// one. One table of bad steps runs through every registered back-end, the
// example plugin's included (it is the template plugin authors copy, which
// is why this suite lives with the plugin tests: it needs the plugin built).
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <functional>
#include <string>
#include <vector>

#include "backends/builtins.h"
#include "core/error.h"
#include "core/plugin.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/prior_factor.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

Registry everyBackend() {
  Registry registry;
  registerBuiltins(registry);
  loadPlugin(testing::buildPath("plugins/libhamal_example_plugin.so"), registry);
#ifdef HAMAL_GTSAM_PLUGIN  // built only where GTSAM is installed (plugins/gtsam)
  loadPlugin(testing::buildPath("plugins/libhamal_gtsam_plugin.so"), registry);
#endif
  return registry;
}

const Eigen::Matrix3d kInfo = Eigen::Matrix3d::Identity() * 100;

FactorPtr between(int a, int b, double dx) {
  return std::make_shared<BetweenFactor>(X(a), X(b), Pose2(dx, 0.1, 0.05), kInfo);
}

// Two good steps before the bad one, one after it.
Step first() {
  Step s;
  s.index = 0;
  s.new_values.insert(X(0), Pose2());
  s.new_values.insert(X(1), Pose2(1, 0, 0));
  s.new_factors = {std::make_shared<PriorFactor>(X(0), Pose2(), kInfo), between(0, 1, 1.0)};
  return s;
}
Step second() {
  Step s;
  s.index = 1;
  s.new_values.insert(X(2), Pose2(2, 0.2, 0.1));
  s.new_factors = {between(1, 2, 1.1)};
  return s;
}
Step after() {
  Step s;
  s.index = 3;
  s.new_values.insert(X(3), Pose2(3, 0.3, 0.2));
  s.new_factors = {between(2, 3, 0.9), between(0, 3, 3.0)};
  return s;
}

struct BadStep {
  const char* name;
  const char* says;  // a part of the message
  std::function<Step()> make;
};

// Each bad step also carries good parts (a new variable, a good factor)
// before the bad one, so that a back-end recording as it checks would show.
Step withGoodParts() {
  Step s;
  s.index = 2;
  s.new_values.insert(X(7), Pose2(2.5, 0, 0));
  s.new_factors = {between(2, 7, 0.5)};
  return s;
}

const BadStep kBadSteps[] = {
    {"VariableAddedTwice", "x1, which already exists",
     [] {
       Step s = withGoodParts();
       s.new_values.insert(X(1), Pose2());
       return s;
     }},
    {"NullFactor", "null factor",
     [] {
       Step s = withGoodParts();
       s.new_factors.push_back(nullptr);
       return s;
     }},
    {"FactorOnUnknownVariable", "unknown variable x9",
     [] {
       Step s = withGoodParts();
       s.new_factors.push_back(between(7, 9, 1));
       return s;
     }},
    {"ParameterSizeIsNotTheVariables", "expects 3 parameters for l0",
     [] {
       Step s = withGoodParts();
       s.new_values.insert(L(0), Point2(1, 1));
       s.new_factors.push_back(std::make_shared<BetweenFactor>(X(7), L(0), Pose2(),
                                                               kInfo));  // a pose factor on a point
       return s;
     }},
    {"FixedKeyNamesNoVariable", "fixes x8",
     [] {
       Step s = withGoodParts();
       s.fixed.push_back(X(8));
       return s;
     }},
};

class BadStepTest : public ::testing::TestWithParam<std::string> {};

TEST_P(BadStepTest, ThrowsAndLeavesTheBackendAsItWas) {
  const Registry registry = everyBackend();
  const std::string name = GetParam();
  auto reference = registry.makeBackend(name);
  reference->update(first());
  reference->update(second());
  reference->update(after());

  for (const BadStep& bad : kBadSteps) {
    SCOPED_TRACE(bad.name);
    auto backend = registry.makeBackend(name);
    backend->update(first());
    backend->update(second());
    const Values before = backend->estimate();
    try {
      backend->update(bad.make());
      ADD_FAILURE() << name << " accepted a bad step";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(bad.says), std::string::npos) << e.what();
    }
    ASSERT_EQ(backend->estimate().size(), before.size());
    for (const auto& [key, entry] : before)
      EXPECT_EQ(backend->estimate().entry(key).data, entry.data) << key.str();

    const UpdateResult next = backend->update(after());
    EXPECT_TRUE(next.status.ok()) << next.status.message;
    ASSERT_EQ(backend->estimate().size(), reference->estimate().size());
    for (const auto& [key, entry] : reference->estimate())
      for (std::size_t k = 0; k < entry.data.size(); ++k)
        EXPECT_NEAR(backend->estimate().entry(key).data[k], entry.data[k], 1e-12) << key.str();
  }
}

// Evaluated when the tests are listed: a plugin that fails to load leaves
// the built-ins, and CoversTheBuiltinsAndThePlugin fails.
std::vector<std::string> backendNames() {
  Registry registry;
  registerBuiltins(registry);
  try {
    loadPlugin(testing::buildPath("plugins/libhamal_example_plugin.so"), registry);
#ifdef HAMAL_GTSAM_PLUGIN
    loadPlugin(testing::buildPath("plugins/libhamal_gtsam_plugin.so"), registry);
#endif
  } catch (const Error&) {
  }
  std::vector<std::string> names;
  for (const BackendInfo* info : registry.backends()) names.push_back(info->name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(EveryBackend, BadStepTest, ::testing::ValuesIn(backendNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string s = info.param;
                           for (char& c : s)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return s;
                         });

// The table reaches every back-end: the built-in ones and the plugin's.
TEST(BadStepTable, CoversTheBuiltinsAndThePlugin) {
  const std::vector<std::string> names = backendNames();
  for (const char* expected : {"ceres", "cholesky", "aprilsam", "dense-gauss-newton"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
#ifdef HAMAL_GTSAM_PLUGIN
  for (const char* expected : {"isam2", "gtsam-lm"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
#endif
}

}  // namespace
}  // namespace hamal
