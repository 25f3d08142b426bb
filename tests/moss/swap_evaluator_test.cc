// SwapEvaluator (thesis Alg. 5.1 lines 4-7): reusing the trials a swap cannot
// change and refusing a swap once it cannot win takes exactly the decisions,
// and gives exactly the errors, of localizing every training trial; MOSS
// picks the same maps both ways while localizing fewer trials.
#include "apps/moss/swap_evaluator.h"

#include <gtest/gtest.h>

#include <random>

#include "apps/moss/moss_selection.h"
#include "backends/builtins.h"
#include "core/error.h"

namespace hamal::moss {
namespace {

struct Corridor {
  World world = loadWorld("CORRIDOR");
  TrialConfig config = scenarioConfig("CORRIDOR");
  PriorMap map;
  std::vector<Trial> trials;
  Registry registry;
  Corridor() {
    map = mappingRun(world, config, 3);
    for (int s = 0; s < 6; ++s) trials.push_back(localizationTrial(world, map, config, 3, 0, s));
    registerBuiltins(registry);
  }
};

const Corridor& corridor() {
  static const Corridor* c = new Corridor();
  return *c;
}

void decidesEverySwapAsLocalizingEveryTrial(Objective objective) {
  const Corridor& w = corridor();
  LocalizerConfig config;
  config.objective = objective;
  Localizer loc(w.map, w.trials, config, w.registry);
  const std::size_t m = loc.mapSize();
  Selection start(m, 0);
  for (int j : {2, 9, 15}) start[j] = 1;
  SwapEvaluator ev(loc, start);
  EXPECT_EQ(ev.error(), loc.error(start));
  std::mt19937_64 rng(7);
  int accepted = 0;
  for (int k = 0; k < 40; ++k) {
    const std::vector<int> in = selectedNodes(ev.current());
    std::vector<int> out;
    for (std::size_t j = 0; j < m; ++j)
      if (!ev.current()[j]) out.push_back(static_cast<int>(j));
    const int drop = in[rng() % in.size()], add = out[rng() % out.size()];
    Selection candidate = ev.current();
    candidate[drop] = 0;
    candidate[add] = 1;
    const double slow = loc.error(candidate);
    const bool slow_accepts = slow < ev.error();
    ASSERT_EQ(ev.trySwap(drop, add), slow_accepts) << "swap " << drop << " -> " << add;
    if (slow_accepts) {
      ++accepted;
      EXPECT_EQ(ev.current(), candidate);
      EXPECT_EQ(ev.error(), slow);  // bit for bit: same trials, same order of summation
    }
  }
  EXPECT_GT(accepted, 0);
  EXPECT_LT(ev.trialsLocalized(), ev.trialsConsidered());  // something was reused or skipped
}

TEST(SwapEvaluator, DecidesEverySwapAsLocalizingEveryTrialDoes) {
  decidesEverySwapAsLocalizingEveryTrial(Objective::kRmse);
}

// Eq. 5.3's sum of error norms: the same reuse and refusal, the same decisions.
TEST(SwapEvaluator, DecidesEverySwapAsLocalizingEveryTrialDoesForTheSumOfNorms) {
  decidesEverySwapAsLocalizingEveryTrial(Objective::kSumOfNorms);
}

// The objective MOSS minimises is the one asked for; the mean norm is at most
// the RMSE (Jensen) and differs from it when the errors do.
TEST(Localizer, ErrorIsTheObjectiveAskedFor) {
  const Corridor& w = corridor();
  LocalizerConfig config;
  Localizer rmse(w.map, w.trials, config, w.registry);
  config.objective = Objective::kSumOfNorms;
  Localizer norms(w.map, w.trials, config, w.registry);
  Selection some(rmse.mapSize(), 0);
  some[3] = some[12] = 1;
  EXPECT_EQ(rmse.error(some), rmse.rmse(some));
  EXPECT_EQ(norms.error(some), norms.meanError(some));
  EXPECT_LT(norms.meanError(some), norms.rmse(some));
  double sum = 0.0;
  std::size_t poses = 0;
  for (std::size_t s = 0; s < norms.trials(); ++s) {
    const Localization l = norms.localize(static_cast<int>(s), some);
    sum += l.sum_error_norm;
    poses += l.estimate.size();
  }
  EXPECT_NEAR(norms.meanError(some), sum / poses, 1e-12);
  EXPECT_EQ(parseObjective("sum_of_norms"), Objective::kSumOfNorms);
  EXPECT_THROW(parseObjective("mae"), Error);
}

TEST(SwapEvaluator, RefusesASwapThatIsNotOne) {
  const Corridor& w = corridor();
  Localizer loc(w.map, w.trials, LocalizerConfig(), w.registry);
  Selection start(loc.mapSize(), 0);
  start[4] = 1;
  SwapEvaluator ev(loc, start);
  EXPECT_THROW(ev.trySwap(5, 6), Error);   // 5 is not selected
  EXPECT_THROW(ev.trySwap(4, 4), Error);   // 4 is already in
  EXPECT_THROW(ev.trySwap(4, 99), Error);  // no such node
  EXPECT_THROW(SwapEvaluator(loc, Selection(3, 1)), Error);
}

TEST(Moss, ReuseGivesTheSameMapsAndErrorsWithFewerLocalizations) {
  const Corridor& w = corridor();
  Localizer loc(w.map, w.trials, LocalizerConfig(), w.registry);
  MossConfig c;
  c.climbs = 3;
  c.steps = 15;
  c.seed = 5;
  c.threads = 2;
  for (int size : {2, 5}) {
    c.reuse = false;
    const MossResult slow = mossSelect(loc, size, c);
    c.reuse = true;
    const MossResult fast = mossSelect(loc, size, c);
    EXPECT_EQ(fast.best, slow.best) << "C = " << size;
    EXPECT_EQ(fast.best_error, slow.best_error) << "C = " << size;
    EXPECT_EQ(fast.climb_errors, slow.climb_errors) << "C = " << size;
    EXPECT_EQ(fast.evaluations, slow.evaluations);
    EXPECT_EQ(slow.trials_localized, slow.trials_considered);
    EXPECT_LT(fast.trials_localized, slow.trials_localized) << "C = " << size;
  }
}

}  // namespace
}  // namespace hamal::moss
