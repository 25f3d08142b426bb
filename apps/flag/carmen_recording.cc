// FLAG's labelled map and recording from a real CARMEN log (carmen_recording.h).
#include "apps/flag/carmen_recording.h"

#include <cmath>
#include <random>

#include "core/error.h"

namespace hamal::flag {

void CarmenFlagOptions::validate() const {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(std::string(name) + " must be > 0");
  };
  positive(scans.step, "carmen step");
  positive(scans.turn, "carmen turn");
  positive(cluster_radius, "cluster_radius");
  positive(min_distance, "carmen min distance");
  positive(stated_odom_sigma_x, "odometry sigma x");
  positive(stated_odom_sigma_y, "odometry sigma y");
  positive(stated_odom_sigma_theta, "odometry sigma theta");
  positive(stated_range_sigma, "range sigma");
  positive(stated_bearing_sigma, "bearing sigma");
  if (min_sightings < 1) throw Error("min_sightings must be >= 1");
  for (double v : {label_sigma, odom_sigma_x, odom_sigma_y, odom_sigma_theta})
    if (!(v >= 0) || !std::isfinite(v)) throw Error("label and world odometry sigmas must be >= 0");
  edges.validate();
}

RangeScan rangeScanOf(const carmen::LaserScan& scan) {
  RangeScan r;
  r.start_angle = scan.start_angle;
  r.angular_step = scan.angular_step;
  r.max_range = scan.max_range;
  r.ranges = scan.ranges;
  return r;
}

CarmenFlag prepareCarmenFlag(const carmen::CarmenLog& log, const CarmenFlagOptions& options) {
  options.validate();
  if (options.map_corners) options.walls.validate();
  const std::vector<const carmen::LaserScan*> kept = carmen::keyScans(log, options.scans);
  // Detections in each kept scan, in the robot frame.
  std::vector<std::vector<VerticalEdge>> edges(kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    edges[i] = detectVerticalEdges(rangeScanOf(*kept[i]), options.edges);
    for (VerticalEdge& e : edges[i]) {
      e.position = kept[i]->laser_offset.transformFrom(e.position);
      e.range = e.position.norm();
      e.bearing = std::atan2(e.position.y(), e.position.x());
    }
  }
  // Clusters of the detections in the world.
  struct Cluster {
    Point2 sum = Point2::Zero();
    int n = 0;
    Point2 mean() const { return sum / double(n); }
  };
  std::vector<Cluster> clusters;
  std::vector<std::vector<std::size_t>> member(kept.size());
  for (std::size_t i = 0; i < kept.size(); ++i)
    for (const VerticalEdge& e : edges[i]) {
      const Point2 w = kept[i]->pose.transformFrom(e.position);
      std::size_t k = 0;
      while (k < clusters.size() && (clusters[k].mean() - w).norm() > options.cluster_radius) ++k;
      if (k == clusters.size()) clusters.emplace_back();
      clusters[k].sum += w;
      ++clusters[k].n;
      member[i].push_back(k);
    }
  CarmenFlag out;
  std::vector<long> landmark_of(clusters.size(), -1);
  std::vector<Point2> corners;
  if (options.map_corners) {
    std::vector<WallSegment> segments;
    for (const carmen::LaserScan* k : kept)
      for (const LineSegment& l : extractLineSegments(rangeScanOf(*k), options.edges))
        segments.push_back({k->pose.transformFrom(k->laser_offset.transformFrom(l.a)),
                            k->pose.transformFrom(k->laser_offset.transformFrom(l.b))});
    const std::vector<MapWall> walls = mergeWalls(segments, options.walls);
    corners = wallCorners(walls, options.walls);
    out.clusters = walls.size();
  }
  // Labels and odometry draw from streams of their own, so the odometry
  // does not change with the count of landmarks.
  std::mt19937_64 label_rng(options.seed), rng(options.seed ^ 0x0d0e7e70d0e7e7ULL);
  std::normal_distribution<double> label_n01(0.0, 1.0), n01(0.0, 1.0);
  if (!options.map_corners) {
    for (std::size_t k = 0; k < clusters.size(); ++k) {
      if (clusters[k].n < options.min_sightings) continue;
      landmark_of[k] = long(corners.size());
      corners.push_back(clusters[k].mean());
    }
    out.clusters = clusters.size();
  }
  for (std::size_t k = 0; k < corners.size(); ++k) {
    out.landmarks.push_back(corners[k]);
    const double dx = label_n01(label_rng), dy = label_n01(label_rng);
    out.labels.push_back({std::uint64_t(k), corners[k] + options.label_sigma * Point2(dx, dy)});
  }
  // With map corners, a detection's source is the corner it lies near.
  const auto sourceOf = [&](std::size_t i, std::size_t j) -> long {
    if (!options.map_corners) return landmark_of[member[i][j]];
    const Point2 w = kept[i]->pose.transformFrom(edges[i][j].position);
    long best = -1;
    double best_d = options.cluster_radius;
    for (std::size_t k = 0; k < corners.size(); ++k)
      if ((corners[k] - w).norm() <= best_d) best_d = (corners[best = long(k)] - w).norm();
    return best;
  };
  if (out.landmarks.empty())
    throw Error(log.file +
                (options.map_corners
                     ? std::string(": the map's walls make no corner")
                     : ": no corner was seen " + std::to_string(options.min_sightings) +
                           " times (min_sightings)") +
                ": no landmark to localize against");
  Recording& rec = out.recording;
  rec.odom_sigma_x = options.stated_odom_sigma_x;
  rec.odom_sigma_y = options.stated_odom_sigma_y;
  rec.odom_sigma_theta = options.stated_odom_sigma_theta;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    RecordedStep s;
    s.truth = kept[i]->pose;
    s.time = kept[i]->timestamp;
    if (i > 0) {
      const Pose2 delta = kept[i - 1]->pose.between(kept[i]->pose);
      s.distance = std::hypot(delta.x, delta.y);
      const double d = std::max(s.distance, options.min_distance);
      const Eigen::Vector3d drawn =
          odometrySigmas(options.odom_sigma_x, options.odom_sigma_y, options.odom_sigma_theta, d);
      s.odometry_sigma = odometrySigmas(options.stated_odom_sigma_x, options.stated_odom_sigma_y,
                                        options.stated_odom_sigma_theta, d);
      const double ex = n01(rng), ey = n01(rng), et = n01(rng);
      s.odometry = Pose2(delta.x + drawn[0] * ex, delta.y + drawn[1] * ey,
                         wrapAngle(delta.theta + drawn[2] * et));
    }
    for (std::size_t j = 0; j < edges[i].size(); ++j) {
      Detection d;
      d.range = edges[i][j].range;
      d.bearing = edges[i][j].bearing;
      d.range_sigma = options.stated_range_sigma;
      d.bearing_sigma = options.stated_bearing_sigma;
      const long lm = sourceOf(i, j);
      d.source = lm >= 0 ? Source{Source::kCorner, std::uint64_t(lm)} : Source{Source::kNone, 0};
      s.detections.push_back(d);
      ++out.detections;
    }
    rec.steps.push_back(std::move(s));
  }
  return out;
}

}  // namespace hamal::flag
