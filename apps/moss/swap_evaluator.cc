// SwapEvaluator: see swap_evaluator.h (thesis Alg. 5.1, eq. 5.3).
#include "apps/moss/swap_evaluator.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/error.h"

namespace hamal::moss {

SwapEvaluator::SwapEvaluator(Localizer& training, Selection start)
    : training_(training), current_(std::move(start)) {
  if (current_.size() != training_.mapSize())
    throw Error("SwapEvaluator: a selection of " + std::to_string(current_.size()) +
                " nodes for a map of " + std::to_string(training_.mapSize()));
  for (std::size_t s = 0; s < training_.trials(); ++s) {
    trials_.push_back(training_.localize(static_cast<int>(s), current_));
    sse_.push_back(training_.cost(trials_.back()));
    poses_ += trials_.back().estimate.size();
  }
  error_ = rmseOf(sse_);
}

double SwapEvaluator::rmseOf(const std::vector<double>& sse) const {
  double sum = 0.0;
  for (double e : sse) sum += e;
  return training_.errorOf(sum, poses_);
}

bool SwapEvaluator::affects(const Localization& l, int drop, int add) const {
  for (std::size_t i = 1; i < l.node.size(); ++i) {
    const int chosen = l.node[i];
    if (chosen == drop) return true;
    // localize() keeps the first strictly nearer node in index order.
    const double d = training_.nodeDistance(add, l.predicted[i]);
    if (d < l.node_distance[i] || (d == l.node_distance[i] && chosen >= 0 && add < chosen))
      return true;
  }
  return false;
}

bool SwapEvaluator::trySwap(int drop, int add) {
  if (drop < 0 || add < 0 || static_cast<std::size_t>(drop) >= current_.size() ||
      static_cast<std::size_t>(add) >= current_.size() || !current_[drop] || current_[add])
    throw Error("SwapEvaluator: swap " + std::to_string(drop) + " -> " + std::to_string(add) +
                " does not take a selected node out and an unselected one in");
  Selection candidate = current_;
  candidate[drop] = 0;
  candidate[add] = 1;

  // Affected trials, those that leaned most on the dropped node first: they
  // are the likeliest to get worse, and a refusal then comes sooner.
  std::vector<std::pair<int, int>> affected;  // (-steps matched to drop, trial)
  double bound = 0.0;                         // reused costs plus those localized so far
  for (std::size_t s = 0; s < trials_.size(); ++s) {
    if (affects(trials_[s], drop, add)) {
      const auto& nodes = trials_[s].node;
      affected.emplace_back(-static_cast<int>(std::count(nodes.begin(), nodes.end(), drop)),
                            static_cast<int>(s));
    } else {
      bound += sse_[s];
    }
  }
  std::sort(affected.begin(), affected.end());
  considered_ += trials_.size();
  double current_sum = 0.0;
  for (double e : sse_) current_sum += e;
  // The margin keeps summation-order rounding from refusing a swap that the
  // in-order sum would accept.
  const double refuse_above = current_sum * (1.0 + 1e-9) + 1e-300;

  std::vector<std::pair<int, Localization>> fresh;
  for (const auto& [uses, s] : affected) {
    (void)uses;
    Localization l = training_.localize(s, candidate);
    ++localized_;
    bound += training_.cost(l);
    fresh.emplace_back(s, std::move(l));
    if (bound > refuse_above) return false;
  }
  std::vector<double> sse = sse_;
  for (const auto& f : fresh) sse[f.first] = training_.cost(f.second);
  const double e = rmseOf(sse);
  if (!(e < error_)) return false;
  for (auto& f : fresh) trials_[f.first] = std::move(f.second);
  sse_ = std::move(sse);
  current_ = std::move(candidate);
  error_ = e;
  return true;
}

}  // namespace hamal::moss
