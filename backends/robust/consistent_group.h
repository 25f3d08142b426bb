// ConsistentGroup: the largest set of loop closures that agree with each
// other through the odometry, as a start for the alternatives by which the
// doubt rules judge a robust answer (docs/ROBUST_DOUBT_RULES.md, "a cheap
// alternative beats it"). It is PCM's maximum clique (Mangelson et al.,
// ICRA 2018; pairwise_consistency_maximization.h) over every candidate,
// whatever the answer decided for it.
//
// Why. GNC decides each closure on the map it has when the closure comes.
// After a long drift (kitti_02 + 1000: 29 m of heading drift within the
// stated noise) the true closures of a revisit are each rejected alone on
// the drifted map, and the alternatives built from the answer's decisions
// (every rejected closure; those since the last check) hold them among a
// thousand false ones, which bend the least-squares start GNC anneals
// from. The odometry, though, says that the revisit's closures agree with
// one another, and random false closures mostly do not: a group PCM picks
// without looking at the map. Which map the group makes is still judged by
// the truncated objective, as every alternative is, so a false group that
// outnumbers the true one gives a map that must be cheaper to count.
#pragma once

#include <vector>

#include "core/factor.h"

namespace hamal::robust {

// Per candidate, whether it is in a maximum clique of the consistency graph
// the odometry among `inliers` (odometry_chain.h: factors between poses one
// id apart) gives, PCM's default tests (pcm_probability 0.99, one test per
// other closure) and at most `clique_seconds` of exact search (then
// incremental PCM's answer). Candidates that are not relative poses
// (loopClosureOf throws) are outside it. Empty when fewer than two
// candidates can be tested.
std::vector<bool> consistentGroup(const std::vector<FactorPtr>& inliers,
                                  const std::vector<const Factor*>& candidates,
                                  double clique_seconds);

// The exact search's budget the doubt rules give it: a start, not a
// decision, so incremental PCM's group will do where the search is long.
inline constexpr double kGroupCliqueSeconds = 1;

}  // namespace hamal::robust
