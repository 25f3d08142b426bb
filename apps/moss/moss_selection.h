// MossSelection: Map Optimization for Size and Saliency (thesis sec. 5.4.3,
// Alg. 5.1): T hill climbs of K steps over node sets of size C. A climb
// starts from C nodes drawn uniformly; each step swaps one selected node for
// one unselected node (Hamming distance 2) and keeps the swap when the
// training error (eq. 5.3, the RMSE over S training trials, Localizer::rmse)
// drops. The best set over all climbs is returned.
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

namespace hamal::moss {

struct MossConfig {
  int climbs = 10;   // T
  int steps = 1000;  // K
  std::uint64_t seed = 1;
  int threads = 2;
  std::string checkpoint_dir;  // empty: no checkpoints
  int checkpoint_every = 25;
  // Called from worker threads (serialised) after each evaluation.
  std::function<void(int climb, int step, double current, double best)> progress;
};

struct MossResult {
  Selection best;
  double best_error = 0.0;
  std::vector<double> climb_errors;  // each climb's final training error
  std::uint64_t evaluations = 0;     // maps evaluated in this run (resumed ones excluded)
};

MossResult mossSelect(Localizer& training, int c, const MossConfig& config);

}  // namespace hamal::moss
