// Tests of the AprilSAM back-end's contract (thesis Alg. 3.1): update
// results, the damped-batch fallback when an incremental update is not
// positive definite, numerical failures as a Status, options and the
// registered variants.
#include "backends/aprilsam/aprilsam_backend.h"

#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include <limits>
#include <map>
#include <utility>

#include "backends/aprilsam/register_aprilsam.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/stopwatch.h"
#include "factors/prior_factor.h"
#include "tests/aprilsam/aprilsam_test_graphs.h"

namespace hamal::aprilsam {
namespace {

using testing::makeAprilSam;

// A range-only-like observation of a Point2 from nowhere: one residual,
// (x - target) * w. Alone it leaves the point's y unconstrained, so the
// normal equations of the point are rank one.
class OneAxisCost : public ceres::SizedCostFunction<1, 2> {
 public:
  OneAxisCost(double target, double w) : target_(target), w_(w) {}
  bool Evaluate(double const* const* x, double* r, double** j) const override {
    r[0] = (x[0][0] - target_) * w_;
    if (j && j[0]) {
      j[0][0] = w_;
      j[0][1] = 0;
    }
    return true;
  }

 private:
  double target_, w_;
};

class OneAxisFactor : public Factor {
 public:
  OneAxisFactor(Key key, double target, double w)
      : Factor({key}, std::make_unique<OneAxisCost>(target, w)) {}
  std::string tag() const override { return "TEST_ONE_AXIS"; }
  void writeFields(std::ostream& os) const override { os << keys()[0]; }
};

Step firstStep() {
  Step s;
  s.index = 0;
  s.new_values.insert(X(0), Pose2(0, 0, 0));
  s.new_factors.push_back(std::make_shared<PriorFactor>(
      X(0), Pose2(0, 0, 0), Eigen::Vector3d(1e4, 1e4, 1e3).asDiagonal().toDenseMatrix()));
  return s;
}

Step odometryStep(int i) {
  Step s;
  s.index = i;
  s.new_values.insert(X(i), Pose2(i, 0, 0));
  s.new_factors.push_back(std::make_shared<BetweenFactor>(X(i - 1), X(i), Pose2(1, 0, 0),
                                                          Eigen::Matrix3d::Identity() * 100));
  return s;
}

TEST(AprilSamBackend, FirstUpdateIsBatchThenIncremental) {
  auto be = makeAprilSam({{"mode", "incremental"}});
  UpdateResult r = be->update(firstStep());
  EXPECT_EQ(r.kind, UpdateKind::kBatch);
  EXPECT_EQ(r.reason, "first update");
  for (int i = 1; i < 5; ++i) {
    r = be->update(odometryStep(i));
    ASSERT_TRUE(r.status.ok());
  }
  EXPECT_EQ(r.kind, UpdateKind::kIncremental);
  // An odometry step refactors the new pose and the one it hangs from.
  EXPECT_EQ(r.columns_recomputed, 6u);
  EXPECT_EQ(r.columns_total, 15u);
  EXPECT_EQ(r.variables, 5u);
  EXPECT_NEAR(be->estimate().pose(X(4)).x, 4.0, 1e-9);
}

// batch_first: a step the periodic criterion batches runs no incremental
// update before its batch (the batch refactors exactly R's columns), the
// batches fall on the same steps, and the estimate stays the batch's.
TEST(AprilSamBackend, BatchFirstSkipsTheIncrementalUpdateABatchWouldUndo) {
  for (const char* first : {"false", "true"}) {
    SCOPED_TRACE(std::string("batch_first=") + first);
    auto be = makeAprilSam({{"mode", "periodic"}, {"period", "3"}, {"batch_first", first}});
    ASSERT_TRUE(be->update(firstStep()).status.ok());
    for (int i = 1; i < 10; ++i) {
      const UpdateResult r = be->update(odometryStep(i));
      ASSERT_TRUE(r.status.ok());
      EXPECT_EQ(r.kind, i % 3 == 0 ? UpdateKind::kBatch : UpdateKind::kIncremental) << i;
      if (r.kind != UpdateKind::kBatch) continue;
      // Without batch_first the step's own update (6 columns) comes first.
      EXPECT_EQ(r.columns_recomputed, r.columns_total + (std::string(first) == "true" ? 0 : 6))
          << i;
    }
    EXPECT_EQ(be->batches(), 4);
    EXPECT_NEAR(be->estimate().pose(X(9)).x, 9.0, 1e-9);
  }
}

TEST(AprilSamBackend, NotPositiveDefiniteIncrementalFallsBackToDampedBatch) {
  auto be = makeAprilSam({{"mode", "incremental"}});
  ASSERT_TRUE(be->update(firstStep()).status.ok());
  ASSERT_TRUE(be->update(odometryStep(1)).status.ok());
  Step s;
  s.index = 2;
  s.new_values.insert(L(0), Point2(3.0, 1.0));
  s.new_factors.push_back(std::make_shared<OneAxisFactor>(L(0), 2.5, 10.0));
  const UpdateResult r = be->update(s);
  EXPECT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_EQ(r.kind, UpdateKind::kBatch);
  EXPECT_NE(r.reason.find("not positive definite at l0"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("damped"), std::string::npos) << r.reason;
  // The constrained axis moves to its target, the free one stays put.
  EXPECT_NEAR(be->estimate().point(L(0)).x(), 2.5, 1e-3);
  EXPECT_NEAR(be->estimate().point(L(0)).y(), 1.0, 1e-6);
  // Later steps go on incrementally from the damped factor.
  const UpdateResult next = be->update(odometryStep(2));
  EXPECT_TRUE(next.status.ok());
  EXPECT_EQ(next.kind, UpdateKind::kIncremental);
}

// One PhaseClock per update times every path (incremental, batch, the top
// re-eliminated, a damped batch after a failed incremental update): no
// phase is counted twice and what no phase counted is other, so the phases
// add up to the update's wall time.
TEST(AprilSamBackend, PhaseTimesAddUpToTheUpdatesWallTime) {
  for (const char* reeliminate : {"full", "top"}) {
    SCOPED_TRACE(std::string("reeliminate=") + reeliminate);
    auto be = makeAprilSam({{"mode", "periodic"}, {"period", "3"}, {"reeliminate", reeliminate}});
    double phases = 0, wall = 0;
    std::map<UpdateKind, int> kinds;
    auto update = [&](const Step& step) {
      const Stopwatch clock;
      const UpdateResult r = be->update(step);
      const double seconds = clock.seconds();
      ASSERT_TRUE(r.status.ok()) << r.status.message;
      for (double t : {r.time.linearize, r.time.order, r.time.factor, r.time.solve, r.time.other})
        EXPECT_GE(t, 0.0);
      EXPECT_LE(r.time.total(), seconds);
      phases += r.time.total();
      wall += seconds;
      ++kinds[r.kind];
    };
    update(firstStep());
    for (int i = 1; i < 120; ++i) {
      Step s = odometryStep(i);
      if (i % 7 == 0)  // a loop closure, so the top spans more than the newest pose
        s.new_factors.push_back(std::make_shared<BetweenFactor>(X(i - 6), X(i), Pose2(6, 0, 0),
                                                                Eigen::Matrix3d::Identity() * 100));
      update(s);
    }
    Step s;
    s.index = 120;
    s.new_values.insert(L(0), Point2(3.0, 1.0));
    s.new_factors.push_back(std::make_shared<OneAxisFactor>(L(0), 2.5, 10.0));
    update(s);  // not positive definite: the damped batch
    EXPECT_GT(kinds[UpdateKind::kIncremental], 0);
    EXPECT_GT(kinds[UpdateKind::kBatch], 0);
    // Only the call itself is outside the clock.
    EXPECT_GE(phases, 0.5 * wall);
  }
}

// reeliminate=top with a factor R holds at weight 0 (a loop closure a
// robust wrapper rejected; core/factor_weights.h): after a batch R has no
// rows of it, so it ties no top variable to a kept row, and a top variable
// due for relinearisation moves its point although the factor reaches
// below the top. Pinned for it, the variable kept rows linearised where it
// was before the loop moved it, further with every solve (on ais2klinik
// with 1000 false closures, hundreds of metres, and GNC diverged).
TEST(AprilSamBackend, TopReeliminationRelinearisesAVariableOnlyAWeightZeroFactorTies) {
  auto be = makeAprilSam({{"reeliminate", "top"}, {"mode", "periodic"}, {"period", "1"}});
  ASSERT_TRUE(be->update(firstStep()).status.ok());
  const auto closure = [](int a, int b, Pose2 z) {
    return std::make_shared<BetweenFactor>(X(a), X(b), z, Eigen::Matrix3d::Identity() * 100);
  };
  const FactorPtr rejected = closure(1, 45, Pose2(44, 0, 0));
  for (int i = 1; i < 60; ++i) {
    Step s = odometryStep(i);
    if (i == 45) s.new_factors.push_back(rejected);
    ASSERT_TRUE(be->update(s).status.ok()) << i;
  }
  // Rejected, then a batch: no update has anything new or due, so the
  // periodic decision finds no top and refactors all of R without it.
  be->setFactorWeight(rejected.get(), 0);
  UpdateResult r;
  for (int k = 0; k < 3 && r.kind != UpdateKind::kBatch; ++k) {
    r = be->update(Step{});
    ASSERT_TRUE(r.status.ok()) << r.status.message;
  }
  ASSERT_EQ(r.kind, UpdateKind::kBatch) << r.reason;
  // Closures x40-x60 along the odometry and x45-x60 two metres off it
  // move x45 well past delta_T; the top is x40 and the poses above it, x1
  // stays below.
  Step s = odometryStep(60);
  s.new_factors.push_back(closure(40, 60, Pose2(20, 0, 0)));
  s.new_factors.push_back(closure(45, 60, Pose2(15, 2, 0)));
  const Values before = be->estimate();
  r = be->update(s);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  ASSERT_NE(r.reason.find("top re-eliminated"), std::string::npos) << r.reason;
  const Eigen::Vector2d was = before.pose(X(45)).t();
  const double moved = (be->estimate().pose(X(45)).t() - was).norm();
  ASSERT_GT(moved, 0.1);
  // Relinearised at the estimate the step's own solve gave it, the point
  // followed the loop (the top's solve, a second Gauss-Newton step, moves
  // the estimate a little further); pinned, it would be where it was.
  const auto& lin = be->linearizationPoint(X(45)).data;
  EXPECT_GT((Eigen::Vector2d(lin[0], lin[1]) - was).norm(), 0.5 * moved) << moved;
}

// The partial back-substitution leaves a row's dx where its change is
// under backsolve_tolerance; the closing verdict solves every row, so at
// the end of a run the estimate is R's own solution, and the chi2 no worse.
TEST(AprilSamBackend, TheClosingVerdictSolvesEveryRow) {
  testing::RandomGraphOptions go;
  go.poses = 200;
  go.loop_probability = 0.1;
  const Graph graph = testing::randomGraph(go);
  ThesisProtocol protocol(graph);
  auto be = makeAprilSam({{"backsolve_tolerance", "0.05"}});
  std::unique_ptr<PartialBacksolve> exact;
  const auto gap = [&] {
    exact = std::make_unique<PartialBacksolve>(be->backsolve());
    exact->solve(be->factor(), true, 0.0);
    double worst = 0;
    for (int p = 0; p < be->factor().size(); ++p)
      for (int k = 0; k < 3; ++k)
        worst = std::max(worst, std::abs(be->backsolve().dx(p)[k] - exact->dx(p)[k]));
    return worst;
  };
  // The run stops at the first incremental step the tolerance left behind.
  std::size_t i = 0;
  for (; i < protocol.size(); ++i) {
    const UpdateResult r = be->update(protocol.step(i, be->estimate()));
    ASSERT_TRUE(r.status.ok()) << i;
    if (r.kind == UpdateKind::kIncremental && gap() > 1e-4) break;
  }
  ASSERT_LT(i, protocol.size()) << "no step left a row behind";
  std::vector<FactorPtr> so_far;
  for (const FactorPtr& f : graph.factors) {
    bool held = true;
    for (Key k : f->keys()) held &= be->estimate().contains(k);
    if (held) so_far.push_back(f);
  }
  const double before = chi2(so_far, be->estimate());
  ASSERT_TRUE(be->closingVerdict().ok());
  EXPECT_EQ(gap(), 0.0);
  EXPECT_LE(chi2(so_far, be->estimate()), before);
}

TEST(AprilSamBackend, TheClosingVerdictLeavesAnExactRunAsItIs) {
  const Graph graph = testing::randomGraph({});
  ThesisProtocol protocol(graph);
  auto be = makeAprilSam({{"backsolve_tolerance", "0"}});
  for (std::size_t i = 0; i < protocol.size(); ++i)
    ASSERT_TRUE(be->update(protocol.step(i, be->estimate())).status.ok()) << i;
  const Values before = be->estimate();
  ASSERT_TRUE(be->closingVerdict().ok());
  for (const auto& [key, entry] : before)
    for (int k = 0; k < dimension(entry.type); ++k)
      EXPECT_EQ(be->estimate().entry(key).data[k], entry.data[k]) << key.str();
}

TEST(AprilSamBackend, NonFiniteFactorIsANumericalFailureStatus) {
  auto be = makeAprilSam({});
  ASSERT_TRUE(be->update(firstStep()).status.ok());
  Step s;
  s.index = 1;
  s.new_values.insert(L(3), Point2(1.0, 1.0));
  s.new_factors.push_back(
      std::make_shared<OneAxisFactor>(L(3), std::numeric_limits<double>::infinity(), 1.0));
  UpdateResult r;
  ASSERT_NO_THROW(r = be->update(s));
  EXPECT_EQ(r.status.code, Status::kNumericalFailure);
  ASSERT_EQ(r.status.keys.size(), 1u);
  EXPECT_EQ(r.status.keys[0], L(3));
}

TEST(AprilSamBackend, BadInputThrowsAndLeavesTheBackendUnchanged) {
  auto be = makeAprilSam({});
  be->update(firstStep());
  EXPECT_THROW(be->update(firstStep()), Error);  // x0 again
  Step s = odometryStep(1);
  s.new_factors.push_back(
      std::make_shared<BetweenFactor>(X(0), X(7), Pose2(1, 0, 0), Eigen::Matrix3d::Identity()));
  EXPECT_THROW(be->update(s), Error);  // x7 was never added
  EXPECT_EQ(be->estimate().size(), 1u);
  EXPECT_EQ(be->factors().size(), 1u);
  const UpdateResult r = be->update(odometryStep(1));
  EXPECT_TRUE(r.status.ok());
  EXPECT_NEAR(be->estimate().pose(X(1)).x, 1.0, 1e-9);
}

TEST(AprilSamBackend, OptionsAreCheckedAndVariantsRegistered) {
  Registry registry;
  registerAprilSamBackends(registry);
  for (const char* name :
       {"aprilsam", "aprilsam-fullsolve", "aprilsam-periodic", "aprilsam-nopredictive"})
    ASSERT_NE(registry.findBackend(name), nullptr) << name;
  const Options full = registry.resolveOptions(BackendSpec::parse("aprilsam-fullsolve"));
  EXPECT_EQ(full.getString("backsolve"), "full");
  const Options nopred = registry.resolveOptions(BackendSpec::parse("aprilsam-nopredictive"));
  EXPECT_EQ(nopred.getString("mode"), "periodic");
  EXPECT_EQ(nopred.getString("ordering"), "bhamd");
  EXPECT_EQ(registry.resolveOptions(BackendSpec::parse("aprilsam-periodic")).getInt("period"), 10);
  EXPECT_EQ(nopred.getInt("period"), 10);
  for (const auto& spec : registry.findBackend("aprilsam")->options)
    EXPECT_FALSE(spec.help.empty()) << spec.name;
  EXPECT_THROW(registry.makeBackend("aprilsam:ordering=colamd"), Error);
  EXPECT_THROW(registry.makeBackend("aprilsam:backsolve_tolerance=-1"), Error);
  EXPECT_THROW(registry.makeBackend("aprilsam:batch_iterations=0"), Error);
  EXPECT_THROW(registry.makeBackend("aprilsam:n_lc=-1"), Error);
  EXPECT_NO_THROW(registry.makeBackend("aprilsam:n_lc=0"));
  EXPECT_THROW(registry.makeBackend("aprilsam:no_such_option=1"), Error);
  EXPECT_NO_THROW(registry.makeBackend("aprilsam:ordering=natural,batch_iterations=2"));
  const Options top = registry.resolveOptions(BackendSpec::parse("aprilsam-top"));
  EXPECT_EQ(top.getString("reeliminate"), "top");
  EXPECT_EQ(top.getInt("nl_t"), 10);
  EXPECT_EQ(top.getInt("n_lc"), 2);
  EXPECT_DOUBLE_EQ(top.getDouble("delta_t"), 0.13);
  auto message = [&](const std::string& spec) {
    try {
      registry.makeBackend(spec);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("aprilsam-top:ordering=amd").find("reeliminate=top needs ordering=minheap"),
            std::string::npos);
  EXPECT_NE(message("aprilsam-top:top_share=1.5").find("top_share"), std::string::npos);
  EXPECT_NE(message("aprilsam-top:top_relinearize=0").find("top_relinearize"), std::string::npos);
  EXPECT_NE(message("aprilsam-top:top_backoff=-1").find("top_backoff"), std::string::npos);
  EXPECT_NE(message("aprilsam:reeliminate=some").find("reeliminate"), std::string::npos);
}

// Options are parsed once into typed values: each name maps to its choice.
TEST(AprilSamBackend, OptionChoicesAreParsedIntoTheirEnums) {
  using O = AprilSamOptions;
  auto parse = [](std::map<std::string, std::string> given) {
    return O::fromOptions(Options("aprilsam", O::optionSpecs(), given));
  };
  const std::pair<const char*, O::Ordering> orderings[] = {{"minheap", O::Ordering::kMinHeap},
                                                           {"bhamd", O::Ordering::kBhamd},
                                                           {"amd", O::Ordering::kAmd},
                                                           {"natural", O::Ordering::kNatural}};
  for (const auto& [text, value] : orderings)
    EXPECT_EQ(parse({{"ordering", text}}).ordering, value) << text;
  EXPECT_EQ(parse({{"backsolve", "full"}}).backsolve.kind, O::Backsolve::kFull);
  EXPECT_EQ(parse({{"backsolve", "partial"}}).backsolve.kind, O::Backsolve::kPartial);
  EXPECT_EQ(parse({{"factor_update", "refactor"}}).factor_update, O::FactorUpdate::kRefactor);
  EXPECT_EQ(parse({{"factor_update", "rank"}}).factor_update, O::FactorUpdate::kRank);
  EXPECT_EQ(parse({{"cost", "wallclock"}}).policy.cost, UpdatePolicyOptions::Cost::kWallclock);
  EXPECT_EQ(parse({{"reeliminate", "top"}}).reeliminate, O::Reeliminate::kTop);
  EXPECT_EQ(parse({{"reeliminate", "full"}}).reeliminate, O::Reeliminate::kFull);
  EXPECT_THROW(parse({{"ordering", "colamd"}}), Error);
  // The old spelling of the tolerance is read as the new one for a release.
  EXPECT_EQ(parse({{"backsolve_tol", "0.25"}}).backsolve.tolerance, 0.25);
  EXPECT_THROW(parse({{"backsolve_tol", "0"}, {"backsolve_tolerance", "0"}}), Error);
}

// The defaults --list-backends shows are the values a back-end built from
// them gets: each equals the AprilSamOptions default (a printed "0" for
// backsolve_tolerance=1e-9 once made every run exact and slow).
TEST(AprilSamBackend, ListedDefaultsAreTheOptionDefaults) {
  const AprilSamOptions d;
  const AprilSamOptions listed =
      AprilSamOptions::fromOptions(Options("aprilsam", AprilSamOptions::optionSpecs(), {}));
  EXPECT_EQ(listed.backsolve.tolerance, d.backsolve.tolerance);
  EXPECT_EQ(listed.loop_closure_radius, d.loop_closure_radius);
  EXPECT_EQ(listed.batch.damping, d.batch.damping);
  EXPECT_EQ(listed.n_lc, d.n_lc);
  EXPECT_EQ(listed.batch.iterations, d.batch.iterations);
  EXPECT_EQ(listed.ordering, d.ordering);
  EXPECT_EQ(listed.backsolve.kind, d.backsolve.kind);
  EXPECT_EQ(listed.policy.delta_t, d.policy.delta_t);
  EXPECT_EQ(listed.policy.big_delta_t, d.policy.big_delta_t);
  EXPECT_EQ(listed.policy.nl_t, d.policy.nl_t);
  EXPECT_EQ(listed.policy.period, d.policy.period);
  EXPECT_EQ(listed.reeliminate, d.reeliminate);
  EXPECT_EQ(listed.top.share, d.top.share);
  EXPECT_EQ(listed.top.relinearize, d.top.relinearize);
  EXPECT_EQ(listed.top.backoff, d.top.backoff);
}

TEST(AprilSamBackend, BatchIterationsAreGaussNewtonSteps) {
  testing::RandomGraphOptions o;
  o.poses = 80;
  o.seed = 3;
  const Graph g = testing::randomGraph(o);
  ThesisProtocol protocol(g);
  // The whole graph in one step, from guesses perturbed far enough that one
  // Gauss-Newton step does not converge: the first update is a batch of
  // batch_iterations Gauss-Newton steps.
  Step step = protocol.batch();
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (const Key& key : step.new_values.keys()) {
    double* d = step.new_values.data(key);
    d[0] += 1.0 * noise(rng);
    d[1] += 1.0 * noise(rng);
    d[2] += 0.3 * noise(rng);
  }
  double chi[2];
  int k = 0;
  for (const char* iters : {"1", "6"}) {
    auto be = makeAprilSam({{"batch_iterations", iters}});
    const UpdateResult r = be->update(step);
    EXPECT_EQ(r.kind, UpdateKind::kBatch);
    EXPECT_EQ(r.iterations, std::stoi(iters));
    std::vector<FactorPtr> all = g.factors;
    all.push_back(protocol.prior());
    chi[k++] = hamal::chi2(all, be->estimate());
  }
  EXPECT_LT(chi[1], chi[0] - 0.01);
}

}  // namespace
}  // namespace hamal::aprilsam
