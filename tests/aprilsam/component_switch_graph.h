// Test-local graphs of the component-switch tests (MultiModal::mode, thesis
// ch. 4's max-mixtures; AprilSAM's switch hook and the dormant rule of
// AprilSAM and cholesky): a chain whose one max-mixture loop closure changes
// its active component between its arrival and the optimum, and random
// false loop closures as max-mixtures whose null hypothesis is always active.
//
// The chain is linear within each component (poses along x, translation-only
// "between" factors and a GPS-like position factor), so one incremental
// Gauss-Newton step is exact and any difference between back-ends is the
// component each holds the mixture with.
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "core/graph.h"
#include "core/step.h"
#include "factors/between_factor.h"
#include "factors/max_mixture_factor.h"
#include "factors/position_factor.h"
#include "factors/prior_factor.h"

namespace hamal::testing {

// r = sqrt(info) (b - a - z) on all three coordinates: linear.
class LinearBetweenCost : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  LinearBetweenCost(Eigen::Vector3d z, double sqrt_info) : z_(std::move(z)), s_(sqrt_info) {}
  bool Evaluate(double const* const* p, double* r, double** jacobians) const override {
    for (int i = 0; i < 3; ++i) r[i] = s_ * (p[1][i] - p[0][i] - z_[i]);
    if (jacobians)
      for (int k = 0; k < 2; ++k)
        if (jacobians[k])
          for (int i = 0; i < 9; ++i) jacobians[k][i] = i % 4 == 0 ? (k == 0 ? -s_ : s_) : 0.0;
    return true;
  }

 private:
  Eigen::Vector3d z_;
  double s_;
};

class LinearBetween : public Factor {
 public:
  LinearBetween(Key a, Key b, Eigen::Vector3d z, double info)
      : Factor({a, b}, std::make_unique<LinearBetweenCost>(std::move(z), std::sqrt(info))) {}
  std::string tag() const override { return "TEST_LINEAR_BETWEEN"; }
  void writeFields(std::ostream&) const override {}
};

struct SwitchScenario {
  std::string name;
  double closure_dx;    // the mixture's measurement of x5 - x0
  double gps_x;         // the late position measurement of x5
  std::size_t initial;  // component active when the mixture arrives
  std::size_t final;    // component active at the optimum
  double null_scale;    // 1e-4: in the system at every mode; 1e-9: dormant while null
};

constexpr int kSwitchPoses = 12;
constexpr int kSwitchClosureStep = 5;  // the mixture x0 -> x5 arrives with x5
constexpr int kSwitchGpsStep = 11;     // the GPS on x5 arrives with the last pose

inline std::shared_ptr<MaxMixtureFactor> switchMixture(const SwitchScenario& s) {
  return MaxMixtureFactor::withNullHypothesis(
      std::make_shared<LinearBetween>(X(0), X(kSwitchClosureStep),
                                      Eigen::Vector3d(s.closure_dx, 0, 0), 100.0),
      0.1, s.null_scale);
}

inline std::vector<Step> switchSteps(const SwitchScenario& s,
                                     const std::shared_ptr<MaxMixtureFactor>& mixture) {
  std::vector<Step> out(kSwitchPoses);
  for (int i = 0; i < kSwitchPoses; ++i) {
    Step& step = out[i];
    step.index = i;
    // Guesses off the chain so that every update has work to do.
    step.new_values.insert(X(i), Pose2(i + 0.3, 0.1, 0.0));
    if (i == 0)
      step.new_factors.push_back(std::make_shared<PriorFactor>(
          X(0), Pose2(0, 0, 0), Eigen::Vector3d(1e4, 1e4, 1e4).asDiagonal()));
    else
      step.new_factors.push_back(
          std::make_shared<LinearBetween>(X(i - 1), X(i), Eigen::Vector3d(1, 0, 0), 100.0));
    if (i == kSwitchClosureStep) step.new_factors.push_back(mixture);
    if (i == kSwitchGpsStep)
      step.new_factors.push_back(std::make_shared<PositionFactor>(
          X(kSwitchClosureStep), Point2(s.gps_x, 0.0), Eigen::Matrix2d::Identity() * 1e4));
  }
  return out;
}

// All the steps as one.
inline Step switchBatch(const std::vector<Step>& steps) {
  Step all;
  for (const Step& st : steps) {
    for (const auto& [k, e] : st.new_values) all.new_values.insertEntry(k, e);
    all.new_factors.insert(all.new_factors.end(), st.new_factors.begin(), st.new_factors.end());
  }
  return all;
}

// `count` false loop closures as max-mixtures (null weight 0.01, information
// scale `null_scale`) between poses x0 .. x(poses - 1) at least 2 apart,
// measured 40 m off in a 10 x 10 m world: the null hypothesis is active
// wherever the estimate goes.
inline void addFalseLoopClosures(Graph* g, int poses, int count, unsigned seed, double null_scale) {
  std::mt19937 rng(seed);
  for (int n = 0; n < count; ++n) {
    const int a = static_cast<int>(rng() % (poses - 2));
    const int b = a + 2 + static_cast<int>(rng() % (poses - 2 - a));
    g->add(MaxMixtureFactor::withNullHypothesis(
        std::make_shared<BetweenFactor>(X(a), X(b), Pose2(40.0, -40.0, 0.5),
                                        Eigen::Vector3d(100, 50, 400).asDiagonal()),
        0.01, null_scale));
  }
}

}  // namespace hamal::testing
