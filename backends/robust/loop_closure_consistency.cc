// LoopClosureConsistency: the cycle test of two loop closures
// (loop_closure_consistency.h).
#include "backends/robust/loop_closure_consistency.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/relative_pose_measurement.h"

namespace hamal::robust {

LoopClosure loopClosureOf(const Factor& factor) {
  const auto name = [&factor] {
    std::string keys;
    for (Key k : factor.keys()) keys += " " + k.str();
    return "factor " + factor.tag() + keys;
  };
  const auto rel = relativePoseOf(factor);
  if (!rel) throw Error("pairwise consistency: " + name() + " gives no relative-pose measurement");
  if (rel->from.kind() != kPoseKind || rel->to.kind() != kPoseKind)
    throw Error("pairwise consistency: " + name() + " does not join two poses");
  Eigen::LDLT<Eigen::Matrix3d> ldlt(rel->information);
  if (!rel->information.allFinite() || ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      ldlt.vectorD().minCoeff() <= 0)
    throw Error("pairwise consistency: " + name() +
                " has information that is not positive definite");
  LoopClosure c;
  c.from = rel->from.index();
  c.to = rel->to.index();
  c.measurement = {rel->measurement, rel->information.inverse()};
  const Eigen::Matrix3d a = additiveFromLeft(-rel->measurement.t());
  c.left_covariance = a * c.measurement.covariance * a.transpose();
  return c;
}

LoopClosure reversed(const LoopClosure& b) {
  LoopClosure r;
  r.from = b.to;
  r.to = b.from;
  r.measurement = inverse(b.measurement);
  const Eigen::Matrix3d a = additiveFromLeft(-r.measurement.pose.t());
  r.left_covariance = a * r.measurement.covariance * a.transpose();
  return r;
}

std::optional<CycleError> cycleThroughOdometry(const OdometryChain& chain, const LoopClosure& a,
                                               const LoopClosure& b) {
  if (chain.joined(a.from, b.from) && chain.joined(b.to, a.to)) return cycleError(chain, a, b);
  if (chain.joined(a.from, b.to) && chain.joined(b.from, a.to))
    return cycleError(chain, a, reversed(b));
  return std::nullopt;
}

CycleError cycleError(const OdometryChain& chain, const LoopClosure& a, const LoopClosure& b) {
  const std::uint64_t i = a.from, j = a.to, k = b.from, l = b.to;
  const Eigen::Matrix3d s11 = chain.noiseCovariance(i, k);
  const Eigen::Matrix3d s22 = chain.noiseCovariance(l, j);
  const Eigen::Matrix3d s12 = chain.noiseCrossCovariance(i, k, l, j);
  const Pose2 &pi = chain.pose(i), &pk = chain.pose(k), &pl = chain.pose(l), &pj = chain.pose(j);
  const Pose2 c_ik = pi.between(pk);
  const Pose2 c_ik_zb = c_ik.compose(b.measurement.pose);
  const Pose2 t = c_ik_zb.compose(pl.between(pj)).compose(a.measurement.pose.inverse());
  const Eigen::Matrix3d m1 = adjoint(pi.inverse());
  const Eigen::Matrix3d m2 = adjoint(c_ik_zb.compose(pl.inverse()));
  const Eigen::Matrix3d ad_b = adjoint(c_ik), ad_a = adjoint(t);
  const Eigen::Matrix3d cross = m1 * s12 * m2.transpose();
  CycleError out;
  out.error = Eigen::Vector3d(t.x, t.y, t.theta);
  out.covariance = m1 * s11 * m1.transpose() + m2 * s22 * m2.transpose() + cross +
                   cross.transpose() + ad_b * b.left_covariance * ad_b.transpose() +
                   ad_a * a.left_covariance * ad_a.transpose();
  Eigen::LDLT<Eigen::Matrix3d> ldlt(out.covariance);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.vectorD().minCoeff() > 0)) {
    out.mahalanobis2 = std::numeric_limits<double>::infinity();
    return out;
  }
  out.mahalanobis2 = out.error.dot(ldlt.solve(out.error));
  if (!std::isfinite(out.mahalanobis2)) out.mahalanobis2 = std::numeric_limits<double>::infinity();
  return out;
}

}  // namespace hamal::robust
