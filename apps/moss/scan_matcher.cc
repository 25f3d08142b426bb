// ScanMatcher: see scan_matcher.h (Censi 2008, point-to-line ICP).
#include "apps/moss/scan_matcher.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <cstdint>
#include <nanoflann.hpp>

#include "apps/moss/icp_covariance.h"
#include "core/enum_names.h"
#include "core/error.h"

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

struct IndexedScan::Grid {
  static constexpr double kCell = 0.05;  // m
  double x0 = 0.0, y0 = 0.0;
  int nx = 0, ny = 0;
  std::vector<std::uint32_t> begin;  // per cell, into `points`; nx * ny + 1 entries
  std::vector<std::uint32_t> points;
};

IndexedScan::IndexedScan(Scan points, double reach) : points_(std::move(points)), reach_(reach) {
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

void IndexedScan::buildGrid() const {
  auto g = std::make_unique<Grid>();
  if (!points_.empty()) {
    Point2 lo = points_[0], hi = points_[0];
    for (const Point2& p : points_) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const double margin = reach_ + Grid::kCell;
    g->x0 = lo.x() - margin;
    g->y0 = lo.y() - margin;
    g->nx = static_cast<int>(std::ceil((hi.x() - lo.x() + 2 * margin) / Grid::kCell));
    g->ny = static_cast<int>(std::ceil((hi.y() - lo.y() + 2 * margin) / Grid::kCell));
    const double r = Grid::kCell * std::sqrt(0.5);
    g->begin.reserve(static_cast<std::size_t>(g->nx) * g->ny + 1);
    std::vector<std::pair<unsigned, double>> found;
    for (int iy = 0; iy < g->ny; ++iy) {
      for (int ix = 0; ix < g->nx; ++ix) {
        g->begin.push_back(static_cast<std::uint32_t>(g->points.size()));
        const Point2 centre(g->x0 + (ix + 0.5) * Grid::kCell, g->y0 + (iy + 0.5) * Grid::kCell);
        double d2;
        nearest(centre, &d2);
        const double d0 = std::sqrt(d2);
        if (d0 > reach_ + r) continue;
        const double within = d0 + 2 * r;
        // Padded so that rounding in the search cannot leave a candidate out.
        tree_->index.radiusSearch(centre.data(), within * within * (1 + 1e-9) + 1e-12, found,
                                  nanoflann::SearchParams());
        for (const auto& f : found) g->points.push_back(f.first);
      }
    }
  }
  g->begin.push_back(static_cast<std::uint32_t>(g->points.size()));
  grid_ = std::move(g);
}

int IndexedScan::nearestWithin(const Point2& p, double gate, double* squared_distance) const {
  if (gate > reach_) {
    const int j = nearest(p, squared_distance);
    return j >= 0 && *squared_distance <= gate * gate ? j : -1;
  }
  std::call_once(grid_once_, [this] { buildGrid(); });
  const Grid& g = *grid_;
  const double fx = (p.x() - g.x0) / Grid::kCell, fy = (p.y() - g.y0) / Grid::kCell;
  if (!(fx >= 0 && fy >= 0 && fx < g.nx && fy < g.ny)) return -1;  // beyond reach of every point
  const std::size_t cell = static_cast<std::size_t>(static_cast<int>(fy)) * g.nx +
                           static_cast<std::size_t>(static_cast<int>(fx));
  int best = -1;
  double best_d2 = 0.0;
  for (std::uint32_t k = g.begin[cell]; k < g.begin[cell + 1]; ++k) {
    const std::uint32_t j = g.points[k];
    const double d2 = (points_[j] - p).squaredNorm();
    if (best < 0 || d2 < best_d2 || (d2 == best_d2 && static_cast<int>(j) < best)) {
      best = static_cast<int>(j);
      best_d2 = d2;
    }
  }
  if (best < 0 || best_d2 > gate * gate) return -1;
  *squared_distance = best_d2;
  return best;
}

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
      Point2 n;
      double r;
      if (!reference.pointToLine(q, gate, &n, &r)) continue;
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
  Eigen::Matrix3d information = h / (c.sigma * c.sigma);
  if (c.information == ScanMatcherConfig::Information::kCensi) {
    const IcpCovariance cov = icpCovariance(reference, live, t, c.gate_fine, c.sigma_range);
    if (!cov.ok) return m;
    information = cov.covariance.inverse();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(information);
  const Eigen::Vector3d ev = es.eigenvalues().cwiseMax(c.min_eigenvalue);
  m.information = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
  m.information = 0.5 * (m.information + m.information.transpose()).eval();
  m.ok = std::isfinite(m.information.sum()) && std::isfinite(t.x + t.y + t.theta);
  return m;
}

namespace {
constexpr EnumNames<ScanMatcherConfig::Information, 2> kInformation = {
    {{ScanMatcherConfig::Information::kHessian, "hessian"},
     {ScanMatcherConfig::Information::kCensi, "censi"}}};
}  // namespace

ScanMatcherConfig::Information parseInformation(const std::string& name) {
  return parseEnum(kInformation, name, "scan matcher information");
}

const char* toString(ScanMatcherConfig::Information information) {
  return enumName(kInformation, information);
}

}  // namespace hamal::moss
