// PairwiseConsistencyMaximization: the loop closures to keep are the
// largest set of mutually consistent ones (Mangelson, Dominic, Eustice,
// Vasudevan, "Pairwise Consistency Maximization for Robust Multi-Robot Map
// Merging", ICRA 2018, eq. 7-9): the consistency graph has a vertex per
// closure and an edge per consistent pair (loop_closure_consistency.h), and
// the accepted set is a maximum clique of it, found by igraph
// (maximum_clique.h).
//
// Cost: n(n-1)/2 cycle tests, each O(1) (odometry_chain.h), then the clique
// search, exponential in the worst case. With pcm_clique_seconds > 0 the
// exact search is given that budget (maximum_clique.h); when it runs out,
// incremental PCM (incremental_pairwise_consistency_maximization.h) decides
// over the closures in their order, and PcmResult::exact is false.
// pcm_clique_seconds = 0 (default): always exact, however long it takes.
//
// Pairs the odometry cannot test. Across an odometry gap or between
// components of the graph no odometry may join two closures' ends
// (loop_closure_consistency.h, cycleThroughOdometry). Such a pair is not in
// conflict: it is an edge of the consistency graph, as two measurements
// whose agreement nothing can test, and it is counted (unchecked_pairs).
// So the accepted set is the union of the largest consistent sets of the
// parts the odometry splits the closures into (each component, each side
// of a gap, the closures across one gap), not the largest part alone; a
// closure no other can be tested against (a lone closure across a gap) is
// accepted untested. Neither kind is dropped or called consistent silently:
// PcmResult::unchecked_pairs counts the pairs, `unchecked` flags the
// closures with one, and hamal_pcm prints both.
//
// The options (pcmOptionSpecs(), shared by the batch and incremental forms
// and the front end, pcm_front_end.h):
//   pcm_probability=0.99  a true closure passes every test PCM puts it to
//                         with this probability: half of 1 - it for the
//                         estimate's test, half for the pairwise tests,
//                         split evenly over them (pcmThreshold; 12.84 and
//                         20.64 with the defaults)
//   pcm_threshold=auto    or this Mahalanobis distance (squared), > 0, for
//                         every test
//   pcm_clique_seconds=0  batch: budget of the exact clique search; 0: none
//   pcm_window=20         incremental: K, the latest closures a new one is
//                         tested against and the clique is recomputed over
//   pcm_sample=20         incremental: S, draws among older closures; the
//                         accepted ones drawn join the test and the clique
//   pcm_seed=1            incremental: seed of those draws
//   pcm_covariance=estimate  the front end (pcm_front_end.h) first tests a
//                         new closure against the back-end's estimate and
//                         its covariance (estimate_consistency.h) where the
//                         back-end gives it; odometry: the odometry chain only
#pragma once

#include <cstdint>
#include <vector>

#include "backends/robust/loop_closure_consistency.h"
#include "backends/robust/maximum_clique.h"
#include "backends/robust/odometry_chain.h"
#include "core/options.h"

namespace hamal::robust {

// Why the probability is per closure, not per test. A closure is accepted
// only in a clique: one failed test against any accepted closure is enough
// to drop it. Incremental PCM tests a new closure against up to pcm_window
// + pcm_sample others, after the estimate's test (pcm_front_end.h); at the
// chi2 quantile at 0.99 per test, a true closure fails one of those 41 with
// probability about 1 - 0.99^41 = 34%, and on hamal_generate's worlds of
// 600-1300 true closures PCM rejected 3-9% of them (right needs at most
// 1%). Splitting the 1% over the tests (Bonferroni) keeps a true closure's
// chance of any failure at most 1%; a false closure random over the map is
// many times beyond either threshold (docs/ROBUST_PCM_MAXMIX_RULES.md, "PCM's tests").
struct PcmOptions {
  double probability = 0.99;
  // Resolved from probability unless given: the pairwise tests' threshold
  // for incremental PCM (pcm_window + pcm_sample tests a closure) and the
  // estimate's test's (one).
  double threshold = 0;
  double estimate_threshold = 0;
  bool threshold_given = false;
  double clique_seconds = 0;
  int window = 20;
  int sample = 20;
  std::uint64_t seed = 1;
  enum class Covariance { kOdometry, kEstimate };
  Covariance covariance = Covariance::kEstimate;
};

// The option names above with their defaults and help.
std::vector<OptionSpec> pcmOptionSpecs();
// Reads them from a resolved Options; throws hamal::Error naming the option
// (pcm_threshold <= 0, pcm_probability outside (0, 1), negative budget,
// window < 1, sample < 0).
PcmOptions pcmOptionsFrom(const Options& options);
// The defaults, thresholds resolved (20.64, 12.84).
PcmOptions defaultPcmOptions();
// The threshold of one test of a stage of `tests` tests: the chi2 quantile
// of 3 dof at 1 - (1 - probability) / (2 tests), or the given one.
double pcmThreshold(const PcmOptions& options, std::size_t tests);

// Edges between every consistent pair (i < j) of `closures`, and between
// every pair the odometry cannot test (above); those are counted in
// `unchecked_pairs` and flagged per closure in `unchecked` when given.
ConsistencyGraph consistencyGraph(const OdometryChain& chain,
                                  const std::vector<LoopClosure>& closures, double threshold,
                                  std::size_t* unchecked_pairs = nullptr,
                                  std::vector<bool>* unchecked = nullptr);

struct PcmResult {
  std::vector<bool> accepted;        // per closure
  std::size_t consistent_pairs = 0;  // tested and consistent
  // Pairs no odometry joins (edges, untested) and the closures in one.
  std::size_t unchecked_pairs = 0;
  std::vector<bool> unchecked;
  // The accepted set is a maximum clique; false: the budget ran out and
  // incremental PCM decided.
  bool exact = true;
  // The pairwise tests' threshold of the consistency graph: one test per
  // other closure, so above options.threshold, which the fallback uses.
  double threshold = 0;
  double consistency_seconds = 0, clique_seconds = 0, fallback_seconds = 0;
};

// Batch PCM: the consistency graph of all closures and a maximum clique.
// `closures` in their arrival order (the fallback takes them in it).
// `preferred` breaks ties between maximum cliques (maximum_clique.h).
PcmResult pairwiseConsistencyMaximization(const OdometryChain& chain,
                                          const std::vector<LoopClosure>& closures,
                                          const PcmOptions& options,
                                          const std::vector<bool>& preferred = {});

}  // namespace hamal::robust
