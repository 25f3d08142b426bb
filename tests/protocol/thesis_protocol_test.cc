// ThesisProtocol: the step plan of docs/PROTOCOL.md on small hand-made graphs.
#include "protocol/thesis_protocol.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/prior_factor.h"

namespace hamal {
namespace {

const Eigen::Matrix3d kInfo = Eigen::Matrix3d::Identity();

FactorPtr between(Key a, Key b, Pose2 z) { return std::make_shared<BetweenFactor>(a, b, z, kInfo); }

// 0 -> 1 -> 2 -> 3 with a loop closure 3 -> 0 stored from the higher id, and
// odometry 1 -> 2 stored reversed (2, 1).
Graph square() {
  Graph g;
  g.add(between(X(0), X(1), Pose2(1, 0, M_PI / 2)));
  g.add(between(X(2), X(1), Pose2(1, 0, M_PI / 2).inverse()));
  g.add(between(X(2), X(3), Pose2(1, 0, M_PI / 2)));
  g.add(between(X(3), X(0), Pose2(1, 0, M_PI / 2)));
  return g;
}

TEST(ThesisProtocol, StepsFollowPoseIds) {
  const Graph g = square();
  ThesisProtocol p(g);
  ASSERT_EQ(p.size(), 4u);
  Values est;
  std::vector<std::size_t> factors_per_step;
  for (std::size_t i = 0; i < p.size(); ++i) {
    Step s = p.step(i, est);
    EXPECT_EQ(s.new_values.size(), 1u);
    EXPECT_TRUE(s.new_values.contains(X(i)));
    factors_per_step.push_back(s.new_factors.size());
    for (const auto& [k, e] : s.new_values) est.insertEntry(k, e);
  }
  // Step 0: the prior; steps 1, 2: odometry; step 3: odometry + loop closure.
  EXPECT_EQ(factors_per_step, (std::vector<std::size_t>{1, 1, 1, 2}));
  // The reversed edge was inverted: pose 2 is at (1, 1).
  EXPECT_NEAR(est.pose(X(2)).x, 1, 1e-12);
  EXPECT_NEAR(est.pose(X(2)).y, 1, 1e-12);
  EXPECT_NEAR(est.pose(X(2)).theta, M_PI, 1e-12);
}

TEST(ThesisProtocol, GuessesComeFromTheGivenEstimate) {
  ThesisProtocol p(square());
  Values est;
  est.insert(X(0), Pose2(10, 0, 0));
  const Step s = p.step(1, est);
  EXPECT_NEAR(s.new_values.pose(X(1)).x, 11, 1e-12);
}

TEST(ThesisProtocol, PriorAndBatch) {
  Graph g = square();
  g.initial.insert(X(0), Pose2(5, 5, 0.1));
  ThesisProtocol p(g);
  const auto* prior = dynamic_cast<const PriorFactor*>(p.prior().get());
  ASSERT_NE(prior, nullptr);
  EXPECT_EQ(prior->measurement().x, 5);
  EXPECT_EQ(prior->information()(0, 0), 1e4);
  EXPECT_EQ(prior->information()(2, 2), 1e3);
  const Step b = p.batch();
  EXPECT_EQ(b.new_factors.size(), 5u);
  EXPECT_EQ(b.new_values.size(), 4u);
  EXPECT_NEAR(p.initialValues().pose(X(1)).x, 5 + std::cos(0.1), 1e-12);
}

TEST(ThesisProtocol, LandmarksEnterWithTheirFirstObservation) {
  Graph g;
  g.add(between(X(0), X(2), Pose2(1, 0, 0)));  // ids skip 1, as in victoria_park.txt
  g.add(std::make_shared<PosePointFactor>(X(2), L(1), Point2(2, 0), Eigen::Matrix2d::Identity()));
  g.add(std::make_shared<PosePointFactor>(X(0), L(1), Point2(3, 0), Eigen::Matrix2d::Identity()));
  ThesisProtocol p(g);
  ASSERT_EQ(p.size(), 2u);
  Values est;
  Step s0 = p.step(0, est);
  // The observation from x0 completes at step 0, so the landmark enters there.
  EXPECT_TRUE(s0.new_values.contains(L(1)));
  EXPECT_NEAR(s0.new_values.point(L(1)).x(), 3, 1e-12);
  for (const auto& [k, e] : s0.new_values) est.insertEntry(k, e);
  Step s1 = p.step(1, est);
  EXPECT_EQ(s1.new_values.size(), 1u);
  EXPECT_EQ(s1.new_factors.size(), 2u);
}

TEST(ThesisProtocol, FixedVariablesEnterAtTheGraphsValueAndAFixedPoseReplacesThePrior) {
  Graph g = square();
  g.initial.insert(X(2), Pose2(7, 8, 0.5));
  g.fixed = {X(2)};
  const ThesisProtocol p(g);
  EXPECT_EQ(p.prior(), nullptr);
  Values est;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Step s = p.step(i, est);
    EXPECT_EQ(s.fixed, i == 2 ? std::vector<Key>{X(2)} : std::vector<Key>{}) << i;
    for (const auto& [k, e] : s.new_values) est.insertEntry(k, e);
  }
  EXPECT_EQ(est.pose(X(2)).x, 7);
  EXPECT_EQ(est.pose(X(2)).theta, 0.5);
  // Pose 3 is composed from the fixed pose's value.
  EXPECT_NEAR(est.pose(X(3)).x, 7 + std::cos(0.5), 1e-12);
  const Step batch = p.batch();
  EXPECT_EQ(batch.fixed, std::vector<Key>{X(2)});
  EXPECT_EQ(batch.new_values.pose(X(2)).y, 8);

  // A fixed landmark leaves the rotation free: the prior stays.
  Graph h = square();
  h.add(std::make_shared<PosePointFactor>(X(1), L(0), Point2(1, 0), Eigen::Matrix2d::Identity()));
  h.fixed = {L(0)};
  const ThesisProtocol q(h);
  EXPECT_NE(q.prior(), nullptr);
  EXPECT_EQ(q.step(1, p.initialValues()).fixed, std::vector<Key>{L(0)});
}

TEST(ThesisProtocol, UnreachablePoseIsAnError) {
  Graph g;
  g.source = "broken.g2o";
  g.add(between(X(0), X(1), Pose2(1, 0, 0)));
  g.add(std::make_shared<PriorFactor>(X(2), Pose2(), kInfo));
  try {
    ThesisProtocol p(g);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.g2o: pose x2 has no factor to an earlier pose"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ThesisProtocol(Graph{}), Error);
}

}  // namespace
}  // namespace hamal
