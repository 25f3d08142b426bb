// ScanMatcher: see scan_matcher.h (Censi 2008, point-to-line ICP).
#include "apps/moss/scan_matcher.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <nanoflann.hpp>

namespace hamal::moss {

namespace {

struct Cloud {
  const Scan* points;
  std::size_t kdtree_get_point_count() const { return points->size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return (*points)[i][d]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 2>;

}  // namespace

struct IndexedScan::Tree {
  Cloud cloud;
  KdTree index;
  explicit Tree(const Scan* p)
      : cloud{p}, index(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    index.buildIndex();
  }
};

IndexedScan::IndexedScan(Scan points) : points_(std::move(points)) {
  tree_ = std::make_unique<Tree>(&points_);
  // Normal of each point: the smallest principal direction of the points
  // within 25 cm (itself included). A point with fewer than 4 such
  // neighbours, or whose neighbourhood is not line-like, gets no normal and
  // is never paired: a fixed neighbour count would reach across to another
  // wall where the scan is sparse and invent a normal along the hallway.
  normals_.resize(points_.size(), Point2::Zero());
  std::vector<std::pair<unsigned, double>> found;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    tree_->index.radiusSearch(points_[i].data(), 0.25 * 0.25, found, nanoflann::SearchParams());
    if (found.size() < 4) continue;
    Point2 mean = Point2::Zero();
    for (const auto& f : found) mean += points_[f.first];
    mean /= static_cast<double>(found.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& f : found) {
      const Point2 d = points_[f.first] - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    if (es.eigenvalues()(0) > 0.05 * es.eigenvalues()(1)) continue;
    normals_[i] = es.eigenvectors().col(0);
  }
}

IndexedScan::~IndexedScan() = default;

int IndexedScan::nearest(const Point2& p, double* squared_distance) const {
  if (points_.empty()) return -1;
  unsigned idx = 0;
  double d2 = 0.0;
  tree_->index.knnSearch(p.data(), 1, &idx, &d2);
  *squared_distance = d2;
  return static_cast<int>(idx);
}

ScanMatch ScanMatcher::match(const IndexedScan& reference, const Scan& live,
                             const Pose2& guess) const {
  const ScanMatcherConfig& c = config_;
  ScanMatch m;
  Pose2 t = guess;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int it = 0; it < c.max_iterations; ++it) {
    const double gate = it < c.coarse_iterations ? c.gate_coarse : c.gate_fine;
    const double cs = std::cos(t.theta), sn = std::sin(t.theta);
    h.setZero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    double sum2 = 0.0;
    int pairs = 0;
    for (const Point2& p : live) {
      const Point2 q(cs * p.x() - sn * p.y() + t.x, sn * p.x() + cs * p.y() + t.y);
      double d2;
      const int j = reference.nearest(q, &d2);
      if (j < 0 || d2 > gate * gate) continue;
      const Point2& n = reference.normals()[j];
      if (n.isZero()) continue;
      const double r = n.dot(q - reference.points()[j]);
      const Eigen::Vector3d jac(
          n.x(), n.y(), n.x() * (-sn * p.x() - cs * p.y()) + n.y() * (cs * p.x() - sn * p.y()));
      h += jac * jac.transpose();
      g += jac * r;
      sum2 += r * r;
      ++pairs;
    }
    m.pairs = pairs;
    m.rms = pairs ? std::sqrt(sum2 / pairs) : 0.0;
    m.iterations = it + 1;
    if (pairs < c.min_pairs) return m;
    // Levenberg-style damping keeps a degenerate direction from running off.
    const Eigen::Vector3d delta =
        -(h + 1e-6 * Eigen::Matrix3d::Identity() * (1.0 + h.trace())).ldlt().solve(g);
    t = Pose2(t.x + delta.x(), t.y + delta.y(), wrapAngle(t.theta + delta.z()));
    if (it >= c.coarse_iterations && delta.head<2>().norm() < 1e-4 && std::abs(delta.z()) < 1e-4)
      break;
  }
  m.relative = t;
  if (m.pairs < c.min_pairs || m.pairs < c.min_inlier_fraction * live.size() || m.rms > c.max_rms)
    return m;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(h / (c.sigma * c.sigma));
  const Eigen::Vector3d ev = es.eigenvalues().cwiseMax(c.min_eigenvalue);
  m.information = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
  m.information = 0.5 * (m.information + m.information.transpose()).eval();
  m.ok = std::isfinite(m.information.sum()) && std::isfinite(t.x + t.y + t.theta);
  return m;
}

}  // namespace hamal::moss
