// MaxMixtureStart: where max-mixture loop closures start (max_mixture_start.h).
#include "backends/robust/max_mixture_start.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <utility>

#include "backends/robust/estimate_consistency.h"
#include "core/error.h"
#include "core/factor_weights.h"
#include "core/stopwatch.h"

namespace hamal::robust {

namespace {

// The nominal component of a loop closure with modes that gives a relative
// pose, else null.
const Factor* nominalOf(const Factor& f) {
  if (!f.hasModes()) return nullptr;
  const Factor* nominal = f.modeComponent(0);
  return nominal && nominal->relativePose() ? nominal : nullptr;
}

bool finite(const Values& values) {
  for (const auto& [key, entry] : values)
    for (int d = 0; d < dimension(entry.type); ++d)
      if (!std::isfinite(entry.data[d])) return false;
  return true;
}

}  // namespace

MaxMixtureStart::MaxMixtureStart(std::function<std::unique_ptr<Backend>()> make,
                                 Predicate is_candidate, GncOptions gnc, double threshold,
                                 double crossover)
    : make_(std::move(make)),
      is_candidate_(std::move(is_candidate)),
      gnc_(gnc),
      threshold_(threshold),
      crossover_(crossover) {
  if (!make_) throw Error("max-mixture start: no back-end factory");
  if (!is_candidate_) throw Error("max-mixture start: no candidate predicate");
  if (!(threshold_ > 0) || !std::isfinite(threshold_) || !(crossover_ > 0) ||
      !std::isfinite(crossover_))
    throw Error("max-mixture start: the threshold and the crossover must be positive");
  inner_ = make_();
  if (!inner_) throw Error("max-mixture start: the factory made no back-end");
  if (gnc_.doubt != GncOptions::Doubt::kOff)
    check_ = std::make_unique<TruncatedObjectiveCheck>(make_, is_candidate_, gnc_);
}

UpdateResult MaxMixtureStart::update(const Step& step) {
  if (check_) check_->add(step);
  UpdateResult r = start(step);
  if (check_ && r.status.ok()) {
    const Stopwatch clock;
    const Status doubt = check_->judge(inner_->estimate());
    r.time.other += clock.seconds();
    if (!doubt.ok()) r.status = Status::uncertain("maxmix: " + doubt.message);
  }
  return r;
}

Status MaxMixtureStart::closingVerdict() {
  if (!check_) return Status();
  const Status doubt = check_->judge(inner_->estimate(), true);
  return doubt.ok() ? doubt : Status::uncertain("maxmix: " + doubt.message);
}

UpdateResult MaxMixtureStart::start(const Step& step) {
  bool mixtures = false;
  for (const FactorPtr& f : step.new_factors) {
    if (OdometryChain::isOdometry(*f) && !is_candidate_(*f)) chain_.add(*f);
    mixtures = mixtures || (is_candidate_(*f) && nominalOf(*f));
  }
  if (!mixtures) return inner_->update(step);
  if (inner_->estimate().empty()) return batchStart(step);
  return inner_->update(guessFromClosures(step));
}

UpdateResult MaxMixtureStart::batchStart(const Step& step) {
  const Stopwatch clock;
  Step nominal = step;
  for (FactorPtr& f : nominal.new_factors)
    if (is_candidate_(*f))
      if (const Factor* n = nominalOf(*f))
        f = FactorPtr(f, const_cast<Factor*>(n));  // shares the mixture's ownership
  Step start = step;
  {
    GraduatedNonConvexity gnc(make_, is_candidate_, gnc_);
    // Only a converged GNC: one that ran out of iterations can end metres
    // off, worse than the odometry it would replace.
    const UpdateResult r = gnc.update(nominal);
    const Values& guess = gnc.estimate();
    bool usable = r.status.ok() && finite(guess);
    for (const auto& [key, entry] : step.new_values) usable = usable && guess.contains(key);
    if (usable) {
      for (const auto& [key, entry] : step.new_values)
        start.new_values.setEntry(key, guess.entry(key));
      started_from_gnc_ = true;
    }
  }
  const double seconds = clock.seconds();
  inner_ = make_();
  UpdateResult r = inner_->update(start);
  r.time.other += seconds;
  return r;
}

Step MaxMixtureStart::guessFromClosures(const Step& step) {
  auto* weights = dynamic_cast<FactorWeights*>(inner_.get());
  if (!weights) return step;
  const Values& estimate = inner_->estimate();
  std::map<Key, std::pair<double, Pose2>> best;  // new pose: (distance, guess)
  for (const FactorPtr& f : step.new_factors) {
    if (!is_candidate_(*f)) continue;
    const Factor* nominal = nominalOf(*f);
    if (!nominal) continue;
    const Factor::RelativePose rel = *nominal->relativePose();
    const bool to_new = step.new_values.contains(rel.to) && !estimate.contains(rel.to) &&
                        estimate.contains(rel.from);
    const bool from_new = step.new_values.contains(rel.from) && !estimate.contains(rel.from) &&
                          estimate.contains(rel.to);
    if (!to_new && !from_new) continue;
    // Only where the odometry's guess puts it on the null hypothesis' side.
    Values at_guess;
    at_guess.insert(rel.from, to_new ? estimate.pose(rel.from) : step.new_values.pose(rel.from));
    at_guess.insert(rel.to, to_new ? step.new_values.pose(rel.to) : estimate.pose(rel.to));
    if (nominal->chi2(at_guess) < crossover_) continue;
    const std::optional<double> d2 = estimateConsistency(*inner_, *weights, chain_, *nominal);
    if (!d2 || !(*d2 < threshold_)) continue;
    const Key key = to_new ? rel.to : rel.from;
    if (std::find(step.fixed.begin(), step.fixed.end(), key) != step.fixed.end()) continue;
    const Pose2 guess = to_new ? estimate.pose(rel.from).compose(rel.measurement)
                               : estimate.pose(rel.to).compose(rel.measurement.inverse());
    const auto it = best.find(key);
    if (it == best.end() || *d2 < it->second.first) best[key] = {*d2, guess};
  }
  if (best.empty()) return step;
  Step out = step;
  for (const auto& [key, guess] : best) out.new_values.set(key, guess.second);
  guessed_from_closures_ += best.size();
  return out;
}

}  // namespace hamal::robust
