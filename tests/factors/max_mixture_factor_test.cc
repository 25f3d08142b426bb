// MaxMixtureFactor (Olson & Agarwal 2012; factors/max_mixture_factor.h):
// the active component on both sides of the analytic switching point for
// between, range-bearing and pose-point components; the selection against
// the weighted likelihoods computed from determinants; each component's
// Jacobians over random states where it is active; the residual's layout and
// constant; construction errors; the EDGE_MAXMIX line, its round trip and its
// bad input.
#include "factors/max_mixture_factor.h"

#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <random>
#include <sstream>

#include "backends/builtins.h"
#include "conformance/factor_round_trip.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/jacobian_check.h"
#include "core/mixture_component.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/range_bearing_factor.h"
#include "factors/register_factors.h"

namespace hamal {
namespace {

Eigen::Matrix3d betweenInformation() {
  Eigen::Matrix3d info;
  info << 40.0, 3.0, 1.0,  //
      3.0, 8.0, -0.5,      //
      1.0, -0.5, 20.0;
  return info;
}

Eigen::Matrix2d pointInformation() {
  Eigen::Matrix2d info;
  info << 4.0, 0.5, 0.5, 30.0;
  return info;
}

// Three factor kinds a mixture wraps, each with one key whose error along
// its first residual coordinate is `t` at stateAt(t).
struct Kind {
  std::string name;
  FactorPtr factor;
  double info11;  // Omega(0, 0): chi2 = info11 t^2 at stateAt(t)
  std::function<Values(double t)> stateAt;
};

std::vector<Kind> kinds() {
  const Pose2 z(1.0, 0.5, 0.3);
  return {
      {"between", std::make_shared<BetweenFactor>(X(0), X(1), z, betweenInformation()), 40.0,
       [z](double t) {
         Values v;
         v.insert(X(0), Pose2(0, 0, 0));
         v.insert(X(1), Pose2(z.x + t, z.y, z.theta));
         return v;
       }},
      {"range-bearing",
       std::make_shared<RangeBearingFactor>(X(0), L(0), 5.0, 0.0, pointInformation()), 4.0,
       [](double t) {
         Values v;
         v.insert(X(0), Pose2(0, 0, 0));
         v.insert(L(0), Point2(5.0 + t, 0.0));
         return v;
       }},
      {"pose-point",
       std::make_shared<PosePointFactor>(X(0), L(0), Point2(2.0, -1.0), pointInformation()), 4.0,
       [](double t) {
         Values v;
         v.insert(X(0), Pose2(0, 0, 0));
         v.insert(L(0), Point2(2.0 + t, -1.0));
         return v;
       }},
  };
}

TEST(MaxMixtureFactor, SwitchesToTheNullHypothesisAtTheAnalyticPoint) {
  const double w = 0.1, s = 1e-2;
  for (const Kind& k : kinds()) {
    SCOPED_TRACE(k.name);
    const auto mix = MaxMixtureFactor::withNullHypothesis(k.factor, w, s);
    const int d = k.factor->residualDim();
    // cost_0 = chi2, cost_1 = s chi2 + 2 log((1-w)/w) - d log s: equal at
    // chi2* = (2 log((1-w)/w) - d log s) / (1 - s).
    const double offset = 2.0 * std::log((1.0 - w) / w) - d * std::log(s);
    EXPECT_NEAR(mix->componentOffset(0), 0.0, 1e-15);
    EXPECT_NEAR(mix->componentOffset(1), offset, 1e-12);
    const double t_switch = std::sqrt(offset / ((1.0 - s) * k.info11));
    for (double sign : {1.0, -1.0}) {
      const Values before = k.stateAt(sign * t_switch * (1.0 - 1e-6));
      const Values after = k.stateAt(sign * t_switch * (1.0 + 1e-6));
      EXPECT_EQ(mix->activeComponent(before), 0u);
      EXPECT_EQ(mix->activeComponent(after), 1u);
      // The nominal component's chi2 is the nominal factor's, no constant.
      EXPECT_NEAR(mix->chi2(before), k.factor->chi2(before), 1e-12);
      EXPECT_NEAR(mix->chi2(after), s * k.factor->chi2(after) + offset, 1e-9);
      // The cost is continuous across the switch.
      EXPECT_NEAR(mix->chi2(before), mix->chi2(after), 1e-4);
    }
    EXPECT_EQ(mix->activeComponent(k.stateAt(0.0)), 0u);
    EXPECT_EQ(mix->chi2(k.stateAt(0.0)), 0.0);
    EXPECT_EQ(mix->activeComponent(k.stateAt(10.0 * t_switch)), 1u);
  }
}

TEST(MaxMixtureFactor, ResidualIsTheActiveScaledResidualPaddedWithItsConstant) {
  const double w = 0.2, s = 1e-6;
  for (const Kind& k : kinds()) {
    SCOPED_TRACE(k.name);
    const auto mix = MaxMixtureFactor::withNullHypothesis(k.factor, w, s);
    const int d = k.factor->residualDim();
    ASSERT_EQ(mix->residualDim(), d + 1);
    std::vector<double> inner(d), r(d + 1);
    for (double t : {0.01, 100.0}) {
      const Values v = k.stateAt(t);
      ASSERT_TRUE(k.factor->evaluate(v, inner.data()));
      ASSERT_TRUE(mix->evaluate(v, r.data()));
      const std::size_t j = mix->activeComponent(v);
      EXPECT_EQ(j, t < 1 ? 0u : 1u);
      const double scale = j == 0 ? 1.0 : std::sqrt(s);
      for (int i = 0; i < d; ++i)
        EXPECT_NEAR(r[i], scale * inner[i], 1e-12 * (1 + std::abs(inner[i])));
      EXPECT_NEAR(r[d], std::sqrt(mix->componentOffset(j)), 1e-12);
      EXPECT_GE(mix->chi2(v), 0.0);
    }
  }
}

// Components that are different factors: the selection is the argmax of
// w_j |Omega_j|^(1/2) exp(-chi2_j / 2), computed here from determinants.
TEST(MaxMixtureFactor, DifferentComponentsAreWeighedByTheirDeterminants) {
  Eigen::Matrix3d info_b = Eigen::Matrix3d::Identity() * 2.0;
  info_b(2, 2) = 50.0;
  const auto f0 = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), betweenInformation());
  const auto f1 = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(0, 1, 0.5), info_b);
  const auto f2 =
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(-1, 0, 0), betweenInformation());
  const MaxMixtureFactor mix({{f0, 0.5, 1.0}, {f1, 0.3, 1.0}, {f2, 0.2, 0.1}});
  ASSERT_EQ(mix.residualDim(), 4);
  const double dets[3] = {betweenInformation().determinant(), info_b.determinant(),
                          std::pow(0.1, 3) * betweenInformation().determinant()};
  const double weights[3] = {0.5, 0.3, 0.2}, scales[3] = {1.0, 1.0, 0.1};
  const FactorPtr fs[3] = {f0, f1, f2};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  int seen[3] = {0, 0, 0};
  for (int trial = 0; trial < 2000; ++trial) {
    Values v;
    v.insert(X(0), Pose2(0, 0, 0));
    v.insert(X(1), Pose2(u(rng), u(rng), u(rng)));
    double best = -1;
    std::size_t arg = 0;
    double chi2[3];
    for (std::size_t j = 0; j < 3; ++j) {
      chi2[j] = scales[j] * fs[j]->chi2(v);
      const double likelihood = weights[j] * std::sqrt(dets[j]) * std::exp(-0.5 * chi2[j]);
      if (likelihood > best) best = likelihood, arg = j;
    }
    // Skip states within rounding of a tie.
    bool tie = false;
    for (std::size_t j = 0; j < 3; ++j)
      if (j != arg && std::abs(std::log(weights[j] * std::sqrt(dets[j])) - 0.5 * chi2[j] -
                               std::log(best)) < 1e-9)
        tie = true;
    if (tie) continue;
    ASSERT_EQ(mix.activeComponent(v), arg) << "trial " << trial;
    ++seen[arg];
    // cost_j = -2 log(w_j |Omega_j|^(1/2) exp(-chi2_j/2)) + 2 c_max.
    double c_max = -1e300;
    for (std::size_t j = 0; j < 3; ++j)
      c_max = std::max(c_max, std::log(weights[j]) + 0.5 * std::log(dets[j]));
    EXPECT_NEAR(mix.chi2(v), -2.0 * std::log(best) + 2.0 * c_max, 1e-9 * (1 + mix.chi2(v)));
  }
  for (int j = 0; j < 3; ++j) EXPECT_GT(seen[j], 50) << "component " << j;
}

// A state near the nominal measurement, off by a random amount over four
// decades, so that both components are active in some trials.
ValuesSampler nearMeasurement(const Factor& nominal) {
  return [&nominal](std::mt19937_64& rng) {
    Values v;
    const Key first = nominal.keys()[0], second = nominal.keys()[1];
    v.insertEntry(first, randomEntry(VariableType::kPose2, rng));
    Values::Entry guess;
    if (!predictVariable(nominal, second, v, &guess)) throw Error("sampler: no prediction");
    std::uniform_real_distribution<double> u(-1.0, 1.0), decade(-3.0, 1.0);
    const double magnitude = std::pow(10.0, decade(rng));
    for (int i = 0; i < dimension(guess.type); ++i) guess.data[i] += magnitude * u(rng);
    v.insertEntry(second, guess);
    return v;
  };
}

TEST(MaxMixtureFactor, EachComponentsJacobiansMatchNumericWhereItIsActive) {
  for (const Kind& k : kinds()) {
    const auto mix = MaxMixtureFactor::withNullHypothesis(k.factor, 0.1, 1e-2);
    for (std::size_t j = 0; j < 2; ++j) {
      SCOPED_TRACE(k.name + ", component " + std::to_string(j));
      JacobianCheckOptions options;
      options.trials = 200;
      options.seed = 11 + j;
      // Only states where component j is active and stays so within the
      // finite-difference step (the max is not differentiable at a switch);
      // a range-bearing landmark away from the robot.
      options.accept = [&](const Values& v) {
        if (k.name == "range-bearing" && (v.point(L(0)) - v.pose(X(0)).t()).norm() < 1e-3)
          return false;
        if (mix->activeComponent(v) != j) return false;
        const double other = mix->componentCost(1 - j, v), own = mix->componentCost(j, v);
        return other - own > 1e-3;
      };
      const JacobianCheckResult r = checkJacobians(*mix, nearMeasurement(*k.factor), options);
      EXPECT_TRUE(r.ok) << r.report;
      EXPECT_EQ(r.trials, 200);
    }
  }
}

TEST(MaxMixtureFactor, RefusesBadComponents) {
  const auto f = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), betweenInformation());
  const auto other_keys =
      std::make_shared<BetweenFactor>(X(0), X(2), Pose2(1, 0, 0), betweenInformation());
  const auto point =
      std::make_shared<PosePointFactor>(X(0), L(1), Point2(1, 0), pointInformation());
  const auto expectError = [](const std::function<void()>& make, const std::string& part) {
    try {
      make();
      ADD_FAILURE() << "no error; expected one with '" << part << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  using C = MaxMixtureFactor::Component;
  expectError([&] { MaxMixtureFactor({C{f, 0.5, 1.0}}); }, "at least two");
  expectError([&] { MaxMixtureFactor({C{f, 0.5, 1.0}, C{nullptr, 0.5, 1.0}}); }, "no factor");
  expectError([&] { MaxMixtureFactor({C{f, 0.0, 1.0}, C{f, 0.5, 1.0}}); }, "outside (0, 1)");
  expectError([&] { MaxMixtureFactor({C{f, 1.0, 1.0}, C{f, 0.5, 1.0}}); }, "outside (0, 1)");
  expectError([&] { MaxMixtureFactor({C{f, 0.5, 1.0}, C{f, 0.5, 0.0}}); }, "not positive");
  expectError([&] { MaxMixtureFactor({C{f, 0.5, 1.0}, C{f, 0.5, -1.0}}); }, "not positive");
  expectError([&] { MaxMixtureFactor({C{f, 0.5, 1.0}, C{other_keys, 0.5, 1.0}}); }, "other keys");
  expectError([&] { MaxMixtureFactor({C{f, 0.5, 1.0}, C{point, 0.5, 1.0}}); }, "other keys");
  expectError([&] { MaxMixtureFactor::withNullHypothesis(f, 1.5, 1e-6); },
              "null_weight is 1.5: a null hypothesis' weight must be in (0, 1)");
  expectError([&] { MaxMixtureFactor::withNullHypothesis(f, 0.1, std::nan("")); },
              "null_scale is nan: a null hypothesis' information scale must be in (0, 1]");
  expectError([&] { MaxMixtureFactor::withNullHypothesis(f, 0.1, 5); }, "null_scale is 5");
  const auto nested = MaxMixtureFactor::withNullHypothesis(f, 0.1, 1e-6);
  expectError([&] { MaxMixtureFactor({C{nested, 0.5, 1.0}, C{f, 0.5, 1.0}}); }, "max-mixture");
  const auto robust =
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), betweenInformation());
  robust->setLoss(std::make_shared<ceres::CauchyLoss>(1.0));
  expectError([&] { MaxMixtureFactor::withNullHypothesis(robust, 0.1, 1e-6); }, "robust loss");
}

// A factor kind that is no MixtureComponent and predicts nothing: r = b - a.
class DifferenceCost : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  bool Evaluate(double const* const* p, double* r, double** jacobians) const override {
    for (int i = 0; i < 3; ++i) r[i] = p[1][i] - p[0][i];
    if (jacobians)
      for (int k = 0; k < 2; ++k)
        if (jacobians[k])
          for (int i = 0; i < 9; ++i) jacobians[k][i] = (i % 4 == 0) ? (k == 0 ? -1.0 : 1.0) : 0.0;
    return true;
  }
};

class OpaqueFactor : public Factor {
 public:
  OpaqueFactor() : Factor({X(0), X(1)}, std::make_unique<DifferenceCost>()) {}
  std::string tag() const override { return "OPAQUE"; }
  void writeFields(std::ostream&) const override {}
};

TEST(MaxMixtureFactor, DifferentFactorsMustTellTheirLogDeterminant) {
  const auto opaque = std::make_shared<OpaqueFactor>();
  EXPECT_TRUE(std::isnan(logDetInformationOf(*opaque)));
  const auto f = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), betweenInformation());
  EXPECT_NEAR(f->logDetInformation(), std::log(betweenInformation().determinant()), 1e-12);
  try {
    MaxMixtureFactor({{f, 0.5, 1.0}, {opaque, 0.5, 1.0}});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("logDetInformation"), std::string::npos) << e.what();
  }
  // One factor in both components needs no determinant: it cancels.
  const auto mix = MaxMixtureFactor::withNullHypothesis(opaque, 0.1, 1e-4);
  EXPECT_NEAR(mix->componentOffset(1), 2 * std::log(9.0) - 3 * std::log(1e-4), 1e-12);
}

TEST(MaxMixtureFactor, PredictsAsItsNominalComponent) {
  const auto f =
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 2, 0.5), betweenInformation());
  const auto mix = MaxMixtureFactor::withNullHypothesis(f, 0.1, 1e-6);
  Values known;
  known.insert(X(0), Pose2(3, -1, 0.2));
  Values::Entry a, b;
  ASSERT_TRUE(mix->predict(X(1), known, &a));
  ASSERT_TRUE(f->predict(X(1), known, &b));
  EXPECT_EQ(a.data, b.data);
  // A nominal that predicts nothing: neither does the mixture.
  const auto opaque =
      MaxMixtureFactor::withNullHypothesis(std::make_shared<OpaqueFactor>(), 0.1, 1e-6);
  EXPECT_FALSE(opaque->predict(X(1), known, &a));
}

// The file form: EDGE_MAXMIX w_null scale_null <inner line>.
class MaxMixtureLine : public ::testing::Test {
 protected:
  MaxMixtureLine() { registerFactors(registry_); }

  FactorPtr parse(const std::string& line) const {
    LineTokens tokens = LineTokens::split("m.g2o", 3, line);
    tokens.setRegistry(&registry_, "g2o");
    return registry_.parseFactor(tokens);
  }
  std::string parseError(const std::string& line) const {
    try {
      parse(line);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  Registry registry_;
};

TEST_F(MaxMixtureLine, IsRegisteredAndListed) {
  ASSERT_NE(registry_.findFactor("g2o", "EDGE_MAXMIX"), nullptr);
  EXPECT_NE(registry_.describeFactors().find("EDGE_MAXMIX"), std::string::npos);
}

TEST_F(MaxMixtureLine, WrapsEveryG2oEdgeKindAndWritesItBackIdentically) {
  for (const std::string inner :
       {"EDGE_SE2 0 1 1.5 -0.3 0.4 100 5 1 50 2 300", "EDGE_SE2_XY 4 5 11.5 -3.2 6 -1.5 2",
        "EDGE_SE2_RANGE_BEARING 2 7 5.5 0.3 4 0.5 30",
        "EDGE_SE2_PRIOR 3 1 2 0.5 100 5 1 50 2 300"}) {
    SCOPED_TRACE(inner);
    const FactorPtr f = parse("EDGE_MAXMIX 0.125 1e-06 " + inner);
    const auto* mix = dynamic_cast<const MaxMixtureFactor*>(f.get());
    ASSERT_NE(mix, nullptr);
    ASSERT_TRUE(mix->isNullHypothesisPair());
    EXPECT_EQ(mix->components()[0].weight, 0.875);
    EXPECT_EQ(mix->components()[1].weight, 0.125);
    EXPECT_EQ(mix->components()[1].information_scale, 1e-6);
    EXPECT_EQ(mix->components()[0].factor->tag(), LineTokens::split("", 0, inner).tag());
    EXPECT_TRUE(testing::roundTrips(*f, &registry_));
  }
}

TEST_F(MaxMixtureLine, RoundTripsThroughAFile) {
  Graph g;
  g.initial.insert(X(0), Pose2(0, 0, 0));
  g.initial.insert(X(1), Pose2(1, 0.1, 0.05));
  g.initial.insert(X(2), Pose2(2, 0.3, 0.1));
  g.initial.insert(L(3), Point2(1.5, 2));
  const auto between = [](int a, int b, double dx) {
    return std::make_shared<BetweenFactor>(X(a), X(b), Pose2(dx, 0, 0), betweenInformation());
  };
  g.add(between(0, 1, 1.0));
  g.add(between(1, 2, 1.0));
  g.add(MaxMixtureFactor::withNullHypothesis(between(0, 2, 1.7), 0.01, 1e-9));
  g.add(MaxMixtureFactor::withNullHypothesis(
      std::make_shared<PosePointFactor>(X(2), L(3), Point2(-0.5, 1.8), pointInformation()),
      1.0 / 3.0, 0.123456789));
  std::stringstream file;
  writeG2o(file, g.initial, g.factors);
  const Graph back = readGraph(file, "mix.g2o", registry_, Format::kAuto);
  ASSERT_EQ(back.factors.size(), g.factors.size());
  for (std::size_t i = 0; i < g.factors.size(); ++i) {
    EXPECT_EQ(back.factors[i]->tag(), g.factors[i]->tag());
    EXPECT_EQ(back.factors[i]->keys(), g.factors[i]->keys());
    EXPECT_EQ(back.factors[i]->chi2(g.initial), g.factors[i]->chi2(g.initial)) << i;
  }
  for (std::size_t i = 0; i < g.factors.size(); ++i)
    EXPECT_TRUE(back.factors[i]->equals(*g.factors[i], 0.0)) << i;
}

TEST(MaxMixtureFactor, EqualsComparesWeightsScalesAndComponents) {
  const auto nominal =
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), betweenInformation());
  const auto mix = MaxMixtureFactor::withNullHypothesis(nominal, 0.1, 1e-6);
  EXPECT_TRUE(mix->equals(*MaxMixtureFactor::withNullHypothesis(nominal, 0.1 + 1e-12, 1e-6)));
  EXPECT_FALSE(mix->equals(*MaxMixtureFactor::withNullHypothesis(nominal, 0.2, 1e-6)));
  EXPECT_FALSE(mix->equals(*MaxMixtureFactor::withNullHypothesis(nominal, 0.1, 1e-3)));
  const auto moved =
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1.5, 0, 0), betweenInformation());
  EXPECT_FALSE(mix->equals(*MaxMixtureFactor::withNullHypothesis(moved, 0.1, 1e-6)));
  EXPECT_FALSE(mix->equals(*nominal));
  EXPECT_FALSE(nominal->equals(*mix));
  // A mixture without a file line compares too.
  const MaxMixtureFactor general({{nominal, 0.5, 1.0}, {moved, 0.5, 1.0}});
  EXPECT_TRUE(general.equals(MaxMixtureFactor({{nominal, 0.5, 1.0}, {moved, 0.5, 1.0}})));
  EXPECT_FALSE(general.equals(MaxMixtureFactor({{moved, 0.5, 1.0}, {nominal, 0.5, 1.0}})));
}

TEST_F(MaxMixtureLine, BadInputNamesFileLineAndReason) {
  const std::string se2 = " EDGE_SE2 0 1 1.5 -0.3 0.4 100 5 1 50 2 300";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"EDGE_MAXMIX 0 1e-6" + se2, "w_null is 0"},
      {"EDGE_MAXMIX 1 1e-6" + se2, "in (0, 1)"},
      {"EDGE_MAXMIX -0.1 1e-6" + se2, "in (0, 1)"},
      {"EDGE_MAXMIX 1.5 1e-6" + se2, "in (0, 1)"},
      {"EDGE_MAXMIX 0.1 0" + se2, "scale_null is 0"},
      {"EDGE_MAXMIX 0.1 -1e-6" + se2, "must be in (0, 1]"},
      {"EDGE_MAXMIX 0.1 5" + se2, "scale_null is 5: a null hypothesis' information scale"},
      {"EDGE_MAXMIX 0.1 nan" + se2, "NaN"},
      {"EDGE_MAXMIX 0.1 1e-6", "inner tag is missing"},
      {"EDGE_MAXMIX 0.1", "scale_null is missing"},
      {"EDGE_MAXMIX 0.1 1e-6 EDGE_FOO 0 1 2", "unknown tag 'EDGE_FOO'"},
      {"EDGE_MAXMIX 0.1 1e-6 EDGE2 0 1 1.5 -0.3 0.4 100 5 50 300 1 2", "unknown tag 'EDGE2'"},
      {"EDGE_MAXMIX 0.1 1e-6 EDGE_MAXMIX 0.1 1e-6 EDGE_FOO 0 1", "unknown tag 'EDGE_FOO'"},
      {"EDGE_MAXMIX 0.1 1e-6 EDGE_MAXMIX 0.1 1e-6" + se2, "itself an EDGE_MAXMIX"},
      {"EDGE_MAXMIX 0.1 1e-6 EDGE_SE2 0 1 1.5 -0.3 0.4 100 5 1 50 2", "I33 is missing"},
      {"EDGE_MAXMIX 0.1 1e-6" + se2 + " 7", "extra: '7'"},
      {"EDGE_MAXMIX 0.1 1e-6 EDGE_SE2 0 1 1.5 -0.3 0.4 -100 5 1 50 2 300", "positive definite"},
  };
  for (const auto& [line, reason] : cases) {
    SCOPED_TRACE(line);
    const std::string e = parseError(line);
    EXPECT_EQ(e.rfind("m.g2o:3: ", 0), 0u) << e;
    EXPECT_NE(e.find(reason), std::string::npos) << e;
  }
}

TEST_F(MaxMixtureLine, AFileWithABadMixtureLineFailsAtThatLine) {
  std::istringstream in(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n"
      "EDGE_MAXMIX 0.1 1e-6 EDGE_SE2_NOPE 0 1 1 0 0 1 0 0 1 0 1\n");
  try {
    readGraph(in, "bad.g2o", registry_, Format::kAuto);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bad.g2o:3: ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("EDGE_SE2_NOPE"), std::string::npos) << e.what();
  }
}

TEST(MaxMixtureFactor, SetBetweenResidualSwapsItsComponentsAndKeepsThePair) {
  Graph g;
  const auto inner =
      std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0.5, 0.3), betweenInformation());
  g.add(MaxMixtureFactor::withNullHypothesis(inner, 0.1, 1e-6));
  g.factors[0]->setLoss(std::make_shared<ceres::HuberLoss>(2.0));
  EXPECT_EQ(setBetweenResidual(g, BetweenResidual::kMeasurementFrame), 1);
  const auto* mix = dynamic_cast<const MaxMixtureFactor*>(g.factors[0].get());
  ASSERT_NE(mix, nullptr);
  EXPECT_TRUE(mix->isNullHypothesisPair());
  EXPECT_NE(mix->lossFunction(), nullptr);
  const auto* swapped = dynamic_cast<const BetweenFactor*>(mix->components()[0].factor.get());
  ASSERT_NE(swapped, nullptr);
  EXPECT_EQ(swapped->residual(), BetweenResidual::kMeasurementFrame);
  EXPECT_EQ(setBetweenResidual(g, BetweenResidual::kMeasurementFrame), 0);
}

TEST(MaxMixtureFactor, OnlyTheNullHypothesisPairHasAFileLine) {
  const auto f0 = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), betweenInformation());
  const auto f1 = std::make_shared<BetweenFactor>(X(0), X(1), Pose2(0, 1, 0), betweenInformation());
  const MaxMixtureFactor two({{f0, 0.5, 1.0}, {f1, 0.5, 1.0}});
  EXPECT_FALSE(two.isNullHypothesisPair());
  std::ostringstream os;
  EXPECT_THROW(two.writeFields(os), Error);
  std::stringstream file;
  EXPECT_THROW(
      writeG2o(file, Values(),
               {std::make_shared<MaxMixtureFactor>(
                   std::vector<MaxMixtureFactor::Component>{{f0, 0.5, 1.0}, {f1, 0.5, 1.0}})}),
      Error);
}

}  // namespace
}  // namespace hamal
