// The file round trip every factor test runs, built-in or a plugin's
// (installed with the conformance suite, hamal::testing): write a factor's
// line (tag and writeFields) into a stream whose precision the factor must
// not depend on, read it back through the registry, and compare with
// Factor::equals, with no tolerance (writeFields promises 17 significant
// digits). The second writing must give the same text as the first. With
// core/jacobian_check.h (analytic against numeric Jacobians) it is the
// whole of a factor's contract test (CONTRIBUTING.md, "A new factor").
#pragma once

#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "core/factor.h"
#include "core/line_tokens.h"
#include "core/registry.h"
#include "factors/register_factors.h"

namespace hamal::testing {

inline std::string factorLine(const Factor& f) {
  std::ostringstream os;
  os.precision(3);  // the factor sets its own precision and restores this one
  os << std::fixed << f.tag() << ' ';
  f.writeFields(os);
  return os.str();
}

// `registry` defaults to the built-in factor kinds; a plugin's test passes
// its own.
inline ::testing::AssertionResult roundTrips(const Factor& f, const Registry* registry = nullptr) {
  Registry builtins;
  if (!registry) {
    registerFactors(builtins);
    registry = &builtins;
  }
  const std::string line = factorLine(f);
  LineTokens tokens = LineTokens::split("round_trip.g2o", 1, line);
  tokens.setRegistry(registry, "g2o");
  const FactorPtr back = registry->parseFactor(tokens);
  if (!back) return ::testing::AssertionFailure() << "no factor from '" << line << "'";
  if (!f.equals(*back, 0.0))
    return ::testing::AssertionFailure()
           << "read back differs: '" << line << "' became '" << factorLine(*back) << "'";
  if (!back->equals(f, 0.0))
    return ::testing::AssertionFailure() << "equals is not symmetric on '" << line << "'";
  if (factorLine(*back) != line)
    return ::testing::AssertionFailure()
           << "written again differs: '" << line << "' then '" << factorLine(*back) << "'";
  return ::testing::AssertionSuccess();
}

}  // namespace hamal::testing
