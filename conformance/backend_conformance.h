// The back-end conformance suite (installed with hamal as hamal::testing):
// the contracts every back-end keeps (core/backend.h, core/step.h,
// core/finite_result.h), as GoogleTest tests a back-end's author runs on
// their own back-end with one line:
//
//   #include "conformance/backend_conformance.h"
//   HAMAL_BACKEND_CONFORMANCE(MyBackend, hamal::testing::Conformance{
//       "my-backend", [] { return std::make_unique<MyBackend>(); }});
//
// or, for a back-end registered by a plugin (a spec, core/registry.h):
//
//   HAMAL_BACKEND_CONFORMANCE(MyBackend,
//       hamal::testing::registered("my-backend:tolerance=1e-12", {"path/to/plugin.so"}));
//
// and links hamal::testing and GTest::gtest_main. The tests:
//
//   BadSteps   the bad-step table (conformance/bad_step_table.h): each
//              throws hamal::Error and leaves the back-end as it was.
//   BadNumbers a NaN, infinite or absurd measurement, or a cost that
//              overflows: a not-ok Status (or hamal::Error), never an
//              abort, never "ok" with a non-finite estimate or chi2; a
//              numerical failure leaves the estimate as it was before the
//              update (new variables at their guesses), fixed ones included.
//   Fixed      fixed variables (Step::fixed) never move, in a batch, at
//              every step of the thesis protocol and when fixed later; a
//              graph that fixes a pose needs no prior; everything fixed is
//              no work and no failure.
//   Losses     a factor's robust loss (Factor::lossFunction) is part of
//              the cost: a loop closure far off, under a Cauchy loss, ends
//              at cholesky's robust optimum, not at the least-squares one.
//   Gauge      a graph that nothing anchors (no prior, no fixed variable;
//              core/gauge_freedom.h) has no unique solution: a
//              numerical-failure Status naming a variable, the estimate
//              left at the guesses, and a prior in the next step solves it.
//   Protocol   the thesis protocol (thesis sec. 3.5.1, docs/PROTOCOL.md) on
//              a small world (conformance/small_world.h): every step ok and
//              finite, ending at cholesky's batch optimum within the
//              tolerance; a batch solve reaches it too.
//
// The optimum is cholesky's at tight tolerances: a back-end that stops
// short of convergence (one Gauss-Newton step per update, as AprilSAM)
// needs a looser `optimum_tolerance`, or tighter options in its spec.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "core/backend.h"

namespace hamal::testing {

struct Conformance {
  std::string name;  // names the instantiated tests (non-alphanumerics become _)
  std::function<std::unique_ptr<Backend>()> make;  // a fresh back-end per call
  // Largest |difference| of any estimate component from cholesky's optimum.
  double optimum_tolerance = 1e-6;
};
void PrintTo(const Conformance& c, std::ostream* os);

// A back-end made from `spec` by a registry holding the built-in back-ends
// and the `plugins` (paths of shared libraries, core/plugin.h), loaded when
// a test makes the back-end, so a plugin that fails to load fails the test.
Conformance registered(const std::string& spec, const std::vector<std::string>& plugins = {},
                       double optimum_tolerance = 1e-6);

class BadSteps : public ::testing::TestWithParam<Conformance> {};
class BadNumbers : public ::testing::TestWithParam<Conformance> {};
class Fixed : public ::testing::TestWithParam<Conformance> {};
class Losses : public ::testing::TestWithParam<Conformance> {};
class Gauge : public ::testing::TestWithParam<Conformance> {};
class Protocol : public ::testing::TestWithParam<Conformance> {};

// The test name of an instantiation: Conformance::name made an identifier.
std::string conformanceName(const ::testing::TestParamInfo<Conformance>& info);
// Defined beside the tests: the macro refers to it so that a static link
// keeps them.
bool conformanceLinked();

}  // namespace hamal::testing

// Instantiates every test of the suite for each Conformance given; at
// global scope, once per `prefix` (GoogleTest wants the suites' names
// unqualified, hence the namespace it opens).
#define HAMAL_BACKEND_CONFORMANCE(prefix, ...)                                                   \
  namespace hamal::testing {                                                                     \
  [[maybe_unused]] static const bool conformance_linked_##prefix = conformanceLinked();          \
  INSTANTIATE_TEST_SUITE_P(prefix, BadSteps, ::testing::Values(__VA_ARGS__), conformanceName);   \
  INSTANTIATE_TEST_SUITE_P(prefix, BadNumbers, ::testing::Values(__VA_ARGS__), conformanceName); \
  INSTANTIATE_TEST_SUITE_P(prefix, Fixed, ::testing::Values(__VA_ARGS__), conformanceName);      \
  INSTANTIATE_TEST_SUITE_P(prefix, Losses, ::testing::Values(__VA_ARGS__), conformanceName);     \
  INSTANTIATE_TEST_SUITE_P(prefix, Gauge, ::testing::Values(__VA_ARGS__), conformanceName);      \
  INSTANTIATE_TEST_SUITE_P(prefix, Protocol, ::testing::Values(__VA_ARGS__), conformanceName);   \
  }                                                                                              \
  static_assert(true, "a semicolon after the macro")
