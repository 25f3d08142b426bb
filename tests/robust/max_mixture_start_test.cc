// MaxMixtureStart (backends/robust/max_mixture_start.h): on a clean world
// with sparse loop closures after a long drift, max-mixtures started from
// the odometry's guess switch true closures off and end metres from the
// clean optimum (maxmix_start=odometry, the old behaviour); started at the
// map (the default) they end at the clean optimum with every true closure
// on, in batch and under the thesis protocol, and they still reject the
// false closures of a spoiled world.
#include "backends/robust/max_mixture_start.h"

#include <gtest/gtest.h>

#include "apps/bench/bench_runner.h"
#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "apps/robust/false_loop_closures.h"
#include "apps/robust/robust_loop_closures.h"
#include "core/error.h"
#include "core/metrics.h"
#include "factors/between_factor.h"

namespace hamal::apps {
namespace {

struct Outcome {
  double ate = 0;
  std::size_t true_off = 0, false_on = 0;
  bool ok = false;
  bool from_gnc = false;  // MaxMixtureStart's account, when it ran
  std::size_t guessed = 0;
};

class MaxMixtureStartTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    setUpRegistry(base_, {});
    ManhattanWorldOptions o;
    o.poses = 400;
    o.seed = 11;
    o.pose_closure_probability = 0.15;
    o.first_loop_closure = 150;
    o.odometry_sigma_xy = 0.1;
    o.odometry_sigma_theta = 0.02;
    clean_ = generateManhattanWorld(o).graph;
    const BatchOptimum opt =
        solveBatchOptimum(clean_, ThesisProtocol(clean_), 0, base_, "cholesky");
    ASSERT_TRUE(opt.status.ok()) << opt.status.message;
    optimum_ = opt.estimate;
  }

  // `spec` over `graph` (factors: its false ones are those not in clean_).
  static Outcome run(const Graph& graph, const std::string& spec, bool batch) {
    const Registry registry = robustRegistry(base_);
    const RobustOptions robust =
        robustOptionsFrom(registry.resolveOptions(BackendSpec::parse(spec)));
    Graph model = graph;
    model.factors = applyRobustMethod(graph.factors, robust);
    const ThesisProtocol protocol(model);
    Outcome out;
    Values estimate;
    std::unique_ptr<Backend> backend;
    if (batch) {
      const BatchOptimum r = solveBatchOptimum(model, protocol, 0, registry, spec,
                                               Initialization::kOdometry, &backend);
      out.ok = r.status.ok();
      estimate = r.estimate;
    } else {
      backend = registry.makeBackend(spec);
      const RunResult r = runThesisProtocol(protocol, *backend, spec, RunOptions{});
      out.ok = summarizeRows(r.rows).status.ok();
      estimate = r.estimate;
    }
    if (const auto* start = dynamic_cast<const robust::MaxMixtureStart*>(backend.get())) {
      out.from_gnc = start->startedFromGnc();
      out.guessed = start->guessedFromClosures();
    }
    out.ate = absoluteTrajectoryError(estimate, optimum_, true).translation_rmse;
    for (std::size_t i = 0; i < graph.factors.size(); ++i) {
      if (!isLoopClosure(*graph.factors[i])) continue;
      const bool is_true = i < clean_.factors.size();
      const bool off = nullHypothesisActive(graph.factors[i], estimate, robust);
      out.true_off += is_true && off;
      out.false_on += !is_true && !off;
    }
    return out;
  }

  static Registry base_;
  static Graph clean_;
  static Values optimum_;
};

Registry MaxMixtureStartTest::base_;
Graph MaxMixtureStartTest::clean_;
Values MaxMixtureStartTest::optimum_;

TEST_F(MaxMixtureStartTest, OdometryDriftSwitchesTrueClosuresOffFromTheOdometryStart) {
  for (const bool batch : {true, false}) {
    const Outcome o = run(clean_,
                          batch ? "cholesky:robust=maxmix,maxmix_start=odometry"
                                : "aprilsam:robust=maxmix,maxmix_start=odometry",
                          batch);
    EXPECT_GT(o.true_off, 0u) << (batch ? "batch" : "incremental");
    EXPECT_GT(o.ate, 0.5) << (batch ? "batch" : "incremental");
  }
}

TEST_F(MaxMixtureStartTest, StartedAtTheMapNoTrueClosureIsSwitchedOff) {
  for (const bool batch : {true, false}) {
    const Outcome o =
        run(clean_, batch ? "cholesky:robust=maxmix" : "aprilsam:robust=maxmix", batch);
    EXPECT_TRUE(o.ok);
    // The batch started from GNC; incrementally, poses were guessed from closures.
    EXPECT_EQ(o.from_gnc, batch);
    EXPECT_EQ(o.guessed > 0, !batch);
    EXPECT_EQ(o.true_off, 0u) << (batch ? "batch" : "incremental");
    EXPECT_LT(o.ate, 0.05) << (batch ? "batch" : "incremental");
  }
}

TEST_F(MaxMixtureStartTest, AGncThatDoesNotConvergeIsNoStart) {
  SpoilOptions s;
  s.outliers = 20;
  s.seed = 3;
  const Outcome o =
      run(spoilGraph(clean_, s).graph, "cholesky:robust=maxmix,gnc_max_iterations=1", true);
  EXPECT_FALSE(o.from_gnc);
}

TEST_F(MaxMixtureStartTest, FalseClosuresAreStillRejected) {
  SpoilOptions s;
  s.outliers = 20;
  s.seed = 3;
  const SpoiledGraph spoiled = spoilGraph(clean_, s);
  for (const bool batch : {true, false}) {
    const Outcome o =
        run(spoiled.graph, batch ? "cholesky:robust=maxmix" : "aprilsam:robust=maxmix", batch);
    EXPECT_EQ(o.false_on, 0u) << (batch ? "batch" : "incremental");
    EXPECT_EQ(o.true_off, 0u) << (batch ? "batch" : "incremental");
  }
}

TEST(MaxMixtureStart, TheCrossoverIsWhereTheNullHypothesisWins) {
  RobustOptions robust;
  robust.method = RobustMethod::kMaxMixture;
  const double c = nullHypothesisCrossover(robust.null_weight, robust.null_scale, 3);
  EXPECT_NEAR(c, 92.1, 0.05);
  const auto closure =
      std::make_shared<BetweenFactor>(X(0), X(2), Pose2(), Eigen::Matrix3d::Identity());
  for (const double chi2 : {c - 0.01, c + 0.01}) {
    Values v;
    v.insert(X(0), Pose2());
    v.insert(X(2), Pose2(std::sqrt(chi2), 0, 0));
    EXPECT_NEAR(closure->chi2(v), chi2, 1e-9);
    EXPECT_EQ(nullHypothesisActive(closure, v, robust), chi2 > c);
  }
}

TEST(MaxMixtureStart, BadArgumentsAreErrors) {
  Registry r;
  setUpRegistry(r, {});
  auto make = [&r] { return r.makeBackend("cholesky"); };
  const robust::GncOptions gnc;
  EXPECT_THROW(robust::MaxMixtureStart(nullptr, robust::isLoopClosure, gnc, 11, 92), Error);
  EXPECT_THROW(robust::MaxMixtureStart(make, nullptr, gnc, 11, 92), Error);
  EXPECT_THROW(robust::MaxMixtureStart(make, robust::isLoopClosure, gnc, 0, 92), Error);
  EXPECT_THROW(robust::MaxMixtureStart(make, robust::isLoopClosure, gnc, 11, NAN), Error);
  EXPECT_THROW(robustRegistry(r).makeBackend("cholesky:robust=maxmix,maxmix_start=lago"), Error);
}

}  // namespace
}  // namespace hamal::apps
