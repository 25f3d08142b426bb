// The odometry's noise scale against a reference trajectory
// (odometry_calibration.h).
#include "apps/flag/odometry_calibration.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "apps/flag/dead_reckoning_uncertainty.h"
#include "core/error.h"

namespace hamal::flag {

Eigen::Vector3d stepOdometrySigma(const Recording& recording, std::size_t i) {
  const RecordedStep& rec = recording.steps.at(i);
  const Eigen::Vector3d sig =
      rec.odometry_sigma.any()
          ? rec.odometry_sigma
          : odometrySigmas(recording.odom_sigma_x, recording.odom_sigma_y,
                           recording.odom_sigma_theta, std::max(rec.distance, 1e-3));
  return sig.cwiseMax(Eigen::Vector3d(1e-6, 1e-6, 1e-8));
}

std::vector<OdometryConsistency> odometryConsistency(const Recording& recording,
                                                     std::size_t max_window) {
  const std::size_t n = recording.steps.size();
  if (n < 2) throw Error("odometry calibration: the recording has fewer than two poses");
  if (max_window == 0) throw Error("odometry calibration: the largest window must be >= 1");
  std::vector<OdometryConsistency> out;
  for (std::size_t k = 1; k <= max_window && k < n; k *= 2) {
    OdometryConsistency c;
    c.window = k;
    double nees = 0;
    for (std::size_t start = 0; start + k < n; start += std::max<std::size_t>(1, k / 2)) {
      Pose2 pose = recording.steps[start].truth;
      Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
      for (std::size_t j = start + 1; j <= start + k; ++j) {
        P = propagateOdometry(P, pose, recording.steps[j].odometry,
                              stepOdometrySigma(recording, j));
        pose = pose.compose(recording.steps[j].odometry);
      }
      const Pose2& ref = recording.steps[start + k].truth;
      const Eigen::Vector3d e(ref.x - pose.x, ref.y - pose.y, wrapAngle(ref.theta - pose.theta));
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(P);
      if (ldlt.info() != Eigen::Success) continue;
      const double q = e.dot(ldlt.solve(e));
      if (!std::isfinite(q)) continue;
      nees += q;
      ++c.samples;
    }
    if (c.samples == 0) continue;
    c.scale = std::sqrt(nees / (3.0 * double(c.samples)));
    out.push_back(c);
  }
  return out;
}

std::size_t longestCoast(const Recording& recording) {
  std::size_t run = 0, longest = 0;
  for (const RecordedStep& s : recording.steps) {
    run = s.detections.empty() ? run + 1 : 0;
    longest = std::max(longest, run);
  }
  std::size_t k = 1;
  while (k < longest) k *= 2;
  return k;
}

double odometryNoiseScale(const std::vector<OdometryConsistency>& consistency) {
  double scale = 1e-3;
  for (const OdometryConsistency& c : consistency) scale = std::max(scale, c.scale);
  return scale;
}

}  // namespace hamal::flag
