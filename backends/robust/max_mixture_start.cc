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
#include "core/multi_modal.h"
#include "core/relative_pose_measurement.h"
#include "core/stopwatch.h"

namespace hamal::robust {

namespace {

// The nominal component of a loop closure with modes that gives a relative
// pose, else null.
const Factor* nominalOf(const Factor& f) {
  const MultiModal* moded = asMultiModal(f);
  const Factor* nominal = moded ? moded->modeComponent(0) : nullptr;
  return nominal && relativePoseOf(*nominal) ? nominal : nullptr;
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
                                 double crossover, Initializer initialize)
    : make_(std::move(make)),
      initialize_(std::move(initialize)),
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
  const std::size_t first_new = nominals_.size();
  for (const FactorPtr& f : step.new_factors) {
    factors_.push_back(f);
    const Factor* n = is_candidate_(*f) ? nominalOf(*f) : nullptr;
    if (!n) {
      inliers_.push_back(f);
      continue;
    }
    index_[f.get()] = nominals_.size();
    nominals_.push_back(FactorPtr(f, const_cast<Factor*>(n)));
    on_.push_back(false);
    agreed_.push_back(false);
  }
  fixed_.insert(fixed_.end(), step.fixed.begin(), step.fixed.end());
  UpdateResult r = start(step);
  if (r.status.ok() && nominals_.size() > first_new) reclose(first_new, &r);
  if (check_ && r.status.ok()) {
    const Stopwatch clock;
    Status doubt = check_->judge(inner_->estimate());
    // Adopt: the mixtures start again from the cheaper map, which is judged again.
    if (!doubt.ok())
      if (const std::optional<Values> cheaper = check_->takeCheaperMap())
        if (restart(*cheaper, &r)) {
          ++adopted_;
          r.reason += "; maxmix: started again from a cheaper map";
          for (std::size_t k = 0; k < nominals_.size(); ++k) on_[k] = on(k, inner_->estimate());
          doubt = check_->judgeAgain(inner_->estimate());
        }
    r.time.other += clock.seconds();
    if (!doubt.ok() && r.status.ok()) r.status = Status::uncertain("maxmix: " + doubt.message);
  }
  return r;
}

bool MaxMixtureStart::on(std::size_t k, const Values& values) const {
  try {
    return nominals_[k]->chi2(values) < crossover_;
  } catch (const Error&) {
    return false;
  }
}

bool MaxMixtureStart::restart(const Values& from, UpdateResult* r) {
  const Stopwatch clock;
  Step all;
  all.new_factors = factors_;
  all.fixed = fixed_;
  for (const auto& [key, entry] : inner_->estimate()) {
    if (!from.contains(key)) return false;
    all.new_values.setEntry(key, from.entry(key));
  }
  // A back-end that stops at its iteration limit (mixtures switching on the
  // way) goes on from where it stopped, as a fresh one.
  std::unique_ptr<Backend> fresh;
  UpdateResult s;
  for (int round = 0; round < kRestartRounds; ++round) {
    if (round > 0) all.new_values = fresh->estimate();
    fresh = make_();
    s = fresh->update(all);
    r->iterations += s.iterations;
    if (s.status.code != Status::kNotConverged || !finite(fresh->estimate())) break;
  }
  r->time.other += clock.seconds();
  const bool usable = s.status.ok() || s.status.code == Status::kNotConverged;
  if (!usable || !finite(fresh->estimate())) return false;
  inner_ = std::move(fresh);
  if (!s.status.ok()) r->status = s.status;
  return true;
}

bool MaxMixtureStart::leastSquares(const Step& problem, Values* at) const {
  // Fresh back-ends, each from the last one's estimate, until the cost stops
  // falling: a batch update of an incremental back-end takes one
  // Gauss-Newton step, and one that stops at its iteration limit is still a
  // warm start.
  const auto cost = [&problem](const Values& v) {
    double c = 0;
    for (const FactorPtr& f : problem.new_factors) c += f->chi2(v);
    return c;
  };
  Step step = problem;
  double before = cost(step.new_values);
  for (int round = 0; round < kLeastSquaresRounds; ++round) {
    const std::unique_ptr<Backend> solver = make_();
    const UpdateResult u = solver->update(step);
    if (u.status.code == Status::kNumericalFailure || !finite(solver->estimate())) return false;
    const double after = cost(solver->estimate());
    if (!(after <= before)) break;  // no better: keep the last estimate
    step.new_values = solver->estimate();
    if (u.status.ok() && before - after <= kLeastSquaresTolerance * before) break;
    before = after;
  }
  *at = step.new_values;
  return true;
}

void MaxMixtureStart::reclose(std::size_t first_new, UpdateResult* r) {
  const Values& estimate = inner_->estimate();
  // Those that should hold: on before the update, or new and agreeing with the map.
  std::vector<bool> hold(nominals_.size());
  bool lost = false;
  for (std::size_t k = 0; k < nominals_.size(); ++k) {
    const bool now = on(k, estimate);
    hold[k] = k < first_new ? on_[k] : agreed_[k];
    lost = lost || (hold[k] && !now);
    hold[k] = hold[k] || now;
  }
  if (lost) {
    const Stopwatch clock;
    Step ls;  // least squares with every closure that should hold
    ls.new_values = estimate;
    ls.fixed = fixed_;
    ls.new_factors = inliers_;
    for (std::size_t k = 0; k < nominals_.size(); ++k)
      if (hold[k]) ls.new_factors.push_back(nominals_[k]);
    bool closes = false;
    Values at;
    try {
      closes = leastSquares(ls, &at);
      for (std::size_t k = 0; closes && k < nominals_.size(); ++k) closes = !hold[k] || on(k, at);
    } catch (const Error&) {
      closes = false;
    }
    r->time.other += clock.seconds();
    if (closes && restart(at, r)) {
      ++reclosed_;
      r->reason += "; maxmix: closed again from least squares";
    }
  }
  for (std::size_t k = 0; k < nominals_.size(); ++k) on_[k] = on(k, inner_->estimate());
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
  // Least squares first: where it leaves every closure within its c2, GNC
  // would anneal nothing and answer it, if its own solves converge.
  Values ls;
  bool fits = false;
  if (initialize_) {
    Step from = nominal;
    try {
      from.new_values = initialize_(nominal);
      fits = leastSquares(from, &ls);
    } catch (const Error&) {
      fits = false;
    }
  }
  for (const FactorPtr& f : nominal.new_factors)
    fits = fits && (!is_candidate_(*f) || f->chi2(ls) <= gnc_.threshold(f->residualDim()));
  for (const auto& [key, entry] : step.new_values) fits = fits && ls.contains(key);
  if (fits) {
    for (const auto& [key, entry] : step.new_values) start.new_values.setEntry(key, ls.entry(key));
    started_from_least_squares_ = true;
  } else {
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
    const RelativePose rel = *relativePoseOf(*nominal);
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
    const auto k = index_.find(f.get());
    if (k != index_.end()) agreed_[k->second] = true;
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
