// TruncatedObjectiveCheck (truncated_objective_check.h): the "cheap
// alternative" doubt rule for PCM and max-mixtures.
#include "backends/robust/truncated_objective_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include "backends/robust/answer_doubt.h"
#include "backends/robust/near_misses.h"
#include "backends/robust/noise_scale.h"
#include "backends/robust/odometry_chain.h"
#include "core/error.h"
#include "core/multi_modal.h"
#include "core/relative_pose_measurement.h"

namespace hamal::robust {

TruncatedObjectiveCheck::TruncatedObjectiveCheck(std::function<std::unique_ptr<Backend>()> make,
                                                 Predicate is_candidate, GncOptions gnc,
                                                 Starts starts)
    : make_(std::move(make)), is_candidate_(std::move(is_candidate)), gnc_(gnc), starts_(starts) {
  if (!make_ || !is_candidate_)
    throw Error("truncated objective check: needs a back-end maker and a candidate predicate");
}

void TruncatedObjectiveCheck::add(const Step& step) {
  for (const FactorPtr& f : step.new_factors) {
    if (!is_candidate_(*f)) {
      inliers_.push_back(f);
      continue;
    }
    // A max-mixture is judged by its nominal component, the closure it
    // stands for; the alias keeps the mixture (and so the component) alive.
    FactorPtr nominal = f;
    if (const MultiModal* moded = asMultiModal(*f))
      if (const Factor* c = moded->modeComponent(0)) nominal = FactorPtr(f, const_cast<Factor*>(c));
    candidates_.push_back(nominal);
    c2_.push_back(gnc_.threshold(nominal->residualDim()));
  }
  fixed_.insert(fixed_.end(), step.fixed.begin(), step.fixed.end());
  // The odometry's own start: a new pose whose odometry link comes from a
  // pose already started is that pose composed with the link; any other
  // new variable (the first pose, one after an odometry gap, a landmark)
  // starts at the step's guess. New values come in key order, so a batch
  // chains along the odometry as steps do.
  std::map<Key, RelativePose> link_to;
  for (const FactorPtr& f : step.new_factors)
    if (OdometryChain::isOdometry(*f))
      if (const auto rel = relativePoseOf(*f)) link_to.emplace(rel->to, *rel);
  for (const auto& [key, entry] : step.new_values) {
    if (guesses_.contains(key)) continue;
    const auto link = link_to.find(key);
    if (link != link_to.end() && guesses_.contains(link->second.from))
      guesses_.insert(key, guesses_.pose(link->second.from).compose(link->second.measurement));
    else
      guesses_.setEntry(key, entry);
  }
}

double TruncatedObjectiveCheck::objective(const Values& values,
                                          const std::vector<double>& c2) const {
  std::vector<const Factor*> all;
  all.reserve(candidates_.size());
  for (const FactorPtr& c : candidates_) all.push_back(c.get());
  return truncatedObjective(inliers_, all, c2, values);
}

bool TruncatedObjectiveCheck::alternative(const Values& start, const std::vector<bool>& use,
                                          const GncOptions& gnc, const std::vector<double>& c2,
                                          double* objective_out, Values* at_out) const {
  Step batch;
  batch.new_values = start;
  batch.fixed = fixed_;
  batch.new_factors = inliers_;
  for (std::size_t i = 0; i < candidates_.size(); ++i)
    if (use[i]) batch.new_factors.push_back(candidates_[i]);
  try {
    std::vector<double> fits;
    const std::optional<Values> at =
        polishedGncSolve(make_, is_candidate_, gnc, batch, inliers_, candidates_, c2, &fits);
    if (!at) return false;
    *objective_out = objective(*at, c2);
    *at_out = *at;
  } catch (const Error&) {
    return false;  // an alternative that does not evaluate is no evidence either way
  }
  return true;
}

double TruncatedObjectiveCheck::bestAlternative(const Values& answer,
                                                const std::vector<bool>& beyond,
                                                Values* best) const {
  // Three starts: from the answer, every closure, and the closures it left
  // beyond c2 on their own (consistent as a group, they are the map the
  // answer gave up, as GNC's own rule tries); and every closure from the
  // odometry's own start, which no decision of the answer has shaped (the
  // steps' guesses have: the protocol guesses a pose from the estimate).
  const std::vector<bool> every(candidates_.size(), true);
  double theirs = std::numeric_limits<double>::infinity();
  const auto consider = [&](const Values& start, const std::vector<bool>& use) {
    double one = 0;
    Values at;
    if (alternative(start, use, gnc_, c2_, &one, &at) && one < theirs) {
      theirs = one;
      *best = std::move(at);
    }
  };
  if (starts_.answer_every) consider(answer, every);
  if (starts_.answer_rejected) consider(answer, beyond);
  if (starts_.odometry) consider(guesses_, every);
  return theirs;
}

Status TruncatedObjectiveCheck::judge(const Values& answer, bool now) {
  const auto grown = [&](std::size_t since, double growth) {
    return !candidates_.empty() &&
           (since == 0 || static_cast<double>(candidates_.size()) >= growth * since ||
            (now && candidates_.size() > since));
  };
  const bool share_due = grown(shared_candidates_, kShareGrowth);
  const bool alternative_due = grown(checked_candidates_, kRecheckGrowth);
  const bool noise_due = now && candidates_.size() > noise_candidates_;
  if (!share_due && !alternative_due && !noise_due) return verdict();
  double mine = 0;
  std::vector<bool> beyond(candidates_.size());
  std::size_t rejected = 0;
  try {
    mine = objective(answer, c2_);
    for (std::size_t i = 0; i < candidates_.size(); ++i) {
      beyond[i] = candidates_[i]->chi2(answer) > c2_[i];
      rejected += beyond[i];
    }
  } catch (const Error&) {
    return verdict();  // the answer does not evaluate: the back-end's own status says so
  }
  // The end-of-run rules read the answer's variance factor: made once.
  const std::optional<NoiseScale> overstated = now ? overstatedNoise(answer) : std::nullopt;
  if (share_due || alternative_due) {
    shared_candidates_ = candidates_.size();
    share_ = rejectedShareDoubt(rejected, candidates_.size());
    if (!share_.ok() && near_misses_) {
      std::vector<const Factor*> out, in;
      std::vector<double> c2;
      for (std::size_t i = 0; i < candidates_.size(); ++i) {
        if (!beyond[i]) {
          in.push_back(candidates_[i].get());
          continue;
        }
        out.push_back(candidates_[i].get());
        c2.push_back(c2_[i]);
      }
      share_ = rejectedShareDoubt(rejected, candidates_.size(),
                                  refutation(*near_misses_, out, c2, in, answer));
    }
  }
  if (alternative_due) {
    checked_candidates_ = candidates_.size();
    alternative_ = Status();
    cheaper_.reset();
    if (rejected > 0) {  // else the answer is its own alternative
      ++checks_;
      Values best;
      const double theirs = bestAlternative(answer, beyond, &best);
      if (std::isfinite(theirs)) {
        const double margin = *std::min_element(c2_.begin(), c2_.end());
        alternative_ = alternativeDoubt(mine, theirs, margin);
        if (!alternative_.ok() && judge_at_noise_scale_ && overstated &&
            preferredAtNoiseScale(answer, best, margin, *overstated))
          alternative_ = Status();
        if (!alternative_.ok()) cheaper_ = std::move(best);
      }
    }
  }
  // The noise scale's rule only where the plain one found nothing: its
  // verdict would add a reason, not change the status.
  if (noise_due) {
    noise_candidates_ = candidates_.size();
    noise_cheaper_.reset();
    noise_ = alternative_.ok() && overstated ? noiseScale(answer, *overstated) : Status();
  }
  return verdict();
}

std::optional<NoiseScale> TruncatedObjectiveCheck::overstatedNoise(const Values& answer) const {
  // One c2 for every closure (the scaled one is GNC's inlier_threshold).
  if (std::find_if(c2_.begin(), c2_.end(), [&](double c) { return c != c2_.front(); }) != c2_.end())
    return std::nullopt;
  try {
    const NoiseScale scale = aPosterioriVarianceFactor(inliers_, candidates_, c2_, fixed_, answer);
    if (noiseOverstated(scale)) return scale;
  } catch (const Error&) {
  }
  return std::nullopt;
}

bool TruncatedObjectiveCheck::preferredAtNoiseScale(const Values& answer, const Values& other,
                                                    double margin, const NoiseScale& scale) const {
  const std::vector<double> c2(c2_.size(), c2_.front() * scale.factor());
  try {
    return !(objective(other, c2) < objective(answer, c2) - margin);
  } catch (const Error&) {
    return false;
  }
}

Status TruncatedObjectiveCheck::noiseScale(const Values& answer, const NoiseScale& scale) {
  GncOptions gnc = gnc_;
  gnc.inlier_threshold = c2_.front() * scale.factor();
  const std::vector<double> c2(c2_.size(), gnc.inlier_threshold);
  double mine = 0;
  std::size_t rejected = 0;
  try {
    mine = objective(answer, c2);
    for (std::size_t i = 0; i < candidates_.size(); ++i)
      rejected += candidates_[i]->chi2(answer) > c2[i];
  } catch (const Error&) {
    return Status();
  }
  if (rejected == 0) return Status();  // the answer is its own alternative
  // One start: GNC-TLS from the answer over every closure. On the tuning
  // set it found the cheaper map wherever the rule fired; the other starts
  // changed no verdict there and cost as much again.
  double theirs = 0;
  Values at;
  if (!alternative(answer, std::vector<bool>(candidates_.size(), true), gnc, c2, &theirs, &at))
    return Status();
  Status doubt = noiseScaleDoubt(scale, gnc.inlier_threshold, mine, theirs, c2_.front());
  if (!doubt.ok()) noise_cheaper_ = std::move(at);
  return doubt;
}

std::optional<Values> TruncatedObjectiveCheck::takeCheaperMap() {
  std::optional<Values> out = std::move(cheaper_);
  cheaper_.reset();
  return out;
}

std::optional<Values> TruncatedObjectiveCheck::takeNoiseScaleMap() {
  std::optional<Values> out = std::move(noise_cheaper_);
  noise_cheaper_.reset();
  return out;
}

Status TruncatedObjectiveCheck::judgeAgain(const Values& answer, bool now) {
  checked_candidates_ = 0;
  shared_candidates_ = 0;
  if (now) noise_candidates_ = 0;
  return judge(answer, now);
}

Status TruncatedObjectiveCheck::verdict() const {
  std::string why;
  for (const Status* s : {&alternative_, &share_, &noise_})
    if (!s->ok()) why += (why.empty() ? "" : "; ") + s->message;
  return why.empty() ? Status() : Status::uncertain(why);
}

}  // namespace hamal::robust
