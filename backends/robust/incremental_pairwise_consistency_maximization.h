// IncrementalPairwiseConsistencyMaximization: PCM (Mangelson et al., ICRA
// 2018; pairwise_consistency_maximization.h) under the thesis protocol,
// where loop closures arrive one step at a time and each step must cost a
// bounded amount whatever the number of closures before it.
//
// When closure c arrives (the n-th), with K = pcm_window and S = pcm_sample:
//   V = the last K closures (accepted or not)
//     + the accepted ones among S uniform draws from the older closures
//     + c,  |V| <= K + S + 1.
// Every pair of V is tested (a pair's result is kept, so a pair is tested
// once; at most |V|(|V|-1)/2 tests in a step, K + S of them new pairs of c
// when V was tested before). If c is consistent with every accepted member
// of V, the accepted members plus c are a maximum clique of V whenever the
// accepted members were one of V without c (a larger clique would be one of
// the old graph plus c), so c is accepted with no search. Otherwise a
// maximum clique of V's consistency graph is searched (igraph, at most
// K + S + 1 vertices, the accepted members preferred on ties): its members
// are accepted, the other members of V rejected. Decisions outside V stay.
//
// So a step costs at most (K + S + 1)(K + S)/2 cycle tests, each O(1), and
// one exact clique search on at most K + S + 1 vertices; last() reports
// both counts. The accepted set
// is a maximum clique within each step's V, not of the whole graph: closures
// that never share a V are not compared. A closure accepted earlier may be
// rejected later (and a rejected one within the window accepted).
//
// A pair the odometry cannot test (an odometry gap or another component
// between their ends) counts as consistent, as in batch PCM
// (pairwise_consistency_maximization.h, "Pairs the odometry cannot test");
// uncheckedPairs() counts them.
#pragma once

#include <cstdint>
#include <random>
#include <unordered_map>
#include <vector>

#include "backends/robust/loop_closure_consistency.h"
#include "backends/robust/odometry_chain.h"
#include "backends/robust/pairwise_consistency_maximization.h"

namespace hamal::robust {

class IncrementalPairwiseConsistencyMaximization {
 public:
  explicit IncrementalPairwiseConsistencyMaximization(const PcmOptions& options);

  // Adds `closure` (the odometry so far in `chain`; its ends need not be
  // joined) and updates the decisions; returns its index.
  std::size_t add(const OdometryChain& chain, const LoopClosure& closure);
  // Adds `closure` rejected for good: it never enters a later step's V (a
  // closure the estimate refutes, estimate_consistency.h); returns its index.
  std::size_t addRejected(const OdometryChain& chain, const LoopClosure& closure);
  // Adds closures that come together (before any other): batch PCM over them.
  void addBatch(const OdometryChain& chain, const std::vector<LoopClosure>& closures);

  const std::vector<bool>& accepted() const { return accepted_; }
  std::size_t size() const { return closures_.size(); }
  // Pairs tested so far that no odometry joins (counted as consistent).
  std::size_t uncheckedPairs() const { return unchecked_pairs_; }

  struct StepCost {
    std::size_t vertices = 0;  // |V|
    std::size_t tests = 0;     // cycle tests made in the step
    bool searched = false;     // a clique search ran
    bool exact = true;         // that search was exact
  };
  const StepCost& last() const { return last_; }

 private:
  bool consistent(const OdometryChain& chain, std::size_t a, std::size_t b);

  PcmOptions options_;
  std::mt19937_64 random_;
  std::vector<LoopClosure> closures_;
  std::vector<bool> accepted_;
  std::vector<bool> excluded_;                      // added by addRejected
  std::unordered_map<std::uint64_t, bool> tested_;  // key: a * 2^32 + b, a < b
  StepCost last_;
  std::size_t unchecked_pairs_ = 0;
};

}  // namespace hamal::robust
