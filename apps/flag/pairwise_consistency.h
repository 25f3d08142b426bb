// PairwiseConsistency: which measurements of one landmark agree with each
// other (thesis sec. 4.3.3.1, fig. 4.5). Each measurement, projected
// through its pose's current estimate, is a point; two are consistent when
// their points lie within `threshold`; the consistency graph has an edge
// for each consistent pair.
//
// The thesis' check accepts a measurement that has at least `min_links`
// consistent partners: a person walking past a landmark moves between
// measurements and does not gather them. The option `max_clique` instead
// accepts the largest pairwise-consistent set, the graph's maximum clique
// (Mangelson et al. 2018, PCM), when it has at least min_links + 1 members;
// the clique is found by igraph (backends/robust/maximum_clique.h), not by
// a search of our own.
//
// With `sigmas` > 0 and a covariance per point (ours, for real sensors:
// the points' own uncertainty, the pose's and the detection's), two points
// are consistent when d' (sigmas^2 (C_i + C_j) + threshold^2 I)^-1 d <= 1:
// within the threshold plus `sigmas` standard deviations of their
// difference. Real odometry leaves the poses of a window decimetres apart,
// and a fixed 10 cm drops most right measurements with the wrong ones.
#pragma once
#include <vector>

#include "core/pose2.h"

namespace hamal::flag {

class PairwiseConsistency {
 public:
  PairwiseConsistency(double threshold, int min_links, bool max_clique, double sigmas = 0)
      : threshold_(threshold), min_links_(min_links), max_clique_(max_clique), sigmas_(sigmas) {}
  // accepted[i]: whether measurement i passes the check among `points`.
  // With max_clique and several largest cliques, the one holding the most
  // `preferred` members (those accepted before) wins, then the first.
  // `covariances`: one per point, or empty (the thesis' fixed threshold).
  std::vector<bool> check(const std::vector<Point2>& points,
                          const std::vector<bool>& preferred = {},
                          const std::vector<Eigen::Matrix2d>& covariances = {}) const;
  // The consistency graph's edges (i < j).
  std::vector<std::pair<int, int>> edges(
      const std::vector<Point2>& points,
      const std::vector<Eigen::Matrix2d>& covariances = {}) const;

 private:
  std::vector<bool> linkCount(const std::vector<std::pair<int, int>>& edges, std::size_t n) const;
  std::vector<bool> largestClique(const std::vector<std::pair<int, int>>& edges, std::size_t n,
                                  const std::vector<bool>& preferred) const;
  double threshold_;
  int min_links_;
  bool max_clique_;
  double sigmas_;
};

}  // namespace hamal::flag
