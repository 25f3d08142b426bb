// The multi-scan stability check on a log's corners (stable_edge_filter.h).
#include "apps/flag/stable_edge_filter.h"

#include <algorithm>
#include <cmath>

#include "apps/flag/carmen_recording.h"
#include "core/error.h"

namespace hamal::flag {

void StableEdgeOptions::validate() const {
  if (window < 0) throw Error("stable edges: window must be >= 0, not " + std::to_string(window));
  if (min_scans < 0)
    throw Error("stable edges: min_scans must be >= 0, not " + std::to_string(min_scans));
  if (!(radius > 0) || !std::isfinite(radius)) throw Error("stable edges: radius must be > 0");
  if (!(spacing >= 0) || !std::isfinite(spacing) || !(spacing_turn >= 0) ||
      !std::isfinite(spacing_turn))
    throw Error("stable edges: spacing and spacing_turn must be >= 0");
}

std::vector<VerticalEdge> keepStableEdges(const std::vector<VerticalEdge>& edges,
                                          const std::vector<std::vector<Point2>>& neighbours,
                                          const StableEdgeOptions& options) {
  options.validate();
  const std::size_t need = std::min<std::size_t>(std::size_t(options.min_scans), neighbours.size());
  std::vector<VerticalEdge> kept;
  for (const VerticalEdge& e : edges) {
    std::size_t seen = 0;
    for (const std::vector<Point2>& scan : neighbours)
      seen += std::any_of(scan.begin(), scan.end(), [&](const Point2& p) {
        return (p - e.position).norm() <= options.radius;
      });
    if (seen >= need) kept.push_back(e);
  }
  return kept;
}

StableEdgeFilter::StableEdgeFilter(const carmen::CarmenLog& log, const std::string& tag,
                                   const VerticalEdgeDetectorOptions& edges,
                                   const StableEdgeOptions& options, double latency)
    : log_(log), edges_(edges), options_(options), latency_(latency), scans_(log.scansOf(tag)) {
  options.validate();
  edges.validate();
  if (scans_.empty()) throw Error(log.file + ": no " + tag + " scans");
  if (options.enabled && log.odometry.empty())
    throw Error(log.file +
                ": the stable-edge check moves corners by the log's odometry, and the log has "
                "no ODOM records (turn it off: --nostable_edges)");
  corners_.resize(scans_.size());
  odometry_.resize(scans_.size());
}

const std::vector<VerticalEdge>& StableEdgeFilter::corners(std::size_t k) {
  if (!corners_[k]) corners_[k] = detectVerticalEdges(rangeScanOf(*scans_[k]), edges_);
  return *corners_[k];
}

const Pose2& StableEdgeFilter::laserOdometry(std::size_t k) {
  if (!odometry_[k])
    odometry_[k] = logOdometryAt(log_, *scans_[k], latency_).compose(scans_[k]->laser_offset);
  return *odometry_[k];
}

std::vector<VerticalEdge> StableEdgeFilter::detect(std::size_t index) {
  const carmen::LaserScan* scan = &log_.scans.at(index);
  const auto at = std::lower_bound(scans_.begin(), scans_.end(), scan);
  if (at == scans_.end() || *at != scan)
    throw Error(log_.file + ": scan " + std::to_string(index) +
                " is not one of the filter's laser");
  const std::size_t k = std::size_t(at - scans_.begin());
  if (!options_.enabled) return corners(k);
  std::vector<std::vector<Point2>> neighbours;
  for (const long step : {-1L, 1L}) {
    std::size_t last = k;
    for (long j = long(k) + step, taken = 0;
         j >= 0 && j < long(scans_.size()) && taken < options_.window; j += step) {
      const Pose2 from_last = laserOdometry(last).between(laserOdometry(std::size_t(j)));
      if (from_last.t().norm() < options_.spacing &&
          std::abs(wrapAngle(from_last.theta)) < options_.spacing_turn)
        continue;
      last = std::size_t(j);
      ++taken;
      const Pose2 motion = laserOdometry(k).between(laserOdometry(last));
      std::vector<Point2> seen;
      for (const VerticalEdge& e : corners(last)) seen.push_back(motion.transformFrom(e.position));
      neighbours.push_back(std::move(seen));
    }
  }
  return keepStableEdges(corners(k), neighbours, options_);
}

}  // namespace hamal::flag
