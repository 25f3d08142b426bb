// SparseScanMatching: Schiotka et al. 2017's greedy scan selection (thesis
// sec. 5.4.2, eq. 5.7-5.10), the state-of-the-art baseline.
//
// The log-likelihood of the mapping run's scans given the selected scans:
//   log p(z_1:M | x_1:M, S) = sum_i sum_{q in z_i} log N(d_iq; 0, sigma)
// where the scan of pose i is explained by the selected node nearest to x_i
// (the Dirac p(s | x_i) of eq. 5.8) and d_iq is the distance from point q
// (in the global frame) to the nearest point of that node's scan (eq. 5.9),
// truncated at `max_distance` so that a point the node cannot see costs a
// bounded amount (an outlier floor, as scan-matching likelihoods use).
// The terms D[i][s] are computed once for every (pose, node) pair; the greedy
// selection (eq. 5.10) then adds, C times, the node that raises the
// likelihood most.
#pragma once

#include "apps/moss/selection.h"
#include "apps/moss/trials.h"

namespace hamal::moss {

struct SsmConfig {
  double sigma = 0.05;        // m
  double max_distance = 0.5;  // m
};

class SparseScanMatching {
 public:
  SparseScanMatching(const PriorMap& map, SsmConfig config = {});
  // Greedy selection of C nodes; with `order` the order they were added in.
  Selection select(int c, std::vector<int>* order = nullptr) const;
  // log p(z_1:M | x_1:M, S_alpha), eq. 5.7.
  double logLikelihood(const Selection& a) const;

 private:
  const PriorMap& map_;
  SsmConfig config_;
  std::vector<std::vector<double>> d_;  // d_[i][s]
};

}  // namespace hamal::moss
