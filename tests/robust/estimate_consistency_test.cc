// The estimate's consistency test (backends/robust/estimate_consistency.h)
// and the PCM front end that uses it: composing uncertain poses is the
// odometry chain's propagation; a closure is tested against AprilSAM's
// estimate and covariance; and on a world whose stated covariances are 50
// times its noise's (as M3500's and city10000's are: chi2 at their optimum
// is 2% of its degrees of freedom), PCM over the odometry alone lets false
// loop closures through where the estimate's test rejects most, and all
// once the threshold is scaled by the overstatement.
#include "backends/robust/estimate_consistency.h"

#include <gtest/gtest.h>

#include <random>

#include "apps/bench/bench_runner.h"
#include "apps/robust/robust_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "backends/robust/loop_closure.h"
#include "backends/robust/pcm_front_end.h"
#include "core/error.h"
#include "core/metrics.h"
#include "factors/between_factor.h"
#include "tests/robust/spoiled_world.h"

namespace hamal::robust {
namespace {

TEST(EstimateConsistency, ComposeIsTheOdometryChainsPropagation) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> step(-2, 2), turn(-1.5, 1.5), u(0.5, 2);
  OdometryChain chain;
  for (std::uint64_t m = 0; m < 30; ++m) {
    const Eigen::Matrix3d info =
        Eigen::Vector3d(100 * u(rng), 50 * u(rng), 400 * u(rng)).asDiagonal();
    chain.add(BetweenFactor(X(m), X(m + 1), Pose2(step(rng), step(rng), turn(rng)), info));
  }
  for (const auto& [a, b, c] :
       std::vector<std::array<std::uint64_t, 3>>{{0, 10, 30}, {3, 4, 29}, {5, 20, 21}}) {
    const UncertainPose whole = chain.between(a, c);
    const UncertainPose parts = compose(chain.between(a, b), chain.between(b, c));
    EXPECT_NEAR(parts.pose.x, whole.pose.x, 1e-9);
    EXPECT_NEAR(parts.pose.y, whole.pose.y, 1e-9);
    EXPECT_NEAR(wrapAngle(parts.pose.theta - whole.pose.theta), 0, 1e-12);
    EXPECT_LT((parts.covariance - whole.covariance).norm(), 1e-9 * whole.covariance.norm())
        << parts.covariance << "\n vs \n"
        << whole.covariance;
  }
}

using World = testing::SpoiledWorld;

// 300 poses, 30 random false loop closures (Vertigo's way), every
// information matrix kScale times the generator's noise's: covariances
// overstated 200 times, so that 300 poses drift as M3500's thousands do.
constexpr double kScale = 0.005;
const World& inflatedWorld() {
  static const World w = [] {
    testing::SpoiledWorldOptions o;
    o.information_scale = kScale;
    return testing::makeSpoiledWorld(o);
  }();
  return w;
}

struct Tally {
  std::size_t false_accepted = 0, true_rejected = 0, false_edges = 0, true_closures = 0;
};

Tally tally(const PcmFrontEnd& pcm, const World& w) {
  Tally t;
  const std::size_t clean = w.clean.factors.size();
  for (const auto& [factor, accepted] : pcm.decisions()) {
    std::size_t index = 0;
    while (w.spoiled.graph.factors[index].get() != factor) ++index;
    const bool is_false = index >= clean;
    t.false_edges += is_false;
    t.true_closures += !is_false;
    t.false_accepted += is_false && accepted;
    t.true_rejected += !is_false && !accepted;
  }
  return t;
}

PcmFrontEnd runIncremental(const World& w, const std::string& covariance,
                           double threshold_scale = 1) {
  PcmOptions o = defaultPcmOptions();
  o.threshold *= threshold_scale;
  o.estimate_threshold *= threshold_scale;
  o.covariance = covariance == "estimate" ? PcmOptions::Covariance::kEstimate
                                          : PcmOptions::Covariance::kOdometry;
  PcmFrontEnd pcm(w.registry.makeBackend("aprilsam"), isLoopClosure, o);
  apps::RunOptions options;
  options.chi2_every = 0;
  apps::runThesisProtocol(ThesisProtocol(w.spoiled.graph), pcm, "pcm+aprilsam", options);
  return pcm;
}

TEST(EstimateConsistency, RejectsWhatTheOdometryChainLetsThrough) {
  const World& w = inflatedWorld();
  const PcmFrontEnd odometry = runIncremental(w, "odometry");
  const Tally by_odometry = tally(odometry, w);
  ASSERT_EQ(by_odometry.false_edges, 30u);
  EXPECT_GE(by_odometry.false_accepted, 5u);  // why the estimate's test exists
  EXPECT_EQ(odometry.estimateRejected(), 0u);

  const PcmFrontEnd estimate = runIncremental(w, "estimate");
  const Tally by_estimate = tally(estimate, w);
  EXPECT_LE(2 * by_estimate.false_accepted, by_odometry.false_accepted);
  EXPECT_LE(by_estimate.true_rejected, by_estimate.true_closures / 50);
  EXPECT_GT(estimate.estimateRejected(), 0u);

  // What is left is the overstated covariance: with the thresholds scaled
  // by it (the chi2 quantiles of the noise the data has), the estimate's
  // test rejects every false closure and at most 1% of the true ones, as
  // pcm_probability = 0.99 states.
  const PcmFrontEnd calibrated = runIncremental(w, "estimate", kScale);
  const Tally by_calibrated = tally(calibrated, w);
  EXPECT_EQ(by_calibrated.false_accepted, 0u);
  EXPECT_GT(by_calibrated.true_closures, 50u);
  EXPECT_LE(by_calibrated.true_rejected, by_calibrated.true_closures / 100);
  EXPECT_EQ(calibrated.keptRejected(), 0u);
  EXPECT_LT(absoluteTrajectoryError(calibrated.estimate(), w.clean_optimum).translation_rmse, 1e-2);
  // The odometry's tests alone, calibrated, are right here too: the
  // estimate's test is for covariances stated larger than the noise.
  const Tally odometry_calibrated = tally(runIncremental(w, "odometry", kScale), w);
  EXPECT_EQ(odometry_calibrated.false_accepted, 0u);
  EXPECT_LE(odometry_calibrated.true_rejected, odometry_calibrated.true_closures / 100);
}

// pcm+gnc over aprilsam: PCM's front end sees through GNC to aprilsam's
// estimate and covariance, so it rejects by the estimate as pcm does.
TEST(EstimateConsistency, PcmWithGncReadsTheWrappedBackend) {
  const World& w = inflatedWorld();
  const Registry r = apps::robustRegistry(w.registry);
  for (const char* spec : {"aprilsam:robust=pcm", "aprilsam:robust=pcm+gnc"}) {
    SCOPED_TRACE(spec);
    auto backend = r.makeBackend(spec);
    auto* pcm = dynamic_cast<PcmFrontEnd*>(backend.get());
    ASSERT_NE(pcm, nullptr);
    apps::RunOptions options;
    options.chi2_every = 0;
    apps::runThesisProtocol(ThesisProtocol(w.spoiled.graph), *pcm, spec, options);
    EXPECT_GT(pcm->estimateRejected(), 20u);
  }
}

// GNC's doubt rule builds back-ends of its own and drops them; PCM must go
// on reading the one GNC holds (it once read a freed one and crashed on
// MIT + 100 false closures). A permissive PCM leaves GNC closures to reject,
// which is when the rule runs.
TEST(EstimateConsistency, PcmWithGncReadsTheBackendGncHoldsAfterADoubtCheck) {
  const World& w = inflatedWorld();
  const Registry r = apps::robustRegistry(w.registry);
  auto backend = r.makeBackend("aprilsam:robust=pcm+gnc,pcm_threshold=1e9");
  auto* pcm = dynamic_cast<PcmFrontEnd*>(backend.get());
  ASSERT_NE(pcm, nullptr);
  const auto* gnc = dynamic_cast<const GraduatedNonConvexity*>(&pcm->inner());
  ASSERT_NE(gnc, nullptr);
  apps::RunOptions options;
  options.chi2_every = 0;
  apps::runThesisProtocol(ThesisProtocol(w.spoiled.graph), *pcm, "pcm+gnc", options);
  EXPECT_GT(gnc->alternativesChecked(), 0);
  ASSERT_NE(gnc->nativeWeightsBackend(), nullptr);
  EXPECT_EQ(pcm->estimateSource(), gnc->nativeWeightsBackend());
}

TEST(EstimateConsistency, AgainstAprilsamsEstimateFalseIsFarAndTrueIsNear) {
  const World& w = inflatedWorld();
  // AprilSAM holding the clean graph at its optimum.
  auto aprilsam = w.registry.makeBackend("aprilsam");
  auto* weights = dynamic_cast<FactorWeights*>(aprilsam.get());
  ASSERT_NE(weights, nullptr);
  OdometryChain chain;
  Step step = ThesisProtocol(w.clean).batch();
  for (const auto& f : w.clean.factors)
    if (OdometryChain::isOdometry(*f)) chain.add(*f);
  // Before anything is held there is no estimate to test against.
  EXPECT_FALSE(estimateConsistency(*aprilsam, *weights, chain, *w.spoiled.graph.factors.back()));
  ASSERT_TRUE(aprilsam->update(step).status.ok());
  std::size_t true_far = 0, true_tested = 0;
  for (std::size_t f = 0; f < w.spoiled.graph.factors.size(); ++f) {
    const Factor& factor = *w.spoiled.graph.factors[f];
    if (!isLoopClosure(factor)) continue;
    const auto d2 = estimateConsistency(*aprilsam, *weights, chain, factor);
    ASSERT_TRUE(d2.has_value());
    if (f >= w.clean.factors.size()) {
      EXPECT_GT(*d2, 11.345) << factor.keys()[0].str() << "-" << factor.keys()[1].str();
    } else {
      ++true_tested;
      true_far += *d2 > 11.345;
    }
  }
  EXPECT_GT(true_tested, 10u);
  EXPECT_EQ(true_far, 0u);
  // A loop closure whose kind makes no relativePoseFactor cannot be asked about.
  struct NoProbe : BetweenFactor {
    using BetweenFactor::BetweenFactor;
    std::shared_ptr<Factor> relativePoseFactor(const RelativePose&) const override {
      return nullptr;
    }
  };
  const auto* last = dynamic_cast<const BetweenFactor*>(w.spoiled.graph.factors.back().get());
  ASSERT_NE(last, nullptr);
  const NoProbe no_probe(last->keys()[0], last->keys()[1], last->measurement(),
                         last->information());
  EXPECT_FALSE(estimateConsistency(*aprilsam, *weights, chain, no_probe));
  EXPECT_TRUE(estimateConsistency(*aprilsam, *weights, chain, *last));
  // A back-end without residualCovariance cannot tell.
  auto cholesky = w.registry.makeBackend("cholesky");
  if (auto* none = dynamic_cast<FactorWeights*>(cholesky.get())) {
    ASSERT_TRUE(cholesky->update(ThesisProtocol(w.clean).batch()).status.ok());
    EXPECT_FALSE(estimateConsistency(*cholesky, *none, chain, *w.spoiled.graph.factors.back()));
  }
}

}  // namespace
}  // namespace hamal::robust
