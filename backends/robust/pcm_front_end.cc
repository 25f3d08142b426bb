// PcmFrontEnd: PCM in front of a back-end (pcm_front_end.h).
#include "backends/robust/pcm_front_end.h"

#include <optional>

#include "backends/robust/estimate_consistency.h"
#include "backends/robust/loop_closure_consistency.h"
#include "core/error.h"
#include "core/stopwatch.h"

namespace hamal::robust {

PcmFrontEnd::PcmFrontEnd(std::unique_ptr<Backend> inner, Candidate is_candidate,
                         const PcmOptions& options)
    : inner_(std::move(inner)),
      is_candidate_(std::move(is_candidate)),
      options_(options),
      pcm_(options) {
  if (!inner_) throw Error("pcm: no inner back-end");
  if (!is_candidate_) throw Error("pcm: no candidate predicate");
}

UpdateResult PcmFrontEnd::update(const Step& step) {
  const Stopwatch t0;
  checkStep(step, inner_->estimate(), "pcm");
  if (check_) check_->add(step);
  Step pass;
  pass.index = step.index;
  pass.new_values = step.new_values;
  pass.fixed = step.fixed;
  std::vector<FactorPtr> arrived;
  std::vector<LoopClosure> closures;
  for (const FactorPtr& f : step.new_factors) {
    if (is_candidate_(*f)) {
      closures.push_back(loopClosureOf(*f));  // throws before anything is recorded
      arrived.push_back(f);
    } else {
      pass.new_factors.push_back(f);
    }
  }
  for (const FactorPtr& f : pass.new_factors)
    if (OdometryChain::isOdometry(*f)) chain_.add(*f);
  // The estimate's test needs a back-end that holds poses and gives their
  // covariance; the first batch (nothing held yet) and other back-ends use
  // the odometry's alone.
  Backend* held = estimateSource();
  auto* weights = options_.covariance == PcmOptions::Covariance::kEstimate && held
                      ? dynamic_cast<FactorWeights*>(held)
                      : nullptr;
  if (weights && held->estimate().empty()) weights = nullptr;
  if (!closures.empty()) {
    if (pcm_.size() == 0 && !weights) {
      pcm_.addBatch(chain_, closures);
      exact_ = exact_ && pcm_.last().exact;
    } else {
      for (std::size_t k = 0; k < closures.size(); ++k) {
        const LoopClosure& c = closures[k];
        const std::optional<double> d2 =
            weights ? estimateConsistency(*held, *weights, chain_, *arrived[k]) : std::nullopt;
        if (d2 && !(*d2 < options_.estimate_threshold)) {
          pcm_.addRejected(chain_, c);
          ++estimate_rejected_;
          continue;
        }
        if (pcm_.size() == 0)
          pcm_.addBatch(chain_, {c});
        else
          pcm_.add(chain_, c);
        exact_ = exact_ && pcm_.last().exact;
      }
    }
    candidates_.insert(candidates_.end(), arrived.begin(), arrived.end());
    passed_.resize(candidates_.size(), false);
  }
  const std::vector<bool>& accepted = pcm_.accepted();
  for (std::size_t i = 0; i < candidates_.size(); ++i)
    if (accepted[i] && !passed_[i]) {
      pass.new_factors.push_back(candidates_[i]);
      passed_[i] = true;
    }
  const double pcm_seconds = t0.seconds();
  UpdateResult r = inner_->update(pass);
  r.time.other += pcm_seconds;
  if (check_ && r.status.ok()) {
    const Stopwatch clock;
    const Status doubt = check_->judge(inner_->estimate());
    r.time.other += clock.seconds();
    if (!doubt.ok()) r.status = Status::uncertain("pcm: " + doubt.message);
  }
  return r;
}

void PcmFrontEnd::setAnswerCheck(std::unique_ptr<TruncatedObjectiveCheck> check) {
  check_ = std::move(check);
  if (check_) check_->weighNearMisses(dynamic_cast<FactorWeights*>(inner_.get()));
}

Status PcmFrontEnd::closingVerdict() {
  // The inner back-end's own (GNC's under pcm+gnc) first: it names the
  // closures PCM passed it.
  if (auto* inner = dynamic_cast<ClosingVerdict*>(inner_.get())) {
    const Status s = inner->closingVerdict();
    if (!s.ok()) return s;
  }
  if (!check_) return Status();
  const Status doubt = check_->judge(inner_->estimate(), true);
  return doubt.ok() ? doubt : Status::uncertain("pcm: " + doubt.message);
}

std::vector<std::pair<const Factor*, bool>> PcmFrontEnd::decisions() const {
  std::vector<std::pair<const Factor*, bool>> out;
  out.reserve(candidates_.size());
  for (std::size_t i = 0; i < candidates_.size(); ++i)
    out.emplace_back(candidates_[i].get(), pcm_.accepted()[i]);
  return out;
}

std::size_t PcmFrontEnd::keptRejected() const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < candidates_.size(); ++i)
    if (passed_[i] && !pcm_.accepted()[i]) ++n;
  return n;
}

}  // namespace hamal::robust
