// The conformance suite's world: see small_world.h.
#include "conformance/small_world.h"

#include <cmath>
#include <memory>

#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/prior_factor.h"

namespace hamal::testing {

namespace {
double noise(int i, int k) { return 0.05 * std::sin(1.7 * i + 2.3 * k + 0.5); }
}  // namespace

Graph smallWorld() {
  Graph g;
  g.source = "conformance square";
  const Eigen::Matrix3d info = Eigen::Vector3d(100, 100, 400).asDiagonal();
  Eigen::Matrix2d obs;
  obs << 40, 5, 5, 30;
  const int per_lap = 12, poses = 2 * per_lap;
  Pose2 p;
  for (int i = 0; i < poses; ++i) {
    g.initial.insert(X(i), p);
    if (i + 1 == poses) break;
    const bool corner = (i % 3) == 2;
    const Pose2 z(1.0 + noise(i, 0), noise(i, 1), (corner ? M_PI / 2 : 0.0) + noise(i, 2));
    g.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), z, info));
    p = p.compose(z);
  }
  for (int i = per_lap; i < poses; ++i)
    g.add(std::make_shared<BetweenFactor>(X(i - per_lap), X(i),
                                          Pose2(noise(i, 3), noise(i, 4), noise(i, 5)), info));
  for (int i = 0; i < poses; i += 2)
    g.add(std::make_shared<PosePointFactor>(X(i), L(i / 2 % 4),
                                            Point2(0.5 + noise(i, 6), 1.0 + noise(i, 7)), obs));
  return g;
}

Step chainStep(int n, std::vector<FactorPtr> extra) {
  Step s;
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  s.new_factors.push_back(std::make_shared<PriorFactor>(X(0), Pose2(), 1e4 * info));
  for (int i = 0; i < n; ++i) s.new_values.insert(X(i), Pose2(i + 0.01 * std::sin(i), 0, 0));
  for (int i = 0; i + 1 < n; ++i)
    s.new_factors.push_back(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0), info));
  for (auto& f : extra) s.new_factors.push_back(f);
  return s;
}

}  // namespace hamal::testing
