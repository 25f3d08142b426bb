// The bad-step table of the conformance suite: see bad_step_table.h.
#include "conformance/bad_step_table.h"

#include <cmath>
#include <memory>

#include "factors/between_factor.h"
#include "factors/prior_factor.h"

namespace hamal::testing {

namespace {

const Eigen::Matrix3d kInfo = Eigen::Matrix3d::Identity() * 100;

FactorPtr between(Key a, Key b, double dx) {
  return std::make_shared<BetweenFactor>(a, b, Pose2(dx, 0.1, 0.05), kInfo);
}

Step withGoodParts() {
  Step s;
  s.index = 2;
  s.new_values.insert(X(7), Pose2(2.5, 0, 0));
  s.new_factors = {between(X(2), X(7), 0.5)};
  return s;
}

}  // namespace

Step firstGoodStep() {
  Step s;
  s.index = 0;
  s.new_values.insert(X(0), Pose2());
  s.new_values.insert(X(1), Pose2(1, 0, 0));
  s.new_factors = {std::make_shared<PriorFactor>(X(0), Pose2(), kInfo), between(X(0), X(1), 1.0)};
  return s;
}

Step secondGoodStep() {
  Step s;
  s.index = 1;
  s.new_values.insert(X(2), Pose2(2, 0.2, 0.1));
  s.new_factors = {between(X(1), X(2), 1.1)};
  return s;
}

Step goodStepAfter() {
  Step s;
  s.index = 3;
  s.new_values.insert(X(3), Pose2(3, 0.3, 0.2));
  s.new_factors = {between(X(2), X(3), 0.9), between(X(0), X(3), 3.0)};
  return s;
}

const std::vector<BadStep>& badSteps() {
  static const std::vector<BadStep> table = {
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
         s.new_factors.push_back(between(X(7), X(9), 1));
         return s;
       }},
      {"ParameterSizeIsNotTheVariables", "expects 3 parameters for l0",
       [] {
         Step s = withGoodParts();
         s.new_values.insert(L(0), Point2(1, 1));
         s.new_factors.push_back(std::make_shared<BetweenFactor>(
             X(7), L(0), Pose2(), kInfo));  // a pose factor on a point
         return s;
       }},
      {"FixedKeyNamesNoVariable", "fixes x8",
       [] {
         Step s = withGoodParts();
         s.fixed.push_back(X(8));
         return s;
       }},
      {"FactorNamesOneVariableTwice", "names variable x1 twice",
       [] {
         Step s = withGoodParts();
         s.new_factors.push_back(between(X(1), X(1), 1));
         return s;
       }},
      {"GuessNotFinite", "x8 with a guess that is not finite",
       [] {
         Step s = withGoodParts();
         s.new_values.insert(X(8), Pose2(std::nan(""), 0, 0));
         s.new_factors.push_back(between(X(7), X(8), 1));
         return s;
       }},
  };
  return table;
}

}  // namespace hamal::testing
