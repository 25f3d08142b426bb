// Test-local helpers of the AprilSAM suite: random 2D graphs (odometry, loop
// closures including one that spans the whole trajectory, Point2 landmarks
// seen through PosePointFactor and RangeBearingFactor) and the thesis
// protocol run of a back-end over a graph.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "backends/aprilsam/aprilsam_backend.h"
#include "core/graph.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/range_bearing_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal::aprilsam::testing {

struct RandomGraphOptions {
  int poses = 60;
  double loop_probability = 0.15;
  int landmarks = 0;
  unsigned seed = 1;
};

// Poses walk on a 10 x 10 m square; loop closures link poses closer than
// 3 m; the last pose closes a loop to the first.
inline Graph randomGraph(const RandomGraphOptions& o) {
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<Pose2> truth;
  Pose2 p(0, 0, 0);
  for (int i = 0; i < o.poses; ++i) {
    truth.push_back(p);
    double turn = 0.6 * (uni(rng) - 0.5);
    if (std::fabs(p.x) > 4 || std::fabs(p.y) > 4) turn += 1.2;
    p = p.compose(Pose2(1.0, 0.0, turn));
  }
  Graph g;
  g.source = "random";
  Eigen::Matrix3d info = Eigen::Vector3d(100, 50, 400).asDiagonal();
  info(0, 1) = info(1, 0) = 10;  // off-diagonal information, as intel has
  auto measure = [&](int a, int b) {
    Pose2 z = truth[a].between(truth[b]);
    return Pose2(z.x + 0.05 * noise(rng), z.y + 0.05 * noise(rng), z.theta + 0.02 * noise(rng));
  };
  for (int i = 1; i < o.poses; ++i) {
    g.add(std::make_shared<BetweenFactor>(X(i - 1), X(i), measure(i - 1, i), info));
    for (int j = 0; j + 2 < i; ++j)
      if ((truth[i].t() - truth[j].t()).norm() < 3.0 && uni(rng) < o.loop_probability)
        g.add(std::make_shared<BetweenFactor>(X(j), X(i), measure(j, i), info));
  }
  g.add(std::make_shared<BetweenFactor>(X(0), X(o.poses - 1), measure(0, o.poses - 1), info));
  const Eigen::Matrix2d pinfo = Eigen::Vector2d(40, 40).asDiagonal();
  for (int l = 0; l < o.landmarks; ++l) {
    const int first = static_cast<int>(uni(rng) * (o.poses - 5));
    const Point2 lm = truth[first].transformFrom(Point2(1.0 + uni(rng), uni(rng) - 0.5));
    for (int k = first; k < o.poses; k += 3) {
      if ((truth[k].t() - lm).norm() > 4.0) continue;
      if (k % 2 == 0) {
        const Point2 z = truth[k].transformTo(lm) + 0.05 * Point2(noise(rng), noise(rng));
        g.add(std::make_shared<PosePointFactor>(X(k), L(l), z, pinfo));
      } else {
        const Eigen::Vector2d d = lm - truth[k].t();
        const double range = d.norm() + 0.05 * noise(rng);
        const double bearing =
            wrapAngle(std::atan2(d.y(), d.x()) - truth[k].theta + 0.01 * noise(rng));
        g.add(std::make_shared<RangeBearingFactor>(X(k), L(l), range, bearing,
                                                   Eigen::Vector2d(100, 400).asDiagonal()));
      }
    }
  }
  return g;
}

inline std::unique_ptr<AprilSamBackend> makeAprilSam(
    const std::map<std::string, std::string>& given) {
  Options o("aprilsam", AprilSamOptions::optionSpecs(), given);
  return std::make_unique<AprilSamBackend>(AprilSamOptions::fromOptions(o));
}

}  // namespace hamal::aprilsam::testing
