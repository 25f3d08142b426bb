// Incremental PCM with a bounded step
// (incremental_pairwise_consistency_maximization.h).
#include "backends/robust/incremental_pairwise_consistency_maximization.h"

#include <algorithm>
#include <optional>

#include "backends/robust/maximum_clique.h"
#include "core/error.h"

namespace hamal::robust {

IncrementalPairwiseConsistencyMaximization::IncrementalPairwiseConsistencyMaximization(
    const PcmOptions& options)
    : options_(options), random_(options.seed) {
  if (!(options.threshold > 0)) throw Error("incremental PCM: pcm_threshold must be positive");
  if (options.window < 1) throw Error("incremental PCM: pcm_window must be at least 1");
  if (options.sample < 0) throw Error("incremental PCM: pcm_sample must be >= 0");
}

bool IncrementalPairwiseConsistencyMaximization::consistent(const OdometryChain& chain,
                                                            std::size_t a, std::size_t b) {
  if (a > b) std::swap(a, b);
  const std::uint64_t key = (static_cast<std::uint64_t>(a) << 32) | b;
  const auto it = tested_.find(key);
  if (it != tested_.end()) return it->second;
  ++last_.tests;
  const std::optional<CycleError> cycle = cycleThroughOdometry(chain, closures_[a], closures_[b]);
  if (!cycle) ++unchecked_pairs_;
  const bool ok = !cycle || cycle->mahalanobis2 < options_.threshold;
  tested_.emplace(key, ok);
  return ok;
}

void IncrementalPairwiseConsistencyMaximization::addBatch(
    const OdometryChain& chain, const std::vector<LoopClosure>& closures) {
  if (!closures_.empty()) {
    for (const auto& c : closures) add(chain, c);
    return;
  }
  const PcmResult r = pairwiseConsistencyMaximization(chain, closures, options_);
  if (closures.size() >= (std::size_t{1} << 32))
    throw Error("incremental PCM: more than 2^32 loop closures");
  closures_ = closures;
  accepted_ = r.accepted;
  unchecked_pairs_ += r.unchecked_pairs;
  excluded_.assign(closures.size(), false);
  last_ = StepCost{};
  last_.vertices = closures.size();
  last_.tests = closures.size() * (closures.size() - (closures.empty() ? 0 : 1)) / 2;
  last_.searched = true;
  last_.exact = r.exact;
}

std::size_t IncrementalPairwiseConsistencyMaximization::addRejected(const OdometryChain& /*chain*/,
                                                                    const LoopClosure& closure) {
  if (closures_.size() + 1 >= (std::size_t{1} << 32))
    throw Error("incremental PCM: more than 2^32 loop closures");
  last_ = StepCost{};
  closures_.push_back(closure);
  accepted_.push_back(false);
  excluded_.push_back(true);
  return closures_.size() - 1;
}

std::size_t IncrementalPairwiseConsistencyMaximization::add(const OdometryChain& chain,
                                                            const LoopClosure& closure) {
  if (closures_.size() + 1 >= (std::size_t{1} << 32))
    throw Error("incremental PCM: more than 2^32 loop closures");
  last_ = StepCost{};
  const std::size_t n = closures_.size();
  const std::size_t k = static_cast<std::size_t>(options_.window);
  const std::size_t window_start = n > k ? n - k : 0;
  std::vector<std::size_t> v;
  for (std::size_t i = window_start; i < n; ++i)
    if (!excluded_[i]) v.push_back(i);
  if (window_start > 0) {
    std::uniform_int_distribution<std::size_t> draw(0, window_start - 1);
    std::vector<std::size_t> drawn;
    for (int s = 0; s < options_.sample; ++s) {
      const std::size_t i = draw(random_);
      if (accepted_[i]) drawn.push_back(i);
    }
    std::sort(drawn.begin(), drawn.end());
    drawn.erase(std::unique(drawn.begin(), drawn.end()), drawn.end());
    v.insert(v.begin(), drawn.begin(), drawn.end());
  }
  closures_.push_back(closure);
  accepted_.push_back(false);
  excluded_.push_back(false);
  tested_.reserve(tested_.size() + v.size());
  bool extends = true;
  for (std::size_t i : v)
    if (!consistent(chain, i, n) && accepted_[i]) extends = false;
  v.push_back(n);
  last_.vertices = v.size();
  if (extends) {
    accepted_[n] = true;
    return n;
  }
  ConsistencyGraph g;
  g.vertices = static_cast<int>(v.size());
  std::vector<bool> preferred(v.size());
  for (std::size_t a = 0; a < v.size(); ++a) {
    preferred[a] = accepted_[v[a]];
    for (std::size_t b = a + 1; b < v.size(); ++b)
      if (consistent(chain, v[a], v[b]))
        g.edges.emplace_back(static_cast<int>(a), static_cast<int>(b));
  }
  const CliqueResult clique = maximumClique(g, preferred);
  last_.searched = true;
  last_.exact = clique.exact;
  for (std::size_t i : v) accepted_[i] = false;
  for (int m : clique.members) accepted_[v[static_cast<std::size_t>(m)]] = true;
  return n;
}

}  // namespace hamal::robust
