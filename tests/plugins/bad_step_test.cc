// The one input contract of every back-end (core/step.h, core/backend.h): a
// bad step throws hamal::Error and leaves the back-end as it was, so the
// next good step gives what it gives on a back-end that never saw the bad
// one. The conformance suite's bad-step table (conformance/bad_step_table.h)
// runs through every registered back-end, the example plugin's included (it
// is the template plugin authors copy, which is why this lives with the
// plugin tests: it needs the plugin built).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "backends/builtins.h"
#include "conformance/backend_conformance.h"
#include "core/error.h"
#include "core/plugin.h"
#include "testing/test_data.h"

namespace hamal {
namespace {

std::vector<std::string> plugins() {
  std::vector<std::string> paths = {testing::buildPath("plugins/libhamal_example_plugin.so")};
#ifdef HAMAL_GTSAM_PLUGIN  // built only where GTSAM is installed (plugins/gtsam)
  paths.push_back(testing::buildPath("plugins/libhamal_gtsam_plugin.so"));
#endif
  return paths;
}

// Evaluated when the tests are listed: a plugin that fails to load leaves
// the built-ins, and CoversTheBuiltinsAndThePlugin fails.
std::vector<std::string> backendNames() {
  Registry registry;
  registerBuiltins(registry);
  try {
    for (const std::string& path : plugins()) loadPlugin(path, registry);
  } catch (const Error&) {
  }
  std::vector<std::string> names;
  for (const BackendInfo* info : registry.backends()) names.push_back(info->name);
  return names;
}

std::vector<testing::Conformance> everyBackend() {
  std::vector<testing::Conformance> all;
  for (const std::string& name : backendNames())
    all.push_back(testing::registered(name, plugins()));
  return all;
}

// The table reaches every back-end: the built-in ones and the plugin's.
TEST(BadStepTable, CoversTheBuiltinsAndThePlugin) {
  const std::vector<std::string> names = backendNames();
  for (const char* expected : {"ceres", "cholesky", "aprilsam", "dense-gauss-newton"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
#ifdef HAMAL_GTSAM_PLUGIN
  for (const char* expected : {"isam2", "gtsam-lm", "gtsam-gnc"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
#endif
}

}  // namespace

namespace testing {
INSTANTIATE_TEST_SUITE_P(EveryBackend, BadSteps, ::testing::ValuesIn(everyBackend()),
                         conformanceName);
}  // namespace testing

}  // namespace hamal
