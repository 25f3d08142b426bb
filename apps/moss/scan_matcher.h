// ScanMatcher: point-to-line ICP (Censi 2008, "An ICP variant using a
// point-to-line metric") between a live scan and a prior-map node's scan,
// the front end whose matches become L2G factors (thesis sec. 5.3.2).
//
// The map scan is indexed once in a k-d tree (nanoflann, libnanoflann-dev)
// with a normal per point from its neighbours' line fit. Each Gauss-Newton
// iteration pairs every live point with its nearest map point within a gate
// and minimises the squared distances to the map points' lines. Like any
// local matcher it converges to the nearest local minimum of the guess: in a
// corridor that is a shift along the hallway, which is the aliasing MOSS is
// to learn to avoid.
//
// Information: the Gauss-Newton Hessian J^T J / sigma^2 at the solution (the
// usual approximation; Censi's closed form adds the sensitivity to the
// correspondences), with sigma inflated from the range noise to account for
// correlated errors, and its eigenvalues floored so that a degenerate match
// (a featureless hallway) is weak along the degenerate direction but the
// matrix stays positive definite.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "apps/moss/laser.h"
#include "core/pose2.h"

namespace hamal::moss {

struct ScanMatcherConfig {
  int max_iterations = 30;
  double gate_coarse = 0.5;  // m, pairing distance in the first iterations
  double gate_fine = 0.2;    // m, afterwards
  int coarse_iterations = 8;
  int min_pairs = 30;
  double min_inlier_fraction = 0.3;  // of the live points, at the fine gate
  double max_rms = 0.06;             // m, point-to-line, to accept a match
  double sigma = 0.05;               // m, per point-to-line residual
  double min_eigenvalue = 1.0;       // floor of the information's eigenvalues
  // kHessian: J^T J / sigma^2 (above). kCensi: the inverse of Censi's
  // closed-form covariance (icp_covariance.h) with the laser's range noise.
  enum class Information { kHessian, kCensi } information = Information::kHessian;
  double sigma_range = 0.02;  // m, sigma_d, for kCensi
};

// "hessian" or "censi" (anything else is an Error naming the choices).
ScanMatcherConfig::Information parseInformation(const std::string& name);
const char* toString(ScanMatcherConfig::Information information);

struct ScanMatch {
  bool ok = false;  // converged and passed the acceptance tests
  Pose2 relative;   // T_b^a: the live pose seen from the map node
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
  int pairs = 0;
  double rms = 0.0;  // m
  int iterations = 0;
};

// A map node's scan with its k-d tree and normals; read-only after
// construction (but for the lookup grid, built once under a once_flag), so
// threads may match against it at once.
//
// ICP asks for the nearest point within a gate thousands of times per match.
// nearestWithin() answers from a grid over the scan (cell 5 cm, reaching
// `reach` beyond the points) that holds, per cell, every point that can be
// nearest to some query in that cell: the points within d0 + 2r of the
// cell's centre, d0 the centre's nearest distance and r the half diagonal
// (any query in the cell has its nearest within d0 + r, hence within d0 + 2r
// of the centre). A cell whose centre is farther than reach + r from every
// point has no point within reach of any query and holds none. The answer
// is the k-d tree's (ties between equidistant points aside), at a few
// distance computations instead of a tree descent.
class IndexedScan {
 public:
  explicit IndexedScan(Scan points, double reach = 0.5);
  ~IndexedScan();
  IndexedScan(const IndexedScan&) = delete;
  IndexedScan& operator=(const IndexedScan&) = delete;
  const Scan& points() const { return points_; }
  const std::vector<Point2>& normals() const { return normals_; }
  // Nearest point's index and squared distance (index -1 for an empty scan).
  int nearest(const Point2& p, double* squared_distance) const;
  // The nearest point if it lies within `gate` (-1 otherwise); from the grid
  // when gate <= reach, else from the k-d tree.
  int nearestWithin(const Point2& p, double gate, double* squared_distance) const;
  // The point-to-line pair of `q` that the matcher and its covariance use:
  // the nearest point within `gate`, if it has a normal; that normal, and
  // the signed distance n . (q - point) as the residual. False otherwise.
  bool pointToLine(const Point2& q, double gate, Point2* normal, double* residual) const {
    double d2;
    const int j = nearestWithin(q, gate, &d2);
    if (j < 0 || normals_[j].isZero()) return false;
    *normal = normals_[j];
    *residual = normal->dot(q - points_[j]);
    return true;
  }

 private:
  struct Tree;
  struct Grid;
  void buildGrid() const;
  Scan points_;
  std::vector<Point2> normals_;
  std::unique_ptr<Tree> tree_;
  double reach_;
  mutable std::once_flag grid_once_;
  mutable std::unique_ptr<Grid> grid_;
};

class ScanMatcher {
 public:
  explicit ScanMatcher(ScanMatcherConfig config = {}) : config_(config) {}
  const ScanMatcherConfig& config() const { return config_; }
  // Matches `live` (in the live pose's frame) against `reference`, starting
  // from `guess` (the live pose in the reference's frame).
  ScanMatch match(const IndexedScan& reference, const Scan& live, const Pose2& guess) const;

 private:
  ScanMatcherConfig config_;
};

}  // namespace hamal::moss
