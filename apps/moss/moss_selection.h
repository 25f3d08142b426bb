// MossSelection: Map Optimization for Size and Saliency (thesis sec. 5.4.3,
// Alg. 5.1): T hill climbs of K steps over node sets of size C. A climb
// starts from C nodes drawn uniformly; each step swaps one selected node for
// one unselected node (Hamming distance 2) and keeps the swap when the
// training error (over S training trials, Localizer::error: the RMSE, or
// eq. 5.3's sum of error norms) drops. The best set over all climbs is returned.
//
// A climb evaluates its swaps with a SwapEvaluator, which localizes only the
// training trials a swap can change and stops as soon as the swap cannot
// win; `reuse = false` localizes every trial for every swap (the reference
// the fast path is tested against: both take the same decisions).
//
// The climbs are independent and run in parallel on `threads` threads; they
// share the Localizer and so its scan-match cache. Each climb is a function
// of (seed, C, t) alone, so the result does not depend on the thread count.
// With a checkpoint directory, a climb writes its state (step, sets, errors,
// random generator) every `checkpoint_every` steps and a restarted run
// continues from there.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "apps/moss/localizer.h"
#include "apps/moss/selection.h"
#include "apps/moss/swap_evaluator.h"

namespace hamal::moss {

struct MossConfig {
  int climbs = 10;   // T
  int steps = 1000;  // K
  std::uint64_t seed = 1;
  int threads = 2;
  std::string checkpoint_dir;  // empty: no checkpoints
  int checkpoint_every = 25;
  bool reuse = true;  // SwapEvaluator; false: Localizer::rmse on every trial
  // >= 0: run only this climb (a process of its own, e.g. a Slurm array
  // task, writing its checkpoint); the result is that climb's. The climbs'
  // picking is then a later run over the finished checkpoints.
  int only_climb = -1;
  // Called from worker threads (serialised) after each evaluation.
  std::function<void(int climb, int step, double current, double best)> progress;
};

struct MossResult {
  Selection best;
  double best_error = 0.0;
  std::vector<double> climb_errors;  // each climb's final training error
  std::uint64_t evaluations = 0;     // maps evaluated in this run (resumed ones excluded)
  // Of the evaluations' trial localizations (evaluations x S), how many were
  // run; the rest were reused or made unnecessary (SwapEvaluator).
  std::uint64_t trials_localized = 0, trials_considered = 0;
};

MossResult mossSelect(Localizer& training, int c, const MossConfig& config);

}  // namespace hamal::moss
