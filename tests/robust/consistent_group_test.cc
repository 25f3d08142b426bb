// ConsistentGroup (backends/robust/consistent_group.h): the closures that
// agree through the odometry, whatever the answer decided, on a straight
// run with a revisit group and random false closures; closures it cannot
// test stay outside; too few candidates give no group.
#include "backends/robust/consistent_group.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "core/key.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"

namespace hamal::robust {
namespace {

constexpr int kPoses = 200;

Eigen::Matrix3d information(double sigma_xy, double sigma_theta) {
  Eigen::Matrix3d i = Eigen::Matrix3d::Zero();
  i.diagonal() << 1 / (sigma_xy * sigma_xy), 1 / (sigma_xy * sigma_xy),
      1 / (sigma_theta * sigma_theta);
  return i;
}

// Pose i at (i, 0, 0): exact odometry and exact closures between poses
// `from` and `to` (to < from), or ones `off` metres to the side.
FactorPtr closure(int from, int to, double off) {
  return std::make_shared<BetweenFactor>(X(from), X(to), Pose2(to - from, off, 0),
                                         information(0.1, 0.01));
}

std::vector<FactorPtr> odometry() {
  std::vector<FactorPtr> out;
  for (int i = 0; i + 1 < kPoses; ++i)
    out.push_back(
        std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0), information(0.02, 0.001)));
  return out;
}

TEST(ConsistentGroup, TheRevisitsClosuresAgreeAndRandomOnesDoNot) {
  std::vector<FactorPtr> keep;
  std::vector<const Factor*> candidates;
  std::vector<bool> truth;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pose(0, kPoses - 1);
  std::uniform_real_distribution<double> side(5, 20);  // metres to either side
  for (int k = 0; k < 30; ++k) {                       // false: random ends, metres off
    int a = pose(rng), b = pose(rng);
    if (std::abs(a - b) < 2) continue;
    keep.push_back(closure(std::max(a, b), std::min(a, b), (k % 2 ? 1 : -1) * side(rng)));
    truth.push_back(false);
  }
  for (int k = 0; k < 8; ++k) {  // the revisit: exact
    keep.push_back(closure(150 + k, 20 + k, 0));
    truth.push_back(true);
  }
  for (const FactorPtr& f : keep) candidates.push_back(f.get());
  const std::vector<bool> group = consistentGroup(odometry(), candidates, kGroupCliqueSeconds);
  ASSERT_EQ(group.size(), candidates.size());
  std::size_t true_in = 0, false_in = 0;
  for (std::size_t i = 0; i < group.size(); ++i) {
    true_in += group[i] && truth[i];
    false_in += group[i] && !truth[i];
  }
  EXPECT_EQ(true_in, 8u);
  EXPECT_EQ(false_in, 0u);
}

TEST(ConsistentGroup, AClosureItCannotTestStaysOutside) {
  std::vector<FactorPtr> keep = {closure(150, 20, 0), closure(151, 21, 0), closure(152, 22, 0)};
  keep.push_back(
      std::make_shared<PosePointFactor>(X(5), L(1), Point2(1, 1), Eigen::Matrix2d::Identity()));
  std::vector<const Factor*> candidates;
  for (const FactorPtr& f : keep) candidates.push_back(f.get());
  const std::vector<bool> group = consistentGroup(odometry(), candidates, kGroupCliqueSeconds);
  EXPECT_EQ(group, (std::vector<bool>{true, true, true, false}));
}

TEST(ConsistentGroup, FewerThanTwoTestableClosuresGiveNoGroup) {
  const FactorPtr one = closure(150, 20, 0);
  EXPECT_TRUE(consistentGroup(odometry(), {one.get()}, kGroupCliqueSeconds).empty());
  EXPECT_TRUE(consistentGroup(odometry(), {}, kGroupCliqueSeconds).empty());
}

}  // namespace
}  // namespace hamal::robust
