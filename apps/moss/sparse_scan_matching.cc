// SparseScanMatching: see sparse_scan_matching.h (thesis eq. 5.7-5.10).
#include "apps/moss/sparse_scan_matching.h"

#include <algorithm>
#include <limits>

#include "apps/moss/scan_matcher.h"

namespace hamal::moss {

SparseScanMatching::SparseScanMatching(const PriorMap& map, SsmConfig config)
    : map_(map), config_(config) {
  const std::size_t m = map.poses.size();
  std::vector<std::unique_ptr<IndexedScan>> global;
  for (std::size_t s = 0; s < m; ++s) {
    Scan g;
    for (const Point2& p : map.scans[s]) g.push_back(map.poses[s].transformFrom(p));
    global.push_back(std::make_unique<IndexedScan>(std::move(g)));
  }
  const double dmax2 = config.max_distance * config.max_distance;
  const double k = 1.0 / (2.0 * config.sigma * config.sigma);
  d_.assign(m, std::vector<double>(m, 0.0));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t s = 0; s < m; ++s) {
      double sum = 0.0;
      for (const Point2& q : map.scans[i]) {
        double d2 = dmax2;
        if (global[s]->nearest(map.poses[i].transformFrom(q), &d2) < 0) d2 = dmax2;
        sum -= k * std::min(d2, dmax2);
      }
      d_[i][s] = sum;
    }
  }
}

double SparseScanMatching::logLikelihood(const Selection& a) const {
  const std::size_t m = map_.poses.size();
  double total = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    int nearest = -1;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t s = 0; s < m; ++s) {
      if (!a[s]) continue;
      const double d = (map_.poses[s].t() - map_.poses[i].t()).squaredNorm();
      if (d < best) {
        best = d;
        nearest = static_cast<int>(s);
      }
    }
    if (nearest < 0) return -std::numeric_limits<double>::infinity();
    total += d_[i][nearest];
  }
  return total;
}

Selection SparseScanMatching::select(int c, std::vector<int>* order) const {
  const std::size_t m = map_.poses.size();
  checkMapSize(c, m, "SSM");
  Selection a(m, 0);
  if (order) order->clear();
  for (int added = 0; added < c; ++added) {
    int best = -1;
    double best_l = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < m; ++k) {
      if (a[k]) continue;
      a[k] = 1;
      const double l = logLikelihood(a);
      a[k] = 0;
      if (best < 0 || l > best_l) {
        best_l = l;
        best = static_cast<int>(k);
      }
    }
    a[best] = 1;
    if (order) order->push_back(best);
  }
  return a;
}

}  // namespace hamal::moss
