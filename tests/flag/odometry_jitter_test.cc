// An odometry whose error is a jitter on each pose plus a drift
// (apps/flag/odometry_calibration.h's odometryJitter and driftScale,
// FlagOptions::odometry.jitter_*): the jitter is told apart from a drift,
// the drift's scale is measured with it, and FLAG's graph with the
// odometry's own chain keeps a landmark fix at a jittered pose from
// turning every later pose; and the gate's bound (FlagOptions::
// association.max_gate_sigma) keeps a far corner the map lacks out of the gate.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "apps/flag/flag_run.h"
#include "apps/flag/odometry_calibration.h"
#include "backends/builtins.h"
#include "core/error.h"

namespace hamal::flag {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

// A straight run of n poses 0.5 m apart; the odometry's poses are the truth
// with a jitter of sigma (jitter_xy, jitter_theta) on each pose plus a drift
// random walk of (drift_xy, drift_theta) per step; stated per step as
// `stated` (x, y, theta).
Recording jitteredRun(std::size_t n, double jitter_xy, double jitter_theta, double drift_xy,
                      double drift_theta, const Eigen::Vector3d& stated, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  Recording rec;
  Pose2 drifted;  // the drift's chain
  Pose2 previous_odometry;
  for (std::size_t i = 0; i < n; ++i) {
    RecordedStep s;
    s.truth = Pose2(0.5 * double(i), 0.0, 0.0);
    if (i > 0)
      drifted = drifted.compose(
          Pose2(0.5 + drift_xy * n01(rng), drift_xy * n01(rng), drift_theta * n01(rng)));
    const Pose2 odometry =
        drifted.compose(Pose2(jitter_xy * n01(rng), jitter_xy * n01(rng), jitter_theta * n01(rng)));
    if (i > 0) {
      s.odometry = previous_odometry.between(odometry);
      s.distance = 0.5;
      s.odometry_sigma = stated;
    }
    previous_odometry = odometry;
    rec.steps.push_back(s);
  }
  return rec;
}

TEST(OdometryJitter, TheJitterIsASingleStepsErrorOverTheSquareRootOfTwo) {
  const Eigen::Vector3d stated(0.01, 0.01, 0.5 * kDeg);
  // A jitter of 3 cm and 2 degrees, no drift: found within sampling error
  // (2000 steps).
  const OdometryJitter j = odometryJitter(jitteredRun(2000, 0.03, 2 * kDeg, 0, 0, stated, 1));
  EXPECT_NEAR(j.xy, 0.03, 0.003);
  EXPECT_NEAR(j.theta, 2 * kDeg, 0.2 * kDeg);
  // A drift alone of 3 cm and 2 degrees a step is taken for a jitter of
  // 1/sqrt(2) of it (driftScale tells them apart: below).
  const OdometryJitter d = odometryJitter(jitteredRun(2000, 0, 0, 0.03, 2 * kDeg, stated, 2));
  EXPECT_NEAR(d.xy, 0.03 / std::sqrt(2.0), 0.003);
  EXPECT_NEAR(d.theta, 2 * kDeg / std::sqrt(2.0), 0.2 * kDeg);
  // An exact odometry: the floor.
  const OdometryJitter none = odometryJitter(jitteredRun(20, 0, 0, 0, 0, stated, 1));
  EXPECT_EQ(none.xy, 1e-3);
  EXPECT_EQ(none.theta, 1e-3);
  EXPECT_THROW(odometryJitter(jitteredRun(2, 0, 0, 0, 0, stated, 1)), Error);
}

TEST(OdometryJitter, TheDriftsScaleIsMeasuredBesideTheJitter) {
  // A drift of 1 cm and 0.1 degree a step stated as such, under a jitter of
  // 3 cm and 2 degrees: with the jitter known the drift's sigmas are about
  // right (scale near 1); a drift model alone (odometryConsistency at
  // window 1) takes the jitter for a drift 4-20 times the stated one.
  const Eigen::Vector3d stated(0.01, 0.01, 0.1 * kDeg);
  const Recording rec = jitteredRun(3000, 0.03, 2 * kDeg, 0.01, 0.1 * kDeg, stated, 3);
  const OdometryJitter j = odometryJitter(rec);
  const double s = driftScale(rec, 32, j);
  EXPECT_GT(s, 0.6);
  EXPECT_LT(s, 1.6);
  // A drift alone, stated as it is: the chains of 32 steps outgrow the
  // jitter it was taken for, and the drift's scale stays near 1.
  const Recording drift = jitteredRun(3000, 0, 0, 0.01, 0.1 * kDeg, stated, 5);
  const double sd = driftScale(drift, 32, odometryJitter(drift));
  EXPECT_GT(sd, 0.6);
  EXPECT_LT(sd, 1.3);
  EXPECT_GT(odometryConsistency(rec, 1).front().scale, 4.0);
  // Without drift the jitter explains most of the errors alone.
  const Recording still = jitteredRun(3000, 0.03, 2 * kDeg, 0, 0, stated, 4);
  EXPECT_LT(driftScale(still, 32, odometryJitter(still)), 0.5);
  EXPECT_THROW(driftScale(rec, 0, j), Error);
  EXPECT_THROW(driftScale(jitteredRun(8, 0, 0, 0, 0, stated, 1), 8, j), Error);
}

// Two landmarks seen from poses 4-10; pose 10's odometry heading is 5
// degrees off (a jitter: pose 11's is right again), then 50 poses without
// a landmark.
Recording fixAtAJitteredPose(const Eigen::Vector3d& stated) {
  const Point2 a(5.0, 2.0), b(5.0, -2.0);
  Recording rec;
  Pose2 previous_odometry;
  for (int i = 0; i <= 60; ++i) {
    RecordedStep s;
    s.truth = Pose2(0.5 * i, 0.0, 0.0);
    const Pose2 odometry = i == 10 ? Pose2(s.truth.x, 0.0, 5 * kDeg) : s.truth;
    if (i > 0) {
      s.odometry = previous_odometry.between(odometry);
      s.distance = 0.5;
      s.odometry_sigma = stated;
    }
    previous_odometry = odometry;
    if (i >= 4 && i <= 10)
      for (std::uint64_t id : {0u, 1u}) {
        const Point2 z = s.truth.transformTo(id == 0 ? a : b);
        s.detections.push_back(
            {z.norm(), std::atan2(z.y(), z.x()), 0.02, 0.2 * kDeg, {Source::kCorner, id}});
      }
    rec.steps.push_back(s);
  }
  return rec;
}

TEST(OdometryJitter, ALandmarkFixAtAJitteredPoseDoesNotTurnTheLaterPoses) {
  Registry registry;
  registerBuiltins(registry);
  const std::vector<LandmarkLabel> labels = {{0, Point2(5.0, 2.0)}, {1, Point2(5.0, -2.0)}};
  FlagOptions o;
  o.association.known = true;
  o.consistency.check = false;
  o.max_mixture.enabled = false;
  o.landmarks.sigma = 0.01;
  // The drift model a jittery odometry gets fitted (3 degrees a step): the
  // landmarks pin pose 10 at the truth and the step out of it, 5 degrees
  // off, turns every later pose.
  const FlagRun drift =
      runFlag(labels, fixAtAJitteredPose(Eigen::Vector3d(0.03, 0.03, 3 * kDeg)), o, registry);
  ASSERT_TRUE(drift.ok) << drift.status;
  EXPECT_GT(drift.flag.last_position, 1.5);
  // Jitter and drift: the chain of odometry poses keeps its heading, pose
  // 10 alone leaves it by its jitter.
  o.odometry.jitter_xy = 0.03;
  o.odometry.jitter_theta = 3 * kDeg;
  const FlagRun jitter =
      runFlag(labels, fixAtAJitteredPose(Eigen::Vector3d(0.005, 0.005, 0.05 * kDeg)), o, registry);
  ASSERT_TRUE(jitter.ok) << jitter.status;
  EXPECT_LT(jitter.flag.last_position, 0.2);
  EXPECT_LT(std::abs(jitter.online.back().theta), 1 * kDeg);
  // Both sigmas or none.
  o.odometry.jitter_theta = 0;
  EXPECT_THROW(o.validate(), Error);
}

TEST(FlagLocalizer, TheGatesBoundKeepsAFarCornerOut) {
  // After 40 poses on a stated odometry of 5 cm and 1 degree a step the
  // gate's sigma is metres; a detection 2 m from the only landmark (a
  // corner the map lacks) is within it, not within a gate of 0.3 m sigma.
  Recording rec;
  const Point2 landmark(22.0, 2.0);
  for (int i = 0; i <= 40; ++i) {
    RecordedStep s;
    s.truth = Pose2(0.5 * i, 0.0, 0.0);
    if (i > 0) {
      s.odometry = Pose2(0.5, 0.0, 0.0);
      s.distance = 0.5;
      s.odometry_sigma = Eigen::Vector3d(0.05, 0.05, 1 * kDeg);
    }
    if (i == 40) {
      const Point2 z = s.truth.transformTo(landmark + Point2(0.0, 2.0));
      s.detections.push_back({z.norm(), std::atan2(z.y(), z.x()), 0.05, 0.5 * kDeg, {}});
    }
    rec.steps.push_back(s);
  }
  Registry registry;
  registerBuiltins(registry);
  FlagOptions o;
  o.consistency.check = false;
  const FlagRun open = runFlag({{0, landmark}}, rec, o, registry);
  EXPECT_EQ(open.stats.associated, 1u);
  o.association.max_gate_sigma = 0.3;
  const FlagRun bounded = runFlag({{0, landmark}}, rec, o, registry);
  EXPECT_EQ(bounded.stats.associated, 0u);
  o.association.max_gate_sigma = -1;
  EXPECT_THROW(o.validate(), Error);
}

}  // namespace
}  // namespace hamal::flag
