// The example plugin through hamal's conformance suite (hamal::testing), as
// its author runs it: the plugin is loaded as any user loads it; its
// back-end keeps every contract a built-in one keeps and ends the thesis
// protocol at cholesky's optimum (conformance/backend_conformance.h), and
// its factor kind reads back what it writes
// (conformance/factor_round_trip.h) with analytic Jacobians equal to
// numeric ones (core/jacobian_check.h).
#include <gtest/gtest.h>

#include "conformance/backend_conformance.h"
#include "conformance/factor_round_trip.h"
#include "core/jacobian_check.h"
#include "core/plugin.h"
#include "factors/register_factors.h"

// The plugin this test loads: set by CMakeLists.txt to the one just built.
#ifndef HAMAL_EXAMPLE_PLUGIN
#error "HAMAL_EXAMPLE_PLUGIN must name the plugin's shared library"
#endif

// A step tolerance rounding can reach (|dx| stalls near 4e-12 on the small
// world): a back-end that stops at max_iterations is not_converged, never ok.
HAMAL_BACKEND_CONFORMANCE(ExamplePlugin,
                          hamal::testing::registered("dense-gauss-newton:tolerance=1e-10",
                                                     {HAMAL_EXAMPLE_PLUGIN}));

namespace {

TEST(ExamplePluginFactor, RoundTripsAndHasExactJacobians) {
  hamal::Registry registry;
  hamal::registerFactors(registry);
  hamal::loadPlugin(HAMAL_EXAMPLE_PLUGIN, registry);
  const std::string line = "EDGE_SE2_CAUCHY 0 1 1.5 -0.25 0.3 1 0.02 0.01 0.8 0 4 0.7";
  hamal::LineTokens tokens = hamal::LineTokens::split("test.g2o", 1, line);
  tokens.setRegistry(&registry, "g2o");
  const hamal::FactorPtr f = registry.parseFactor(tokens);
  ASSERT_NE(f, nullptr);
  EXPECT_TRUE(hamal::testing::roundTrips(*f, &registry));
  const hamal::JacobianCheckResult check = hamal::checkJacobians(*f);
  EXPECT_TRUE(check.ok) << check.report;
}

}  // namespace
