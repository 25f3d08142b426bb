// The association gate that grows with the pose's uncertainty
// (apps/flag/dead_reckoning_uncertainty.h, nearest_neighbour_association.h):
// the propagated covariance matches sampled odometry, the Kalman update
// matches the information form, the gate is the thesis' fixed 50 cm when the
// pose is certain and widens along the uncertainty, a robot that coasted
// past the fixed gate associates again with it, and the run counts which
// stage lost a right association (the gate: none or another landmark; the
// max-mixture: a right factor switched off), and with the corner's walls as
// a descriptor the gate takes the right one of two landmarks within it.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "apps/flag/dead_reckoning_uncertainty.h"
#include "apps/flag/flag_run.h"
#include "apps/flag/nearest_neighbour_association.h"
#include "backends/builtins.h"

namespace hamal::flag {
namespace {

TEST(DeadReckoningUncertainty, PropagationMatchesSampledOdometry) {
  const Pose2 start(1.0, -2.0, 0.7);
  const Pose2 odo(0.5, 0.02, 0.01);
  const Eigen::Vector3d sigma(0.05, 0.03, 0.02);
  constexpr int kSteps = 20, kSamples = 20000;
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  Pose2 mean = start;
  for (int k = 0; k < kSteps; ++k) {
    P = propagateOdometry(P, mean, odo, sigma);
    mean = mean.compose(odo);
  }
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  Eigen::Matrix3d sampled = Eigen::Matrix3d::Zero();
  for (int s = 0; s < kSamples; ++s) {
    Pose2 p = start;
    for (int k = 0; k < kSteps; ++k)
      p = p.compose(Pose2(odo.x + sigma[0] * n01(rng), odo.y + sigma[1] * n01(rng),
                          odo.theta + sigma[2] * n01(rng)));
    const Eigen::Vector3d e(p.x - mean.x, p.y - mean.y, wrapAngle(p.theta - mean.theta));
    sampled += e * e.transpose() / kSamples;
  }
  // First order is good to a few per cent at these sigmas; sampling adds ~2%.
  for (int r = 0; r < 3; ++r) EXPECT_NEAR(sampled(r, r), P(r, r), 0.08 * P(r, r)) << "row " << r;
  EXPECT_NEAR(sampled(0, 1), P(0, 1), 0.08 * std::sqrt(P(0, 0) * P(1, 1)));
}

TEST(DeadReckoningUncertainty, KalmanUpdateIsTheInformationForm) {
  Eigen::Matrix3d P;
  P << 0.5, 0.1, 0.02, 0.1, 0.3, -0.01, 0.02, -0.01, 0.01;
  const Pose2 pose(2.0, 1.0, 0.3);
  const Point2 landmark(7.0, 4.0);
  const double ls = 0.2, rs = 0.1, bs = 0.02;
  const Eigen::Matrix3d updated = updateWithRangeBearing(P, pose, landmark, ls, rs, bs);
  // Independently: H by central differences, R with the landmark's share.
  const auto h = [&](const Eigen::Vector3d& x, const Point2& l) {
    const Point2 d = l - Point2(x[0], x[1]);
    return Eigen::Vector2d(d.norm(), std::atan2(d.y(), d.x()) - x[2]);
  };
  const Eigen::Vector3d x0(pose.x, pose.y, pose.theta);
  Eigen::Matrix<double, 2, 3> H;
  Eigen::Matrix2d Hl;
  for (int c = 0; c < 3; ++c) {
    Eigen::Vector3d dx = Eigen::Vector3d::Zero();
    dx[c] = 1e-6;
    H.col(c) = (h(x0 + dx, landmark) - h(x0 - dx, landmark)) / 2e-6;
  }
  for (int c = 0; c < 2; ++c) {
    Point2 dl = Point2::Zero();
    dl[c] = 1e-6;
    Hl.col(c) = (h(x0, landmark + dl) - h(x0, landmark - dl)) / 2e-6;
  }
  const Eigen::Matrix2d R = Eigen::Vector2d(rs * rs, bs * bs).asDiagonal().toDenseMatrix() +
                            ls * ls * Hl * Hl.transpose();
  const Eigen::Matrix3d expected = (P.inverse() + H.transpose() * R.inverse() * H).inverse();
  EXPECT_LT((updated - expected).norm(), 1e-6 * expected.norm());
  EXPECT_LT(updated.trace(), P.trace());
}

TEST(NearestNeighbourAssociation, FixedGateWhenThePoseIsCertain) {
  const NearestNeighbourAssociation nn(0.5, 3.0);
  const std::vector<Point2> landmarks = {{0.0, 0.0}, {3.0, 0.0}};
  EXPECT_EQ(nn.associate({0.49, 0.0}, landmarks), std::optional<std::size_t>(0));
  EXPECT_FALSE(nn.associate({0.51, 0.0}, landmarks).has_value());
  EXPECT_FALSE(nn.associate({0.0, -0.51}, landmarks).has_value());
  EXPECT_EQ(nn.associate({2.7, 0.0}, landmarks), std::optional<std::size_t>(1));
}

TEST(NearestNeighbourAssociation, GateGrowsAlongThePoseUncertainty) {
  const NearestNeighbourAssociation nn(0.5, 3.0);
  const std::vector<Point2> landmarks = {{0.0, 0.0}};
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  cov(1, 1) = 0.5 * 0.5;  // lateral: a heading error seen at range
  EXPECT_EQ(nn.associate({0.0, 1.4}, landmarks, cov), std::optional<std::size_t>(0));
  EXPECT_FALSE(nn.associate({0.0, 1.7}, landmarks, cov).has_value());
  EXPECT_FALSE(nn.associate({0.6, 0.0}, landmarks, cov).has_value());  // not along x
  // The nearest in Mahalanobis distance, not in metres.
  const std::vector<Point2> two = {{0.0, 1.0}, {0.45, 0.0}};
  EXPECT_EQ(nn.associate({0.0, 0.0}, two, cov), std::optional<std::size_t>(0));
}

// A coasting run: 30 m of driving with odometry 2.5% long, then a corner at
// (32, 1) seen from poses 60-64, where dead reckoning is 0.75-0.8 m ahead.
Recording coastingRun(const Point2& corner) {
  Recording rec;
  rec.odom_sigma_x = 0.10;
  rec.odom_sigma_y = 0.05;
  rec.odom_sigma_theta = 0.1 * 3.14159265358979323846 / 180;
  for (int i = 0; i <= 64; ++i) {
    RecordedStep s;
    s.truth = Pose2(0.5 * i, 0.0, 0.0);
    s.time = 0.25 * i;
    if (i > 0) {
      s.distance = 0.5;
      s.odometry = Pose2(0.5 * 1.025, 0.0, 0.0);
    }
    if (i >= 60) {
      const Point2 z = s.truth.transformTo(corner);
      s.detections.push_back(
          {z.norm(), std::atan2(z.y(), z.x()), 0.05, 0.01, {Source::kCorner, 0}});
    }
    rec.steps.push_back(s);
  }
  return rec;
}

// The prediction is 0.75 m off, past the fixed 50 cm gate, but within 3
// sigma of the propagated odometry noise (0.1 m per sqrt(m): 0.55 m along x).
TEST(FlagLocalizer, PoseGateAssociatesAfterCoastingPastTheFixedGate) {
  const Point2 landmark(32.0, 1.0);
  const Recording rec = coastingRun(landmark);
  const std::vector<LandmarkLabel> labels = {{0, landmark}};
  Registry registry;
  registerBuiltins(registry);
  FlagOptions o;
  o.consistency.check = false;
  o.max_mixture.enabled = false;
  o.association.pose_gate = false;
  const FlagRun fixed = runFlag(labels, rec, o, registry);
  EXPECT_EQ(fixed.stats.associated, 0u);
  o.association.pose_gate = true;
  const FlagRun grown = runFlag(labels, rec, o, registry);
  ASSERT_TRUE(grown.ok) << grown.status;
  EXPECT_EQ(grown.stats.associated, 5u);
  EXPECT_EQ(grown.stats.precision(), 1.0);
  EXPECT_LT(grown.flag.last_position, 0.3);
  EXPECT_GT(fixed.flag.last_position, 0.6);
}

TEST(FlagLocalizer, CountsTheRightAssociationsTheGateLost) {
  const Point2 corner(32.0, 1.0);
  const Recording rec = coastingRun(corner);
  Registry registry;
  registerBuiltins(registry);
  FlagOptions o;
  o.consistency.check = false;
  o.association.pose_gate = false;  // the fixed 0.5 m gate: the corner falls outside it
  const FlagRun alone = runFlag({{0, corner}}, rec, o, registry);
  EXPECT_EQ(alone.stats.corner_detections, 5u);
  EXPECT_EQ(alone.stats.gate_lost.outside, 5u);
  EXPECT_EQ(alone.stats.gate_lost.other_landmark, 0u);
  // A second landmark where dead reckoning puts the corner takes it.
  const FlagRun aliased = runFlag({{0, corner}, {1, corner + Point2(0.8, 0.0)}}, rec, o, registry);
  EXPECT_EQ(aliased.stats.gate_lost.outside, 0u);
  EXPECT_EQ(aliased.stats.gate_lost.other_landmark, 5u);
  EXPECT_EQ(aliased.stats.accepted, 5u);
  EXPECT_EQ(aliased.stats.accepted_correct, 0u);
  EXPECT_EQ(aliased.factors.null_active_right, 0u);
  // Known association keeps them; with the corner's label 2 m off and held
  // fixed, the max-mixture switches off right factors, and says so.
  o.association.known = true;
  o.landmarks.fixed = true;
  const FlagRun known = runFlag({{0, corner + Point2(2.0, 0.0)}}, rec, o, registry);
  EXPECT_EQ(known.stats.gate_lost.outside + known.stats.gate_lost.other_landmark, 0u);
  EXPECT_EQ(known.stats.accepted_correct, 5u);
  EXPECT_GT(known.factors.null_active, 0u);
  EXPECT_EQ(known.factors.null_active_right, known.factors.null_active);
}

// The corner's walls as a descriptor (FlagOptions::association.wall_sigma):
// two landmarks within the gate, the right one (walls west and north), and
// one 0.8 m on where dead reckoning puts the corner, its walls east and
// north. Nearest neighbour takes the wrong one; the walls the right one.
TEST(FlagLocalizer, TheWallsPickTheRightOfTwoLandmarksWithinTheGate) {
  constexpr double kPi = 3.14159265358979323846;
  const Point2 corner(32.0, 1.0);
  Recording rec = coastingRun(corner);
  for (RecordedStep& s : rec.steps)
    for (Detection& d : s.detections) d.walls = {kPi, kPi / 2};  // heading 0: as in the world
  std::vector<LandmarkLabel> labels = {{0, corner, {kPi, kPi / 2}},
                                       {1, corner + Point2(0.8, 0.0), {0, kPi / 2}}};
  Registry registry;
  registerBuiltins(registry);
  FlagOptions o;
  o.consistency.check = false;
  const FlagRun nearest = runFlag(labels, rec, o, registry);
  EXPECT_EQ(nearest.stats.gate_lost.other_landmark, 5u);
  EXPECT_EQ(nearest.stats.accepted_correct, 0u);
  o.association.wall_sigma = 2 * kPi / 180;
  const FlagRun walls = runFlag(labels, rec, o, registry);
  ASSERT_TRUE(walls.ok) << walls.status;
  EXPECT_EQ(walls.stats.gate_lost.other_landmark, 0u);
  EXPECT_EQ(walls.stats.gate_lost.walls, 0u);
  EXPECT_EQ(walls.stats.accepted_correct, 5u);
  EXPECT_LT(walls.flag.last_position, 0.3);
  // The right landmark shaped otherwise is refused, and counted so.
  labels[0].walls = {0, -kPi / 2};
  const FlagRun refused = runFlag(labels, rec, o, registry);
  EXPECT_EQ(refused.stats.gate_lost.walls, 5u);
  EXPECT_EQ(refused.stats.accepted_correct, 0u);
}

}  // namespace
}  // namespace hamal::flag
