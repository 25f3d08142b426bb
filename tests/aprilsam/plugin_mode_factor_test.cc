// A factor with modes that is not a MaxMixtureFactor (as a plugin would
// define one) takes part in AprilSAM's component-switch hook and dormant
// rule through the Factor capabilities alone (core/factor.h: hasModes, mode,
// modeInformationScale, modeComponent, isNullHypothesisPair;
// core/dormant_policy.h). The test's factor, defined here, is a nominal +
// null hypothesis pair written from Olson & Agarwal's max-mixture (RSS 2012)
// without any code of factors/max_mixture_factor.cc: the same model, so
// AprilSAM must take the same steps with it as with MaxMixtureFactor, switch
// for switch and number for number.
#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "backends/aprilsam/aprilsam_backend.h"
#include "backends/builtins.h"
#include "core/dormant_policy.h"
#include "core/multi_modal.h"
#include "core/registry.h"
#include "tests/aprilsam/component_switch_graph.h"

namespace hamal {
namespace {

using Scenario = testing::SwitchScenario;

// [sqrt(s_j) r ; sqrt(2 (c_max - c_j))] for the component j (nominal at
// weight 1 - w and scale 1, null at weight w and scale s) with the smallest
// s_j |r|^2 + 2 (c_max - c_j), c_j = log w_j + d log(s_j) / 2.
class GatedCost : public ceres::CostFunction {
 public:
  GatedCost(const Factor& nominal, double w, double s)
      : nominal_(*nominal.costFunction()), d_(nominal.residualDim()) {
    set_num_residuals(d_ + 1);
    *mutable_parameter_block_sizes() = nominal_.parameter_block_sizes();
    scale_[0] = 1.0;
    scale_[1] = s;
    const double c[2] = {std::log(1.0 - w) + 0.5 * (d_ * std::log(1.0)),
                         std::log(w) + 0.5 * (d_ * std::log(s))};
    const double c_max = std::max(c[0], c[1]);
    for (int j = 0; j < 2; ++j) offset_[j] = 2.0 * (c_max - c[j]);
  }
  // The component for the nominal's squared residual `sq`; -1 for NaN.
  int choose(double sq) const {
    const double cost0 = scale_[0] * sq + offset_[0], cost1 = scale_[1] * sq + offset_[1];
    if (!(cost0 < std::numeric_limits<double>::infinity()) && !(cost1 < cost0)) return -1;
    return cost1 < cost0 ? 1 : 0;
  }
  int modeAt(double const* const* parameters) const {
    std::vector<double> r(d_ + 1);
    if (!nominal_.Evaluate(parameters, r.data(), nullptr)) return -1;
    return choose(squaredNorm(r.data()));
  }
  double scale(int j) const { return scale_[j]; }

  bool Evaluate(double const* const* parameters, double* residual,
                double** jacobians) const override {
    if (!nominal_.Evaluate(parameters, residual, jacobians)) return false;
    const int j = choose(squaredNorm(residual));
    if (j < 0) return false;
    const double s = std::sqrt(scale_[j]);
    for (int i = 0; i < d_; ++i) residual[i] *= s;
    residual[d_] = std::sqrt(offset_[j]);
    if (jacobians) {
      const auto& sizes = parameter_block_sizes();
      for (std::size_t k = 0; k < sizes.size(); ++k) {
        if (!jacobians[k]) continue;
        for (int i = 0; i < d_ * sizes[k]; ++i) jacobians[k][i] *= s;
        std::fill(jacobians[k] + d_ * sizes[k], jacobians[k] + (d_ + 1) * sizes[k], 0.0);
      }
    }
    return true;
  }

 private:
  double squaredNorm(const double* r) const {
    double sq = 0.0;
    for (int i = 0; i < d_; ++i) sq += r[i] * r[i];
    return sq;
  }
  const ceres::CostFunction& nominal_;
  int d_;
  double scale_[2], offset_[2];
};

class GatedFactor : public Factor, public MultiModal {
 public:
  GatedFactor(FactorPtr nominal, double w, double s)
      : Factor(nominal->keys(), std::make_unique<GatedCost>(*nominal, w, s)),
        nominal_(std::move(nominal)) {}
  std::string tag() const override { return "TEST_GATED"; }
  void writeFields(std::ostream&) const override {}
  int mode(const double* const* parameters) const override { return cost().modeAt(parameters); }
  double modeInformationScale(int mode) const override {
    return mode == 0 || mode == 1 ? cost().scale(mode) : 1.0;
  }
  const Factor* modeComponent(int mode) const override {
    return mode == 0 || mode == 1 ? nominal_.get() : nullptr;
  }
  bool isNullHypothesisPair() const override { return true; }

 private:
  const GatedCost& cost() const { return static_cast<const GatedCost&>(*costFunction()); }
  FactorPtr nominal_;
};

struct Trace {
  std::vector<UpdateKind> kinds;
  std::vector<std::string> reasons;
  std::vector<Values> estimates;
  int batches = 0;
  long dormant = 0;
};

// The scenario's steps with its loop closure made by `make` from the
// nominal, through AprilSAM `spec`.
template <typename Make>
Trace run(const Scenario& s, const std::string& spec, Make make) {
  Registry registry;
  registerBuiltins(registry);
  const auto mixture = testing::switchMixture(s);
  const FactorPtr closure = make(mixture->components()[0].factor, s.null_scale);
  std::vector<Step> steps = testing::switchSteps(s, mixture);
  for (Step& st : steps)
    for (FactorPtr& f : st.new_factors)
      if (f == mixture) f = closure;
  auto backend = registry.makeBackend(spec);
  Trace t;
  for (const Step& st : steps) {
    const UpdateResult r = backend->update(st);
    EXPECT_TRUE(r.status.ok()) << spec << " step " << st.index << ": " << r.status.message;
    t.kinds.push_back(r.kind);
    t.reasons.push_back(r.reason);
    t.estimates.push_back(backend->estimate());
  }
  const auto& a = dynamic_cast<const AprilSamBackend&>(*backend);
  t.batches = a.batches();
  t.dormant = a.dormantFactors();
  return t;
}

class PluginModeFactor : public ::testing::TestWithParam<Scenario> {};

TEST_P(PluginModeFactor, SwitchesAsAMaxMixtureInAprilSam) {
  const Scenario& s = GetParam();
  for (const char* spec : {"aprilsam:mode=incremental,backsolve_tolerance=0",
                           "aprilsam:mode=incremental,backsolve_tolerance=0,factor_update=refactor",
                           "aprilsam:mode=periodic,period=11,backsolve_tolerance=0", "aprilsam"}) {
    SCOPED_TRACE(spec);
    const Trace mixture = run(s, spec, [](const FactorPtr& nominal, double scale) -> FactorPtr {
      return MaxMixtureFactor::withNullHypothesis(nominal, 0.1, scale);
    });
    const Trace plugin = run(s, spec, [](const FactorPtr& nominal, double scale) -> FactorPtr {
      return std::make_shared<GatedFactor>(nominal, 0.1, scale);
    });
    ASSERT_EQ(plugin.kinds, mixture.kinds);
    EXPECT_EQ(plugin.reasons, mixture.reasons);
    EXPECT_EQ(plugin.batches, mixture.batches);
    EXPECT_EQ(plugin.dormant, mixture.dormant);
    for (std::size_t i = 0; i < mixture.estimates.size(); ++i)
      for (int p = 0; p < testing::kSwitchPoses && mixture.estimates[i].contains(X(p)); ++p)
        for (int t = 0; t < 3; ++t)
          EXPECT_EQ(plugin.estimates[i].data(X(p))[t], mixture.estimates[i].data(X(p))[t])
              << "step " << i << " x" << p << "[" << t << "]";
    // The hook fired for it: a switch in every scenario, and the raised
    // path (MultiModal::isNullHypothesisPair, modeComponent) for null -> nominal.
    if (std::string(spec).rfind("aprilsam:mode=incremental", 0) == 0) {
      std::size_t switched = 0, raised = 0;
      for (const std::string& why : plugin.reasons) {
        switched += why.find("switched mode") != std::string::npos;
        raised += why.find("nominal rows added") != std::string::npos;
      }
      EXPECT_GE(switched, 1u);
      EXPECT_EQ(raised > 0, s.initial == 1 && s.final == 0) << raised << " raised switches";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Scenarios, PluginModeFactor,
                         ::testing::Values(Scenario{"NominalToNull", 5.0, 7.0, 0, 1, 1e-4},
                                           Scenario{"NullToNominal", 7.0, 6.8, 1, 0, 1e-4},
                                           Scenario{"NominalToDormant", 5.0, 7.0, 0, 1, 1e-9},
                                           Scenario{"DormantToNominal", 7.0, 6.8, 1, 0, 1e-9}),
                         [](const ::testing::TestParamInfo<Scenario>& info) {
                           return info.param.name;
                         });

// The one dormant rule: below the scale, never for mode -1 or scale 0, and
// the option's listed default is the policy's.
TEST(DormantPolicy, OneRuleForEveryBackend) {
  const auto nominal =
      std::make_shared<testing::LinearBetween>(X(0), X(1), Eigen::Vector3d(1, 0, 0), 1.0);
  const GatedFactor gated(nominal, 0.1, 1e-9);
  EXPECT_TRUE(DormantPolicy().dormant(gated, 1));
  EXPECT_FALSE(DormantPolicy().dormant(gated, 0));
  EXPECT_FALSE(DormantPolicy().dormant(gated, -1));
  EXPECT_FALSE(DormantPolicy(0.0).dormant(gated, 1));
  EXPECT_FALSE(DormantPolicy(1e-10).dormant(gated, 1));
  EXPECT_EQ(asMultiModal(*nominal), nullptr);  // no modes: never asked
  EXPECT_EQ(std::stod(DormantPolicy::optionSpec().default_value), DormantPolicy::kDefaultScale);
  EXPECT_THROW(DormantPolicy(1.0, "x"), Error);
  EXPECT_THROW(DormantPolicy(-1e-5, "x"), Error);
  EXPECT_THROW(DormantPolicy(std::nan(""), "x"), Error);
}

}  // namespace
}  // namespace hamal
