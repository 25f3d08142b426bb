// The dormant rule of the cholesky back-end (CholeskyBackend, option
// dormant_scale; thesis sec. 3.5.1's sqrt-SAM-Chol with ch. 4's
// max-mixtures): a factor whose active mode carries information below
// dormant_scale adds nothing to H and no block to its pattern. False loop
// closures as max-mixtures then leave the pattern as the clean graph's and
// the optimum as with every factor in the system; a mixture that switches
// off and on across steps and iterations ends where ceres and
// dormant_scale=0 end; a variable left with dormant factors only is a
// numerical failure that says dormant_scale=0, never a crash.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "backends/builtins.h"
#include "backends/cholesky/cholesky_backend.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "factors/pose_point_factor.h"
#include "protocol/thesis_protocol.h"
#include "tests/aprilsam/aprilsam_test_graphs.h"
#include "tests/aprilsam/component_switch_graph.h"

namespace hamal {
namespace {

Registry builtins() {
  Registry r;
  registerBuiltins(r);
  return r;
}

const CholeskyBackend& cholesky(const std::unique_ptr<Backend>& backend) {
  return dynamic_cast<const CholeskyBackend&>(*backend);
}

void expectNear(const Values& a, const Values& b, double tolerance, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (const auto& [key, entry] : a)
    for (std::size_t t = 0; t < entry.data.size(); ++t)
      EXPECT_NEAR(entry.data[t], b.data(key)[t], tolerance)
          << what << ": " << key.str() << "[" << t << "]";
}

// Tight enough that runs that differ by the dropped 1e-12 terms stop at the
// same iterate.
const char* const kDormant = "cholesky:function_tolerance=1e-12";
const char* const kKept = "cholesky:function_tolerance=1e-12,dormant_scale=0";

struct Solution {
  Values estimate;
  long dormant = 0, nonzeros = 0;
};

Solution solveBatch(const Registry& registry, const std::string& spec, const Graph& g) {
  auto backend = registry.makeBackend(spec);
  const UpdateResult r = backend->update(ThesisProtocol(g).batch());
  EXPECT_TRUE(r.status.ok()) << spec << ": " << r.status.message;
  return {backend->estimate(), cholesky(backend).dormantFactors(),
          cholesky(backend).patternNonzeros()};
}

Solution solveProtocol(const Registry& registry, const std::string& spec, const Graph& g) {
  const ThesisProtocol protocol(g);
  auto backend = registry.makeBackend(spec);
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const UpdateResult r = backend->update(protocol.step(i, backend->estimate()));
    EXPECT_TRUE(r.status.ok()) << spec << " step " << i << ": " << r.status.message;
  }
  return {backend->estimate(), cholesky(backend).dormantFactors(),
          cholesky(backend).patternNonzeros()};
}

// (a) 1000 false loop closures as max-mixtures on a 150-pose graph whose true
// loop closures are mixtures too: dormant, they leave H's pattern exactly as
// the clean graph's; the estimate and its cost are those with every factor
// in H, in one batch and at every step of the thesis protocol.
TEST(CholeskyDormant, FalseLoopClosuresAddNoFillAndLeaveTheOptimum) {
  const Registry registry = builtins();
  aprilsam::testing::RandomGraphOptions options;
  options.poses = 150;
  options.loop_probability = 0.02;  // a sparse H, so that fill shows
  Graph clean = aprilsam::testing::randomGraph(options);
  int true_closures = 0;
  for (FactorPtr& f : clean.factors)
    if (f->keys()[1].index() - f->keys()[0].index() != 1) {
      f = MaxMixtureFactor::withNullHypothesis(f, 0.01, 1e-12);
      ++true_closures;
    }
  ASSERT_GT(true_closures, 5);
  Graph spoiled = clean;
  testing::addFalseLoopClosures(&spoiled, options.poses, 1000, 7, 1e-12);

  const Solution plain = solveBatch(registry, kDormant, clean);
  const Solution dormant = solveBatch(registry, kDormant, spoiled);
  const Solution kept = solveBatch(registry, kKept, spoiled);
  EXPECT_EQ(plain.dormant, 0);
  EXPECT_EQ(dormant.dormant, 1000);
  EXPECT_EQ(kept.dormant, 0);
  EXPECT_EQ(dormant.nonzeros, plain.nonzeros);
  EXPECT_GT(kept.nonzeros, 2 * plain.nonzeros) << "the mixtures in H should have filled it in";
  expectNear(dormant.estimate, kept.estimate, 1e-6, "batch, dormant vs kept");
  const double cost_kept = chi2(spoiled.factors, kept.estimate);
  EXPECT_NEAR(chi2(spoiled.factors, dormant.estimate), cost_kept, 1e-9 * cost_kept);

  const Solution step_dormant = solveProtocol(registry, kDormant, spoiled);
  const Solution step_kept = solveProtocol(registry, kKept, spoiled);
  EXPECT_EQ(step_dormant.dormant, 1000);
  EXPECT_EQ(step_dormant.nonzeros, plain.nonzeros);
  expectNear(step_dormant.estimate, step_kept.estimate, 1e-6, "protocol, dormant vs kept");
  expectNear(step_dormant.estimate, dormant.estimate, 1e-6, "protocol vs batch");
}

// (b) The chain of tests/aprilsam/component_switch_graph.h with a null
// hypothesis of scale 1e-9 (dormant): the mixture goes dormant or wakes up
// during one batch's iterations (it starts in `initial` at the guess) and
// between the steps of an incremental run; both end at the optimum of
// dormant_scale=0 and of ceres, to 1e-6.
class CholeskyDormantSwitch : public ::testing::TestWithParam<testing::SwitchScenario> {};

TEST_P(CholeskyDormantSwitch, EndsWhereEveryFactorInTheSystemEnds) {
  const testing::SwitchScenario& s = GetParam();
  const Registry registry = builtins();
  const auto mixture = testing::switchMixture(s);
  const std::vector<Step> steps = testing::switchSteps(s, mixture);
  const Step all = testing::switchBatch(steps);
  ASSERT_EQ(mixture->activeComponent(all.new_values), s.initial);
  const long dormant_at_end = s.final == 1 ? 1 : 0;

  auto reference = registry.makeBackend("cholesky:function_tolerance=1e-15,dormant_scale=0");
  ASSERT_TRUE(reference->update(all).status.ok());
  const Values& optimum = reference->estimate();
  ASSERT_EQ(mixture->activeComponent(optimum), s.final);
  const double best = chi2(all.new_factors, optimum);

  auto ceres = registry.makeBackend(
      "ceres:function_tolerance=1e-15,parameter_tolerance=1e-14,gradient_tolerance=1e-16");
  ASSERT_TRUE(ceres->update(all).status.ok());
  expectNear(ceres->estimate(), optimum, 1e-6, "ceres vs dormant_scale=0");

  auto batch = registry.makeBackend("cholesky:function_tolerance=1e-15");
  const UpdateResult r = batch->update(all);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_EQ(cholesky(batch).dormantFactors(), dormant_at_end);
  expectNear(batch->estimate(), optimum, 1e-6, "batch");
  expectNear(batch->estimate(), ceres->estimate(), 1e-6, "batch vs ceres");
  EXPECT_NEAR(chi2(all.new_factors, batch->estimate()), best, 1e-9 * best);

  auto incremental = registry.makeBackend("cholesky:function_tolerance=1e-15");
  for (const Step& st : steps) {
    const UpdateResult u = incremental->update(st);
    ASSERT_TRUE(u.status.ok()) << "step " << st.index << ": " << u.status.message;
    if (st.index == static_cast<std::size_t>(testing::kSwitchClosureStep)) {
      EXPECT_EQ(mixture->activeComponent(incremental->estimate()), s.initial);
      EXPECT_EQ(cholesky(incremental).dormantFactors(), s.initial == 1 ? 1 : 0);
    }
  }
  EXPECT_EQ(cholesky(incremental).dormantFactors(), dormant_at_end);
  expectNear(incremental->estimate(), optimum, 1e-6, "incremental");
}

INSTANTIATE_TEST_SUITE_P(Scenarios, CholeskyDormantSwitch,
                         ::testing::Values(
                             // Agrees with odometry on arrival, an outlier after the GPS.
                             testing::SwitchScenario{"NominalToDormant", 5.0, 7.0, 0, 1, 1e-9},
                             // Disagrees on arrival, nearly confirmed by the GPS.
                             testing::SwitchScenario{"DormantToNominal", 7.0, 6.8, 1, 0, 1e-9}),
                         [](const ::testing::TestParamInfo<testing::SwitchScenario>& info) {
                           return info.param.name;
                         });

// (c) A landmark seen only through a max-mixture whose null hypothesis is
// active at its guess has no information in H: a numerical failure naming
// it and suggesting dormant_scale=0, with which the same step solves (the
// landmark moves onto its measurement and the nominal component wakes up);
// a later observation repairs the first back-end.
TEST(CholeskyDormant, AVariableWithOnlyDormantFactorsIsANumericalFailure) {
  const Registry registry = builtins();
  const auto mixture = MaxMixtureFactor::withNullHypothesis(
      std::make_shared<PosePointFactor>(X(1), L(0), Point2(2, 0), Eigen::Matrix2d::Identity() * 40),
      0.01, 1e-12);
  Step s;
  s.new_values.insert(X(0), Pose2(0, 0, 0));
  s.new_values.insert(X(1), Pose2(1.1, 0.1, 0.05));
  s.new_values.insert(L(0), Point2(10, 5));  // 7.6 m off: the null hypothesis
  s.new_factors.push_back(
      std::make_shared<PriorFactor>(X(0), Pose2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e4));
  s.new_factors.push_back(std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0),
                                                          Eigen::Matrix3d::Identity() * 100));
  s.new_factors.push_back(mixture);
  ASSERT_EQ(mixture->activeComponent(s.new_values), 1u);

  auto backend = registry.makeBackend("cholesky");
  UpdateResult r = backend->update(s);
  EXPECT_EQ(r.status.code, Status::kNumericalFailure) << r.status.message;
  ASSERT_EQ(r.status.keys.size(), 1u);
  EXPECT_EQ(r.status.keys[0], L(0));
  EXPECT_NE(r.status.message.find("l0"), std::string::npos) << r.status.message;
  EXPECT_NE(r.status.message.find("dormant"), std::string::npos) << r.status.message;
  EXPECT_NE(r.status.message.find("dormant_scale=0"), std::string::npos) << r.status.message;

  auto kept = registry.makeBackend("cholesky:dormant_scale=0");
  r = kept->update(s);
  EXPECT_TRUE(r.status.ok()) << r.status.message;
  const Point2 seen = kept->estimate().pose(X(1)).transformFrom(Point2(2, 0));
  EXPECT_NEAR((kept->estimate().point(L(0)) - seen).norm(), 0, 1e-6);
  EXPECT_EQ(mixture->activeComponent(kept->estimate()), 0u);

  // The first back-end goes on: an observation from x0 constrains l0.
  Step more;
  more.index = 1;
  more.new_factors.push_back(std::make_shared<PosePointFactor>(X(0), L(0), Point2(3, 0),
                                                               Eigen::Matrix2d::Identity() * 40));
  r = backend->update(more);
  EXPECT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_NEAR(backend->estimate().point(L(0)).x(), 3.0, 1e-3);
  EXPECT_EQ(mixture->activeComponent(backend->estimate()), 0u);
  EXPECT_EQ(cholesky(backend).dormantFactors(), 0);
}

TEST(CholeskyDormant, DormantScaleOutsideZeroToOneIsAnError) {
  const Registry registry = builtins();
  for (const char* spec : {"cholesky:dormant_scale=-1e-5", "cholesky:dormant_scale=1"}) {
    try {
      registry.makeBackend(spec);
      ADD_FAILURE() << spec << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("dormant_scale"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace hamal
