// NoiseScale: see noise_scale.h.
#include "backends/robust/noise_scale.h"

#include <cmath>
#include <sstream>
#include <string>
#include <unordered_map>

#include "core/error.h"

namespace hamal::robust {

namespace {

// Union-find over the keys the kept factors touch.
class Parts {
 public:
  std::size_t id(Key k) {
    const auto [it, added] = index_.emplace(k, parent_.size());
    if (added) parent_.push_back(parent_.size());
    return it->second;
  }
  std::size_t root(std::size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void join(std::size_t a, std::size_t b) { parent_[root(a)] = root(b); }
  std::size_t size() const { return parent_.size(); }
  const std::unordered_map<Key, std::size_t>& index() const { return index_; }

 private:
  std::unordered_map<Key, std::size_t> index_;
  std::vector<std::size_t> parent_;
};

constexpr int kPlaneGauge = 3;  // the rigid motions of the plane

}  // namespace

NoiseScale aPosterioriVarianceFactor(const std::vector<FactorPtr>& inliers,
                                     const std::vector<FactorPtr>& candidates,
                                     const std::vector<double>& c2, const std::vector<Key>& fixed,
                                     const Values& values) {
  if (c2.size() != candidates.size())
    throw Error("aPosterioriVarianceFactor: " + std::to_string(candidates.size()) +
                " candidates but " + std::to_string(c2.size()) + " thresholds");
  NoiseScale out;
  double rows = 0;
  Parts parts;
  std::vector<bool> anchored;
  const auto keep = [&](const Factor& f, double chi2) {
    out.chi2 += chi2;
    rows += f.residualDim();
    const std::vector<Key>& keys = f.keys();
    for (Key k : keys) parts.id(k);
    anchored.resize(parts.size(), false);
    for (std::size_t i = 1; i < keys.size(); ++i) parts.join(parts.id(keys[0]), parts.id(keys[i]));
    if (keys.size() == 1) anchored[parts.id(keys[0])] = true;
  };
  for (const FactorPtr& f : inliers) keep(*f, f->chi2(values));
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const double s = candidates[i]->chi2(values);
    if (s <= c2[i]) keep(*candidates[i], s);
  }
  if (!std::isfinite(out.chi2))
    throw Error("aPosterioriVarianceFactor: not finite at these values");
  std::vector<bool> fixed_key(parts.size(), false);
  for (Key k : fixed)
    if (parts.index().count(k)) anchored[parts.id(k)] = fixed_key[parts.id(k)] = true;
  // A part is anchored when any of its variables is.
  std::vector<bool> root_anchored(parts.size(), false);
  for (std::size_t i = 0; i < parts.size(); ++i)
    if (anchored[i]) root_anchored[parts.root(i)] = true;
  double unknowns = 0;
  for (const auto& [key, i] : parts.index())
    if (!fixed_key[i]) unknowns += values.dim(key);
  for (std::size_t i = 0; i < parts.size(); ++i)
    if (parts.root(i) == i && !root_anchored[i]) unknowns -= kPlaneGauge;
  out.redundancy = rows - unknowns;
  return out;
}

bool noiseOverstated(const NoiseScale& scale) {
  return scale.redundancy >= kMinRedundancy && scale.factor() < kOverstatedNoise;
}

Status noiseScaleDoubt(const NoiseScale& scale, double scaled_c2, double objective,
                       double alternative, double margin) {
  if (!(alternative < objective - margin)) return Status();
  std::ostringstream why;
  why << "noise scale: the answer's variance factor " << scale.factor() << " (chi2 " << scale.chi2
      << " over redundancy " << scale.redundancy << ", below " << kOverstatedNoise
      << "), and at c2 scaled to " << scaled_c2 << " a cheaper alternative: truncated objective "
      << alternative << " against the answer's " << objective << " (more than " << margin
      << " lower)";
  return Status::uncertain(why.str());
}

}  // namespace hamal::robust
