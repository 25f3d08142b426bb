// SwapEvaluator: the training error of eq. 5.3 for MOSS' one-swap neighbours
// (thesis Alg. 5.1, lines 4-7) without localizing every training trial again.
//
// A swap (one node out, one in) changes a trial's localization only if, at
// some pose, the node localize() chose was the one dropped, or the one added
// is nearer to that pose's prediction than the node chosen. Until the first
// such pose the trial's steps, and so its back-end, predictions and
// (cached) scan matches, are exactly those of the current map; if there is
// no such pose the whole trial is, and its cost (Localizer::cost: squared
// errors or error norms) is reused. The affected trials are localized;
// since costs are non-negative, once
// the reused ones plus those localized so far exceed the current map's sum
// the swap cannot lower the error and is refused without localizing the
// rest. An accepted swap's error is summed in trial order, as
// Localizer::rmse sums it, so the climb takes the same decisions, bit for
// bit, as one that localizes every trial (tests/moss: same selections and
// errors both ways).
#pragma once

#include <cstdint>
#include <vector>

#include "apps/moss/localizer.h"
#include "apps/moss/selection.h"

namespace hamal::moss {

class SwapEvaluator {
 public:
  // Localizes every training trial with `start`.
  SwapEvaluator(Localizer& training, Selection start);

  const Selection& current() const { return current_; }
  double error() const { return error_; }  // of current(), as Localizer::error

  // Swaps `drop` (selected) for `add` (not selected) if that lowers the
  // training error; returns whether it did.
  bool trySwap(int drop, int add);

  // Trials localized by trySwap (the rest were reused or skipped).
  std::uint64_t trialsLocalized() const { return localized_; }
  std::uint64_t trialsConsidered() const { return considered_; }

 private:
  bool affects(const Localization& l, int drop, int add) const;
  double rmseOf(const std::vector<double>& sse) const;

  Localizer& training_;
  Selection current_;
  std::vector<Localization> trials_;  // current_'s localization of each trial
  std::vector<double> sse_;           // per trial, Localizer::cost
  std::size_t poses_ = 0;
  double error_ = 0.0;
  std::uint64_t localized_ = 0, considered_ = 0;
};

}  // namespace hamal::moss
