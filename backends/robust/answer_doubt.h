// AnswerDoubt: the rules by which a robust back-end that converged still
// does not call its answer ok (backends/robust/README.md, "When the answer
// is in doubt"). Truncated
// least squares (TLS) is not convex: GNC, like every local method, can end
// in a local minimum tens of metres from the map the data support, with
// nothing in its own convergence test to show it. Each rule below looks at
// something the back-end can check cheaply and, when it fires, gives a
// Status kUncertain naming the rule and its figures; a rule that does not
// fire gives an ok Status.
//
// Every constant is the same for every graph, and its reason is written
// beside it: a per-dataset threshold would make the status say what the
// tuning set wanted, not what the run did.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "backends/robust/near_misses.h"
#include "core/backend.h"
#include "core/factor.h"
#include "core/values.h"

namespace hamal::robust {

// Rule "most closures rejected": more than this share of the candidates
// rejected. Past one half the rejected closures outnumber the accepted ones
// the map rests on, so the data alone cannot say which side is the outliers:
// a TLS minimum that keeps the larger side is as plausible, and the run
// picked the smaller. A share needs closures to be one: below
// kMinShareCandidates one decision moves it by more than ten points, so it
// tells which closure came first (an incremental run's first closure,
// rejected, is all of them) rather than what the data hold.
//
// Where the back-end can say how clearly the map refutes the rejected
// closures (near_misses.h: `refuted`), the share is doubt only when the
// false closures they predict among the accepted are at least
// kMaxExpectedFalse, or when an accepted closure holds a direction of the
// map alone: a map that refutes every rejected closure by a wide margin,
// and rests on no closure nothing else tests, would have refuted a false
// one among the accepted too. Half a closure: the estimate is good to a
// factor of a few, and at 0.5 one false closure among the accepted has a
// chance of about 40% (Poisson); the rejected closures of right answers on
// the tuning worlds (seed 11, sparse + 100) predict 0.02-0.10.
inline constexpr double kMaxRejectedShare = 0.5;
inline constexpr std::size_t kMinShareCandidates = 10;
inline constexpr double kMaxExpectedFalse = 0.5;
Status rejectedShareDoubt(std::size_t rejected, std::size_t candidates,
                          std::optional<Refutation> refuted = std::nullopt);

// Rule "decisions flip": a candidate whose accept/reject decision changed
// more than this many times across updates. One change is new evidence (a
// later closure shows an early one false), a second the map moving back
// once it is relinearised; a third means the evidence keeps reversing, and
// whichever way the last update left it is an accident of where the run
// stopped. `flips` holds each candidate's count.
inline constexpr int kMaxFlips = 2;
Status flipDoubt(const std::vector<int>& flips);

// The truncated least-squares objective GNC-TLS minimises: every known
// inlier's chi2 in full, each candidate's capped at its c2 (the cost of
// rejecting it). apps/robust's truncatedObjective grades a run by the same
// sum. Throws hamal::Error when a factor does not evaluate at `values`.
double truncatedObjective(const std::vector<FactorPtr>& inliers,
                          const std::vector<const Factor*>& candidates,
                          const std::vector<double>& c2, const Values& values);

// Rule "a cheap alternative beats it": the objective at an alternative the
// back-end checked (docs/ROBUST_DOUBT_RULES.md says which) below the
// answer's by more than `margin`. The margin is the smallest c2 of the
// candidates: a difference under one closure's rejection cost is within
// what a single decision swings and within the alternative's own
// convergence tolerance, so it is no evidence that the answer is a worse
// minimum.
Status alternativeDoubt(double objective, double alternative, double margin);

}  // namespace hamal::robust
