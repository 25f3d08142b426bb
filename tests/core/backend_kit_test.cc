// The back-end kit (core/backend_kit.h, core/variable_layout.h,
// core/phase_clock.h): variables numbered in order of arrival, columns only
// for free ones, re-laid out when a known variable is fixed; a refused step
// records nothing; a non-finite estimate or cost is a failure naming its
// culprit; phases sum to the update's time.
#include "core/backend_kit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "core/error.h"
#include "core/phase_clock.h"
#include "core/variable_layout.h"
#include "factors/between_factor.h"

namespace hamal {
namespace {

Step twoPosesAndALandmark() {
  Step s;
  s.new_values.insert(X(1), Pose2(1, 0, 0));
  s.new_values.insert(X(0), Pose2());
  s.new_values.insert(L(0), Point2(1, 1));
  s.fixed = {X(0)};
  return s;
}

TEST(VariableLayout, ColumnsForFreeVariablesInOrderOfArrival) {
  VariableLayout layout;
  EXPECT_FALSE(layout.add(twoPosesAndALandmark()));
  ASSERT_EQ(layout.size(), 3);
  // A step's variables arrive in key order: x0, x1, then l0 (Values::keys).
  const int x0 = layout.index(X(0)), x1 = layout.index(X(1)), l0 = layout.index(L(0));
  EXPECT_EQ(layout.key(x0), X(0));
  EXPECT_TRUE(layout.fixed(x0));
  EXPECT_EQ(layout.width(x0), 0);
  EXPECT_EQ(layout.width(x1), 3);
  EXPECT_EQ(layout.width(l0), 2);
  EXPECT_EQ(layout.dimension(), 5);
  EXPECT_LT(x0, x1);
  const int first = std::min(x1, l0), second = std::max(x1, l0);
  EXPECT_EQ(layout.column(first), 0);
  EXPECT_EQ(layout.column(second), layout.width(first));
  for (long c = 0; c < layout.dimension(); ++c) {
    const int v = layout.variableOfColumn(c);
    EXPECT_FALSE(layout.fixed(v)) << c;
    EXPECT_GE(c, layout.column(v));
    EXPECT_LT(c, layout.column(v) + layout.width(v));
  }
  EXPECT_THROW(layout.index(X(7)), Error);
}

TEST(VariableLayout, FixingAKnownVariableLaysTheColumnsOutAgain) {
  VariableLayout layout;
  layout.add(twoPosesAndALandmark());
  Step later;
  later.new_values.insert(X(2), Pose2(2, 0, 0));
  later.fixed = {X(1)};
  EXPECT_EQ(layout.dimensionAfter(later), 5 - 3 + 3);
  EXPECT_TRUE(layout.add(later));
  EXPECT_TRUE(layout.fixed(layout.index(X(1))));
  EXPECT_EQ(layout.dimension(), 5);
  long next = 0;
  for (int i = 0; i < layout.size(); ++i) {
    EXPECT_EQ(layout.column(i), next) << layout.key(i);
    next += layout.width(i);
  }
  // Fixing it again changes nothing.
  Step again;
  again.fixed = {X(1)};
  EXPECT_FALSE(layout.add(again));
}

TEST(VariableLayout, RetractsOnlyTheFreeVariables) {
  VariableLayout layout;
  const Step s = twoPosesAndALandmark();
  layout.add(s);
  Values values = s.new_values;
  std::vector<double> dx(layout.dimension(), 0.5);
  layout.retract(&values, dx.data());
  EXPECT_EQ(values.pose(X(0)).x, 0.0);
  EXPECT_EQ(values.pose(X(1)).x, 1.5);
  EXPECT_EQ(values.point(L(0)).x(), 1.5);
}

TEST(BackendKit, ARefusedStepRecordsNothing) {
  BackendKit kit("test");
  Step s = twoPosesAndALandmark();
  s.new_factors = {
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), Eigen::Matrix3d::Identity())};
  EXPECT_THROW(kit.admit(s, [](const Step&) { throw Error("test: too big"); }), Error);
  EXPECT_TRUE(kit.estimate().empty());
  EXPECT_TRUE(kit.factors().empty());
  EXPECT_EQ(kit.layout().size(), 0);
  s.new_factors.push_back(nullptr);
  EXPECT_THROW(kit.admit(s), Error);  // checkStep
  EXPECT_EQ(kit.layout().size(), 0);
  s.new_factors.pop_back();
  kit.admit(s);
  EXPECT_EQ(kit.estimate().size(), 3u);
  EXPECT_EQ(kit.factors().size(), 1u);
  EXPECT_EQ(kit.layout().dimension(), 5);
  EXPECT_TRUE(kit.finiteStatus().ok());
}

TEST(BackendKit, ANonFiniteResultIsAFailureNamingItsCulprit) {
  BackendKit kit("test");
  Step s = twoPosesAndALandmark();
  s.new_factors = {
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1e300, 0, 0), Eigen::Matrix3d::Identity())};
  kit.admit(s);
  Status cost = kit.finiteStatus();
  EXPECT_FALSE(cost.ok());
  EXPECT_NE(cost.message.find("test"), std::string::npos) << cost.message;
  kit.estimate().data(L(0))[1] = std::nan("");
  const Status estimate = kit.finiteStatus();
  ASSERT_FALSE(estimate.ok());
  ASSERT_EQ(estimate.keys.size(), 1u);
  EXPECT_EQ(estimate.keys[0], L(0));
}

TEST(PhaseClock, PhasesSumToTheWholeTime) {
  PhaseClock clock;
  PhaseTimes times;
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  clock.lap(&times.factor);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  clock.finish(&times);
  EXPECT_GE(times.factor, 0.004);
  EXPECT_GE(times.other, 0.004);
  EXPECT_NEAR(times.total(), clock.seconds(), 1e-3);
}

}  // namespace
}  // namespace hamal
