// IcpCovariance: Censi's closed-form covariance of an ICP estimate (Censi
// 2007, "An accurate closed-form estimate of ICP's covariance"), for the
// point-to-line matcher whose results become L2G factors (thesis sec.
// 5.3.2): the information of an L2G factor, as an alternative to the
// Gauss-Newton Hessian (ScanMatcherConfig::information).
//
// The estimate x = (x, y, theta) minimises J(x, z) = sum_i r_i^2 with
// r_i = n_i . (R(theta) p_i + t - m_i), p_i = z_i u_i the live point of beam
// i (range z_i, unit direction u_i), m_i and n_i the paired reference point
// and its normal. The implicit function theorem gives dx/dz =
// -(d2J/dx2)^-1 d2J/dxdz, so
//
//   cov(x) = (d2J/dx2)^-1 (d2J/dxdz) sigma_d^2 (d2J/dxdz)^T (d2J/dx2)^-1,
//
// with the live ranges the noisy measurements (the reference scan is the
// map's, fixed) and the pairs those of the converged iteration. Unlike
// sigma^2 (J^T J)^-1 it weighs each pair by how much its range error moves
// its residual (n . R u_i: a beam grazing a wall barely does), and keeps
// the second-order term r_i d2r_i/dx2.
#pragma once

#include <Eigen/Core>

#include "apps/moss/laser.h"
#include "apps/moss/scan_matcher.h"
#include "core/pose2.h"

namespace hamal::moss {

struct IcpCovariance {
  bool ok = false;  // enough pairs and a positive definite d2J/dx2
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  int pairs = 0;
};

// At the solution `t` (the live pose in the reference frame), pairing each
// live point with its nearest reference point within `gate` as the matcher
// does; `sigma_range` is the live ranges' standard deviation.
IcpCovariance icpCovariance(const IndexedScan& reference, const Scan& live, const Pose2& t,
                            double gate, double sigma_range);

}  // namespace hamal::moss
