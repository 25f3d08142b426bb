// GaugeFreedom: see gauge_freedom.h.
#include "core/gauge_freedom.h"

#include <numeric>
#include <unordered_map>

namespace hamal {

namespace {

// Union-find over variable indices, with path halving.
class Parts {
 public:
  explicit Parts(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  std::size_t find(std::size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void join(std::size_t a, std::size_t b) { parent_[find(a)] = find(b); }

 private:
  std::vector<std::size_t> parent_;
};

}  // namespace

std::optional<Key> unanchoredVariable(const std::vector<Key>& variables,
                                      const std::vector<FactorPtr>& factors,
                                      const std::vector<Key>& fixed) {
  std::unordered_map<Key, std::size_t> index;
  index.reserve(variables.size());
  for (std::size_t i = 0; i < variables.size(); ++i) index.emplace(variables[i], i);
  const auto at = [&](Key k) {
    const auto it = index.find(k);
    return it == index.end() ? variables.size() : it->second;
  };
  Parts parts(variables.size());
  std::vector<char> anchor(variables.size(), 0);
  for (const FactorPtr& f : factors) {
    const std::vector<Key>& keys = f->keys();
    if (keys.empty()) continue;
    const std::size_t first = at(keys.front());
    if (first == variables.size()) continue;
    if (keys.size() == 1) anchor[first] = 1;
    for (std::size_t j = 1; j < keys.size(); ++j) {
      const std::size_t other = at(keys[j]);
      if (other != variables.size()) parts.join(first, other);
    }
  }
  for (Key k : fixed) {
    const std::size_t i = at(k);
    if (i != variables.size()) anchor[i] = 1;
  }
  std::vector<char> anchored(variables.size(), 0);
  for (std::size_t i = 0; i < variables.size(); ++i)
    if (anchor[i]) anchored[parts.find(i)] = 1;
  for (std::size_t i = 0; i < variables.size(); ++i)
    if (!anchored[parts.find(i)]) return variables[i];
  return std::nullopt;
}

Status gaugeFreedomStatus(const std::string& backend, const std::vector<Key>& variables,
                          const std::vector<FactorPtr>& factors, const std::vector<Key>& fixed) {
  const std::optional<Key> free = unanchoredVariable(variables, factors, fixed);
  if (!free) return Status();
  return Status::numericalFailure(
      backend + ": nothing anchors the part of the graph that holds " + free->str() +
          " (no prior, no fixed variable): its solution is unique only up to a rigid motion; "
          "add a prior or fix a variable",
      {*free});
}

}  // namespace hamal
