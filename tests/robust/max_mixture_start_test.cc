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
  bool from_least_squares = false;
  std::size_t guessed = 0;
  long reclosed = 0, adopted = 0;
};

// A clean world and its least-squares optimum.
struct World {
  Graph clean;
  Values optimum;
};

class MaxMixtureStartTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    setUpRegistry(base_, {});
    world_ = makeWorld(sparseAfterDrift(0.1));
  }

  // Sparse closures after a long drift, the odometry's own noise `sigma_xy`.
  static ManhattanWorldOptions sparseAfterDrift(double sigma_xy) {
    ManhattanWorldOptions o;
    o.poses = 400;
    o.seed = 11;
    o.loop_closures.pose_probability = 0.15;
    o.loop_closures.first_pose = 150;
    o.noise.odometry_sigma_xy = sigma_xy;
    o.noise.odometry_sigma_theta = 0.02;
    return o;
  }

  static World makeWorld(const ManhattanWorldOptions& o) {
    World w;
    w.clean = generateManhattanWorld(o).graph;
    const BatchOptimum opt =
        solveBatchOptimum(w.clean, ThesisProtocol(w.clean), 0, base_, "cholesky");
    EXPECT_TRUE(opt.status.ok()) << opt.status.message;
    w.optimum = opt.estimate;
    return w;
  }

  // `spec` over `graph` (factors: its false ones are those not in the world's).
  static Outcome run(const Graph& graph, const std::string& spec, bool batch) {
    return run(world_, graph, spec, batch);
  }
  // With `made`, that back-end runs the protocol in place of the spec's.
  static Outcome run(const World& world, const Graph& graph, const std::string& spec, bool batch,
                     std::unique_ptr<Backend> made = nullptr) {
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
      backend = made ? std::move(made) : registry.makeBackend(spec);
      const RunResult r = runThesisProtocol(protocol, *backend, spec, RunOptions{});
      out.ok = summarizeRows(r.rows).status.ok();
      estimate = r.estimate;
    }
    if (const auto* start = dynamic_cast<const robust::MaxMixtureStart*>(backend.get())) {
      out.from_gnc = start->startedFromGnc();
      out.from_least_squares = start->startedFromLeastSquares();
      out.guessed = start->guessedFromClosures();
      out.reclosed = start->reclosed();
      out.adopted = start->adopted();
    }
    out.ate = absoluteTrajectoryError(estimate, world.optimum, true).translation_rmse;
    for (std::size_t i = 0; i < graph.factors.size(); ++i) {
      if (!isLoopClosure(*graph.factors[i])) continue;
      const bool is_true = i < world.clean.factors.size();
      const bool off = nullHypothesisActive(graph.factors[i], estimate, robust);
      out.true_off += is_true && off;
      out.false_on += !is_true && !off;
    }
    return out;
  }

  static Registry base_;
  static World world_;
};

Registry MaxMixtureStartTest::base_;
World MaxMixtureStartTest::world_;

TEST_F(MaxMixtureStartTest, OdometryDriftSwitchesTrueClosuresOffFromTheOdometryStart) {
  for (const bool batch : {true, false}) {
    const Outcome o = run(world_.clean,
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
        run(world_.clean, batch ? "cholesky:robust=maxmix" : "aprilsam:robust=maxmix", batch);
    EXPECT_TRUE(o.ok);
    // The batch started from least squares; incrementally, poses were guessed
    // from closures.
    EXPECT_EQ(o.from_least_squares, batch);
    EXPECT_EQ(o.guessed > 0, !batch);
    EXPECT_EQ(o.true_off, 0u) << (batch ? "batch" : "incremental");
    EXPECT_LT(o.ate, 0.05) << (batch ? "batch" : "incremental");
  }
}

// Incrementally, a closure that agrees with the map can end switched off in
// its own step (another closure of the step gave the pose's guess, or the
// solve passed beyond its crossover on the way); so can one that held
// before. Least squares with every closure that should hold closes them.
TEST_F(MaxMixtureStartTest, AClosureSwitchedOffInItsStepIsClosedAgain) {
  ManhattanWorldOptions o;
  o.poses = 1000;
  o.seed = 1;
  o.loop_closures.first_pose = 800;
  o.noise.odometry_sigma_xy = 0.1;
  const World drift = makeWorld(o);
  const Outcome r = run(drift, drift.clean, "aprilsam:robust=maxmix", false);
  EXPECT_GT(r.reclosed, 0);
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.true_off, 0u);
  EXPECT_LT(r.ate, 0.05);
}

// A true closure the estimate's test turns away (MIT's, whose drift the
// covariance does not cover) starts switched off; here the test turns every
// closure away (threshold ~ 0). The doubt rule's cheaper map is where the
// mixtures start again, and no true closure ends off. (One that comes after
// the last check and is turned away ends off, and the run uncertain.)
TEST_F(MaxMixtureStartTest, TheDoubtRulesCheaperMapIsAdopted) {
  const robust::GncOptions gnc;
  RobustOptions robust;
  robust.method = RobustMethod::kMaxMixture;
  auto start = std::make_unique<robust::MaxMixtureStart>(
      [] { return base_.makeBackend("aprilsam"); }, robust::isLoopClosure, gnc, 1e-9,
      nullHypothesisCrossover(robust.null_weight, robust.null_scale, 3));
  // 16 closures: the check that adopts (at 1, 2, 4, 8, 16) sees the last one.
  ManhattanWorldOptions o = sparseAfterDrift(0.1);
  o.poses = 290;
  const World world = makeWorld(o);
  ASSERT_EQ(world.clean.factors.size(), 289u + 16u);
  const Outcome r = run(world, world.clean, "aprilsam:robust=maxmix", false, std::move(start));
  EXPECT_EQ(r.guessed, 0u);
  EXPECT_GT(r.adopted, 0);
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.true_off, 0u);
  EXPECT_LT(r.ate, 0.05);
}

// A batch whose back-end cannot converge from the odometry in its
// iterations (GNC then is no start): least squares from LAGO over the
// closures' nominal components is. (Without the doubt rule, which would
// adopt its cheaper map instead.)
TEST_F(MaxMixtureStartTest, ABatchStartsFromLeastSquaresFromLago) {
  const Outcome r =
      run(world_.clean, "cholesky:robust=maxmix,max_iterations=2,gnc_doubt=off", true);
  EXPECT_TRUE(r.from_least_squares);
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.true_off, 0u);
  EXPECT_LT(r.ate, 0.05);
}

TEST_F(MaxMixtureStartTest, AGncThatDoesNotConvergeIsNoStart) {
  SpoilOptions s;
  s.outliers = 20;
  s.seed = 3;
  const Outcome o =
      run(spoilGraph(world_.clean, s).graph, "cholesky:robust=maxmix,gnc_max_iterations=1", true);
  EXPECT_FALSE(o.from_gnc);
}

TEST_F(MaxMixtureStartTest, FalseClosuresAreStillRejected) {
  SpoilOptions s;
  s.outliers = 20;
  s.seed = 3;
  const SpoiledGraph spoiled = spoilGraph(world_.clean, s);
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
