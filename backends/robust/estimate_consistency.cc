// EstimateConsistency: a loop closure against the estimate and its
// covariance (estimate_consistency.h).
#include "backends/robust/estimate_consistency.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <memory>

#include "core/key.h"
#include "core/relative_pose_measurement.h"

namespace hamal::robust {

UncertainPose compose(const UncertainPose& a, const UncertainPose& b) {
  const double c = std::cos(a.pose.theta), s = std::sin(a.pose.theta);
  Eigen::Matrix2d r;
  r << c, -s, s, c;
  const Eigen::Vector2d rt = r * b.pose.t();
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  f(0, 2) = -rt.y();  // J R_a t_b, J = [[0, -1], [1, 0]]
  f(1, 2) = rt.x();
  Eigen::Matrix3d g = Eigen::Matrix3d::Identity();
  g.topLeftCorner<2, 2>() = r;
  UncertainPose out;
  out.pose = a.pose.compose(b.pose);
  out.covariance = f * a.covariance * f.transpose() + g * b.covariance * g.transpose();
  return out;
}

std::optional<double> estimateConsistency(const Backend& backend, FactorWeights& weights,
                                          const OdometryChain& chain, const Factor& factor) {
  const LoopClosure closure = loopClosureOf(factor);
  // From the earlier pose to the later one.
  const bool forward = closure.from <= closure.to;
  const std::uint64_t i = forward ? closure.from : closure.to;
  const std::uint64_t j = forward ? closure.to : closure.from;
  const UncertainPose z = forward ? closure.measurement : inverse(closure.measurement);
  const Values& estimate = backend.estimate();
  if (!estimate.contains(X(i))) return std::nullopt;
  std::uint64_t m = j;
  while (m > i && !estimate.contains(X(m))) --m;
  UncertainPose held;  // x_i^-1 x_m from the estimate
  held.pose = estimate.pose(X(i)).between(estimate.pose(X(m)));
  if (m > i) {
    const RelativePoseMeasurement* measures = asRelativePoseMeasurement(factor);
    const std::shared_ptr<Factor> probe =
        measures
            ? measures->relativePoseFactor({X(i), X(m), held.pose, Eigen::Matrix3d::Identity()})
            : nullptr;
    Eigen::MatrixXd g;
    if (!probe || !weights.residualCovariance({probe.get()}, &g) || g.rows() != 3 ||
        g.cols() != 3 || !g.allFinite())
      return std::nullopt;
    held.covariance = 0.5 * (g + g.transpose());
  }
  if (m < j && !chain.joined(m, j)) return std::nullopt;  // a gap after the map
  const UncertainPose p = m < j ? compose(held, chain.between(m, j)) : held;
  const Eigen::Vector3d e(p.pose.x - z.pose.x, p.pose.y - z.pose.y,
                          wrapAngle(p.pose.theta - z.pose.theta));
  const Eigen::Matrix3d cov = p.covariance + z.covariance;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(cov);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.vectorD().minCoeff() > 0))
    return std::nullopt;
  const double d2 = e.dot(ldlt.solve(e));
  if (!std::isfinite(d2)) return std::nullopt;
  return d2;
}

}  // namespace hamal::robust
