// TruncatedObjectiveCheck (backends/robust/truncated_objective_check.h): an
// answer that gave up true closures is in doubt, the optimum is not, an
// answer with most closures beyond c2 is in doubt, and the models that
// carry the check (PCM, max-mixtures started at the map) report it unless
// gnc_doubt is off.
#include "backends/robust/truncated_objective_check.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "apps/bench/bench_runner.h"
#include "apps/bench/step_runner.h"
#include "apps/common/cli.h"
#include "apps/generator/manhattan_world.h"
#include "apps/robust/false_loop_closures.h"
#include "apps/robust/robust_loop_closures.h"
#include "backends/robust/loop_closure.h"
#include "backends/robust/max_mixture_start.h"
#include "backends/robust/pcm_front_end.h"
#include "core/error.h"

namespace hamal::robust {
namespace {

struct World {
  Registry registry;
  Graph clean;
  Values optimum;
};

const World& world() {
  static const World w = [] {
    World out;
    apps::setUpRegistry(out.registry, {});
    apps::ManhattanWorldOptions m;
    m.poses = 200;
    m.seed = 2;
    out.clean = apps::generateManhattanWorld(m).graph;
    const apps::BatchOptimum opt =
        apps::solveBatchOptimum(out.clean, ThesisProtocol(out.clean), 0, out.registry, "cholesky");
    EXPECT_TRUE(opt.status.ok()) << opt.status.message;
    out.optimum = opt.estimate;
    return out;
  }();
  return w;
}

TruncatedObjectiveCheck makeCheck(const World& w) {
  return TruncatedObjectiveCheck([&w] { return w.registry.makeBackend("aprilsam"); }, isLoopClosure,
                                 GncOptions());
}

std::size_t closures(const Graph& g) {
  std::size_t n = 0;
  for (const FactorPtr& f : g.factors) n += isLoopClosure(*f);
  return n;
}

TEST(TruncatedObjectiveCheck, AnAnswerThatGaveUpTheTrueClosuresIsInDoubt) {
  const World& w = world();
  ASSERT_GT(closures(w.clean), 20u);
  TruncatedObjectiveCheck check = makeCheck(w);
  const Step batch = ThesisProtocol(w.clean).batch();
  check.add(batch);
  // The odometry's guesses: every closure left to the drift, as a
  // max-mixture whose null hypothesis won everywhere would leave them.
  const Status s = check.judge(batch.new_values);
  EXPECT_EQ(s.code, Status::kUncertain) << s.message;
  EXPECT_NE(s.message.find("cheaper alternative"), std::string::npos) << s.message;
  EXPECT_EQ(check.checks(), 1);
}

TEST(TruncatedObjectiveCheck, TheOptimumIsNotInDoubtAndCostsNoSolve) {
  const World& w = world();
  TruncatedObjectiveCheck check = makeCheck(w);
  check.add(ThesisProtocol(w.clean).batch());
  const Status s = check.judge(w.optimum);
  EXPECT_TRUE(s.ok()) << s.message;
  EXPECT_EQ(check.checks(), 0);  // no closure beyond c2: nothing to re-solve
}

TEST(TruncatedObjectiveCheck, MostClosuresBeyondTheirThresholdIsInDoubt) {
  const World& w = world();
  apps::SpoilOptions o;
  o.outliers = 3 * closures(w.clean);
  o.seed = 4;
  const apps::SpoiledGraph spoiled = apps::spoilGraph(w.clean, o);
  TruncatedObjectiveCheck check = makeCheck(w);
  check.add(ThesisProtocol(spoiled.graph).batch());
  // The clean optimum is the right map, but the data alone cannot tell
  // which three quarters of the closures are the outliers.
  const Status s = check.judge(w.optimum);
  EXPECT_EQ(s.code, Status::kUncertain) << s.message;
  EXPECT_NE(s.message.find("most loop closures rejected"), std::string::npos) << s.message;
}

TEST(TruncatedObjectiveCheck, BetweenChecksTheVerdictStands) {
  const World& w = world();
  TruncatedObjectiveCheck check = makeCheck(w);
  const Step batch = ThesisProtocol(w.clean).batch();
  check.add(batch);
  ASSERT_EQ(check.judge(batch.new_values).code, Status::kUncertain);
  // No new closure: the same verdict without another solve, even at the optimum.
  EXPECT_EQ(check.judge(w.optimum).code, Status::kUncertain);
  EXPECT_EQ(check.checks(), 1);
}

// At the end of a run (judge(..., true)) the closures that came since the
// last check are checked at once, without waiting for them to double.
TEST(TruncatedObjectiveCheck, AtTheEndTheClosuresSinceTheLastCheckAreChecked) {
  const World& w = world();
  const Step all = ThesisProtocol(w.clean).batch();
  Step first = all, rest;
  first.new_factors.clear();
  std::size_t seen = 0, total = closures(w.clean);
  for (const FactorPtr& f : all.new_factors) {
    const bool late = isLoopClosure(*f) && ++seen > total - total / 6;
    (late ? rest.new_factors : first.new_factors).push_back(f);
  }
  TruncatedObjectiveCheck check = makeCheck(w);
  check.add(first);
  ASSERT_TRUE(check.judge(w.optimum).ok());
  check.add(rest);
  // The last sixth of the closures, left to the odometry's drift.
  Values drifted = w.optimum;
  for (const auto& [key, entry] : all.new_values) drifted.setEntry(key, entry);
  EXPECT_TRUE(check.judge(drifted).ok());  // not due: a fifth more closures
  const Status s = check.judge(drifted, true);
  EXPECT_EQ(s.code, Status::kUncertain) << s.message;
}

TEST(TruncatedObjectiveCheck, RefusesAMissingMaker) {
  EXPECT_THROW(TruncatedObjectiveCheck(nullptr, isLoopClosure, GncOptions()), Error);
  EXPECT_THROW(
      TruncatedObjectiveCheck([] { return std::unique_ptr<Backend>(); }, nullptr, GncOptions()),
      Error);
}

// `spec` under the thesis protocol on world() spoiled with three false
// closures to every true one; `backend` keeps the back-end for its estimate.
apps::RunOutcome runThreeFalseToOne(const std::string& spec, std::unique_ptr<Backend>* backend) {
  const World& w = world();
  apps::SpoilOptions o;
  o.outliers = 3 * closures(w.clean);
  o.seed = 5;
  const apps::SpoiledGraph spoiled = apps::spoilGraph(w.clean, o);
  const Registry r = apps::robustRegistry(w.registry);
  apps::RunOptions options;
  options.chi2_every = 0;
  *backend = r.makeBackend(spec);
  return apps::summarizeRows(
      apps::runThesisProtocol(ThesisProtocol(spoiled.graph), **backend, spec, options).rows);
}

// The models that carry the check report it, unless gnc_doubt is off: on a
// graph with three false closures to every true one, the rule "most loop
// closures rejected" fires for PCM and for max-mixtures started at the map.
// PCM over cholesky: no residual covariance, so the share alone is the rule
// (over AprilSAM it weighs the map's refutation: the next test).
TEST(TruncatedObjectiveCheck, PcmAndMaxMixturesCarryItUnlessDoubtIsOff) {
  for (const char* spec : {"cholesky:robust=pcm", "aprilsam:robust=maxmix"}) {
    SCOPED_TRACE(spec);
    for (const bool off : {false, true}) {
      std::unique_ptr<Backend> backend;
      const apps::RunOutcome run =
          runThreeFalseToOne(std::string(spec) + (off ? ",gnc_doubt=off" : ""), &backend);
      if (off) {
        EXPECT_NE(run.status.code, Status::kUncertain) << run.status.message;
      } else {
        EXPECT_EQ(run.status.code, Status::kUncertain) << run.status.message;
        EXPECT_NE(run.status.message.find("most loop closures rejected"), std::string::npos)
            << run.status.message;
      }
    }
  }
}

// PCM over AprilSAM on the same graph: the false closures, drawn between
// random poses of a map whose every loop is closed many times, are refuted
// far beyond their test (near_misses.h), so rejecting three of every four
// closures is no doubt; the answer is the clean map.
TEST(TruncatedObjectiveCheck, PcmOverAprilSamWeighsTheMapsRefutation) {
  std::unique_ptr<Backend> backend;
  const apps::RunOutcome run = runThreeFalseToOne("aprilsam:robust=pcm", &backend);
  EXPECT_TRUE(run.status.ok()) << run.status.message;
  const Values& optimum = world().optimum;
  double worst = 0;
  for (Key key : optimum.keys())
    worst = std::max(worst, (backend->estimate().pose(key).t() - optimum.pose(key).t()).norm());
  EXPECT_LT(worst, 0.05);
}

}  // namespace
}  // namespace hamal::robust
