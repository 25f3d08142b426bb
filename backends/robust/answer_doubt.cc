// AnswerDoubt: see answer_doubt.h.
#include "backends/robust/answer_doubt.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace hamal::robust {

Status rejectedShareDoubt(std::size_t rejected, std::size_t candidates,
                          std::optional<Refutation> refuted) {
  if (candidates < kMinShareCandidates ||
      static_cast<double>(rejected) <= kMaxRejectedShare * candidates)
    return Status();
  // Not a number is no evidence that the map refutes them.
  if (refuted && refuted->expected_false < kMaxExpectedFalse && refuted->alone == 0)
    return Status();
  std::ostringstream why;
  why << "most loop closures rejected: " << rejected << " of " << candidates << " (more than "
      << kMaxRejectedShare * 100 << "%)";
  if (refuted) {
    why << ", and the map does not refute them:";
    if (!(refuted->expected_false < kMaxExpectedFalse))
      why << " " << refuted->expected_false
          << " false closures expected among the accepted (at least " << kMaxExpectedFalse << ")"
          << (refuted->alone ? ";" : "");
    if (refuted->alone)
      why << " " << refuted->alone << " accepted closure(s) hold a direction of the map alone";
  }
  return Status::uncertain(why.str());
}

Status flipDoubt(const std::vector<int>& flips) {
  std::size_t over = 0;
  int most = 0;
  for (int f : flips) {
    over += f > kMaxFlips;
    most = std::max(most, f);
  }
  if (over == 0) return Status();
  std::ostringstream why;
  why << "decisions flip: " << over << " loop closure(s) changed between accepted and rejected "
      << "more than " << kMaxFlips << " times (at most " << most << ")";
  return Status::uncertain(why.str());
}

double truncatedObjective(const std::vector<FactorPtr>& inliers,
                          const std::vector<const Factor*>& candidates,
                          const std::vector<double>& c2, const Values& values) {
  if (c2.size() != candidates.size())
    throw Error("truncatedObjective: " + std::to_string(candidates.size()) + " candidates but " +
                std::to_string(c2.size()) + " thresholds");
  double total = 0;
  for (const FactorPtr& f : inliers) total += f->chi2(values);
  for (std::size_t i = 0; i < candidates.size(); ++i)
    total += std::min(candidates[i]->chi2(values), c2[i]);
  if (!std::isfinite(total)) throw Error("truncatedObjective: not finite at these values");
  return total;
}

Status alternativeDoubt(double objective, double alternative, double margin) {
  if (!(alternative < objective - margin)) return Status();
  std::ostringstream why;
  why << "a cheaper alternative: truncated objective " << alternative << " against the answer's "
      << objective << " (more than " << margin << " lower)";
  return Status::uncertain(why.str());
}

}  // namespace hamal::robust
