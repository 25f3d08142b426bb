// IcpCovariance: see icp_covariance.h (Censi 2007 closed form).
#include "apps/moss/icp_covariance.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace hamal::moss {

IcpCovariance icpCovariance(const IndexedScan& reference, const Scan& live, const Pose2& t,
                            double gate, double sigma_range) {
  IcpCovariance out;
  const double c = std::cos(t.theta), s = std::sin(t.theta);
  const auto rotate = [&](const Point2& v) {
    return Point2(c * v.x() - s * v.y(), s * v.x() + c * v.y());
  };
  const auto rotateDerivative = [&](const Point2& v) {  // dR/dtheta v
    return Point2(-s * v.x() - c * v.y(), c * v.x() - s * v.y());
  };
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();  // d2J/dx2
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();   // sum_i g_i g_i^T, g_i = d2J/dxdz_i
  for (const Point2& p : live) {
    const double range = p.norm();
    if (!(range > 0)) continue;
    const Point2 u = p / range;
    const Point2 q = rotate(p) + t.t();
    Point2 n;
    double r;
    if (!reference.pointToLine(q, gate, &n, &r)) continue;
    const Eigen::Vector3d a(n.x(), n.y(), n.dot(rotateDerivative(p)));  // dr/dx
    hessian += 2.0 * a * a.transpose();
    hessian(2, 2) += 2.0 * r * n.dot(-rotate(p));  // r d2r/dtheta2
    const double dr_dz = n.dot(rotate(u));
    const Eigen::Vector3d da_dz(0.0, 0.0, n.dot(rotateDerivative(u)));
    const Eigen::Vector3d g = 2.0 * (a * dr_dz + r * da_dz);
    spread += g * g.transpose();
    ++out.pairs;
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(hessian);
  if (out.pairs < 3 || ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      ldlt.vectorD().minCoeff() <= 1e-12 * std::max(1.0, hessian.trace()))
    return out;
  const Eigen::Matrix3d inverse = ldlt.solve(Eigen::Matrix3d::Identity());
  out.covariance = inverse * spread * inverse.transpose() * (sigma_range * sigma_range);
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  out.ok = std::isfinite(out.covariance.sum());
  return out;
}

}  // namespace hamal::moss
