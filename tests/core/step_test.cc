// checkStep: every back-end rejects a bad step, with a message, before it
// records anything.
#include "core/step.h"

#include <gtest/gtest.h>

#include <limits>

#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"

namespace hamal {
namespace {

std::string errorOf(const Step& step, const Values& known) {
  try {
    checkStep(step, known, "test");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(CheckStep, AcceptsAGoodStep) {
  Values known;
  known.insert(X(0), Pose2());
  Step s;
  s.new_values.insert(X(1), Pose2(1, 0, 0));
  s.new_factors.push_back(
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), Eigen::Matrix3d::Identity()));
  EXPECT_EQ(errorOf(s, known), "");
}

TEST(CheckStep, NamesEachProblem) {
  Values known;
  known.insert(X(0), Pose2());
  known.insert(X(1), Point2(0, 0));  // wrong type for a between
  Step s;
  s.index = 7;
  s.new_values.insert(X(0), Pose2());
  EXPECT_EQ(errorOf(s, known), "test: step 7 adds variable x0, which already exists");

  Step missing;
  missing.new_factors.push_back(
      std::make_shared<BetweenFactor>(X(0), X(5), Pose2(), Eigen::Matrix3d::Identity()));
  EXPECT_EQ(errorOf(missing, known), "test: step 0: factor EDGE_SE2 refers to unknown variable x5");

  Step wrong_dim;
  wrong_dim.new_factors.push_back(
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(), Eigen::Matrix3d::Identity()));
  EXPECT_EQ(errorOf(wrong_dim, known),
            "test: step 0: factor EDGE_SE2 expects 3 parameters for x1, which has 2");

  Step null_factor;
  null_factor.new_factors.push_back(nullptr);
  EXPECT_EQ(errorOf(null_factor, known), "test: step 0 holds a null factor");
}

TEST(CheckStep, RefusesAFactorThatNamesOneVariableTwice) {
  // Ceres aborts the process on such a factor (a parameter block given
  // twice); the check stops it first, for factors made in code.
  Values known;
  known.insert(X(0), Pose2());
  Step s;
  s.index = 3;
  s.new_factors.push_back(
      std::make_shared<BetweenFactor>(X(0), X(0), Pose2(1, 0, 0), Eigen::Matrix3d::Identity()));
  EXPECT_EQ(errorOf(s, known),
            "test: step 3: factor EDGE_SE2 names variable x0 twice; a factor's variables must "
            "be distinct");
}

TEST(CheckStep, RefusesAGuessThatIsNotFinite) {
  // A variable that no factor touches yet keeps its guess as its estimate:
  // a back-end would report ok with an infinite estimate (found by the
  // step-path fuzzer, tests/fuzz/corpus/step_path/).
  Values known;
  Step s;
  s.index = 2;
  s.new_values.insert(X(1), Pose2(0, std::numeric_limits<double>::infinity(), 0));
  EXPECT_EQ(errorOf(s, known), "test: step 2 adds variable x1 with a guess that is not finite");
  Step nan;
  nan.new_values.insert(L(0), Point2(std::numeric_limits<double>::quiet_NaN(), 0));
  EXPECT_EQ(errorOf(nan, known), "test: step 0 adds variable l0 with a guess that is not finite");
}

}  // namespace
}  // namespace hamal
