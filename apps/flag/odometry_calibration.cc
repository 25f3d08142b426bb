// The odometry's noise scale against a reference trajectory
// (odometry_calibration.h).
#include "apps/flag/odometry_calibration.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>

#include "apps/flag/dead_reckoning_uncertainty.h"
#include "core/error.h"

namespace hamal::flag {
namespace {
// The least jitter odometryJitter reports (m, rad): an odometry without
// one ties each pose to its chain's this tightly.
constexpr double kJitterFloor = 1e-3;
}  // namespace

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

OdometryJitter odometryJitter(const Recording& recording) {
  const std::size_t n = recording.steps.size();
  if (n < 3) throw Error("odometry jitter: the recording has fewer than three poses");
  // Each step's error in its own frame against the reference.
  std::vector<Eigen::Vector3d> e;
  for (std::size_t j = 1; j < n; ++j) {
    const Pose2 ref = recording.steps[j - 1].truth.between(recording.steps[j].truth);
    const Pose2& odo = recording.steps[j].odometry;
    e.emplace_back(odo.x - ref.x, odo.y - ref.y, wrapAngle(odo.theta - ref.theta));
  }
  // A jitter j_i makes step i's error j_i - j_{i-1}, of variance 2 J^2,
  // taken as the whole of a single step's error (driftScale measures what
  // the chains of steps say beyond it).
  double xy = 0, theta = 0;
  for (const Eigen::Vector3d& v : e) {
    xy += v[0] * v[0] + v[1] * v[1];
    theta += v[2] * v[2];
  }
  const double steps = double(e.size());
  return {std::max(std::sqrt(xy / (4 * steps)), kJitterFloor),
          std::max(std::sqrt(theta / (2 * steps)), kJitterFloor)};
}

namespace {
// The median of the chi-square distribution with 3 degrees of freedom.
constexpr double kChi2Median3 = 2.365973884375338;
}  // namespace

double driftScale(const Recording& recording, std::size_t window, const OdometryJitter& jitter) {
  const std::size_t n = recording.steps.size();
  if (window == 0 || n < window + 1)
    throw Error("odometry drift: the recording needs more poses than the window of " +
                std::to_string(window) + " steps");
  const Eigen::Matrix3d J =
      Eigen::Vector3d(jitter.xy * jitter.xy, jitter.xy * jitter.xy, jitter.theta * jitter.theta)
          .asDiagonal();
  // Mean NEES per degree of freedom with the drift's sigmas times s.
  const auto nees = [&](double s) {
    std::vector<double> qs;
    for (std::size_t start = 0; start + window < n; start += std::max<std::size_t>(1, window / 2)) {
      Pose2 pose = recording.steps[start].truth;
      Eigen::Matrix3d P = J;
      for (std::size_t j = start + 1; j <= start + window; ++j) {
        P = propagateOdometry(P, pose, recording.steps[j].odometry,
                              s * stepOdometrySigma(recording, j));
        pose = pose.compose(recording.steps[j].odometry);
      }
      P += J;
      const Pose2& ref = recording.steps[start + window].truth;
      const Eigen::Vector3d e(ref.x - pose.x, ref.y - pose.y, wrapAngle(ref.theta - pose.theta));
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(P);
      if (ldlt.info() != Eigen::Success) continue;
      const double q = e.dot(ldlt.solve(e));
      if (std::isfinite(q)) qs.push_back(q);
    }
    if (qs.empty()) return 0.0;
    std::nth_element(qs.begin(), qs.begin() + long(qs.size() / 2), qs.end());
    return qs[qs.size() / 2] / kChi2Median3;
  };
  // NEES falls as s grows: bisection on log s.
  double lo = std::log(0.01), hi = std::log(100.0);
  if (nees(std::exp(lo)) <= 1) return 0.01;
  if (nees(std::exp(hi)) >= 1) return 100.0;
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    (nees(std::exp(mid)) > 1 ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

double odometryNoiseScale(const std::vector<OdometryConsistency>& consistency) {
  double scale = 1e-3;
  for (const OdometryConsistency& c : consistency) scale = std::max(scale, c.scale);
  return scale;
}

}  // namespace hamal::flag
