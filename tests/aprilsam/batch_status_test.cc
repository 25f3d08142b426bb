// AprilSAM's batch (backends/aprilsam/batch_update.h) takes batch_iterations
// Gauss-Newton steps: when they end with chi2 above the start, the update
// is not_converged, never ok; more steps from the same start are ok.
#include <gtest/gtest.h>

#include <cmath>

#include "backends/aprilsam/aprilsam_backend.h"
#include "backends/aprilsam/aprilsam_options.h"
#include "core/graph.h"
#include "core/metrics.h"
#include "factors/between_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal {
namespace {

// A ring of 40 poses whose odometry headings drift by up to 0.9 rad, closed
// back to its start and across: one Gauss-Newton step from the composed
// odometry overshoots (chi2 13235 -> 13977).
Graph driftingRing() {
  const double turn[39] = {0.8585,  -0.0418, 0.2755,  0.201,  0.4076,  -0.2636, 0.0326,  -0.0684,
                           -0.1653, -0.0961, 0.0033,  0.071,  -0.1149, 0.2837,  -0.0072, -0.8023,
                           0.5143,  0.0395,  -0.0659, 0.2376, 0.2261,  0.1729,  -0.0993, 0.2146,
                           -0.3042, 0.5901,  -0.2226, 0.0951, 0.1628,  0.2228,  0.0831,  0.3019,
                           -0.9333, 0.0869,  0.0702,  -0.012, 0.5773,  -0.1749, 0.0932};
  const int n = 40;
  const double step = 2 * std::sin(M_PI / n);
  const Eigen::Matrix3d info = Eigen::Vector3d(100, 100, 1000).asDiagonal();
  Graph g;
  for (int i = 0; i < n; ++i) g.initial.insert(X(i), Pose2(0, 0, 0));
  for (int i = 0; i + 1 < n; ++i)
    g.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(step, 0, turn[i]), info));
  g.add(std::make_shared<BetweenFactor>(X(n - 1), X(0), Pose2(step, 0, 2 * M_PI / n), info));
  g.add(std::make_shared<BetweenFactor>(X(0), X(n / 2), Pose2(0, 2, 3.14159), info));
  return g;
}

TEST(AprilSamBatch, AStepThatRaisesChi2IsNotConverged) {
  const Graph g = driftingRing();
  const Step batch = ThesisProtocol(g).batch();
  const double start = chi2(g.factors, batch.new_values);

  AprilSamBackend one{aprilsam::AprilSamOptions{}};
  const UpdateResult r = one.update(batch);
  ASSERT_GT(chi2(g.factors, one.estimate()), start) << "the ring no longer overshoots";
  EXPECT_EQ(r.status.code, Status::kNotConverged);
  EXPECT_NE(r.status.message.find("raised the cost"), std::string::npos) << r.status.message;

  aprilsam::AprilSamOptions more;
  more.batch.iterations = 10;
  AprilSamBackend ten{more};
  const UpdateResult s = ten.update(batch);
  EXPECT_LT(chi2(g.factors, ten.estimate()), start);
  EXPECT_TRUE(s.status.ok()) << s.status.message;
}

}  // namespace
}  // namespace hamal
