// Information matrices as dataset files give them, and their square roots
// (thesis eq. 2.8: ||e||^2_Omega = e^T Omega e = ||U e||^2 with U^T U = Omega,
// so a factor's whitened residual is U e).
//
// Each file format stores the matrix in its own order and some store the
// covariance instead; the order is named here once so that no reader guesses.
#pragma once

#include <Eigen/Core>

namespace hamal {

class LineTokens;

enum class MatrixLayout {
  // g2o: information, upper triangle row-major: I11 I12 I13 I22 I23 I33.
  kG2oInformation,
  // TORO: information in the order I11 I12 I22 I33 I13 I23.
  kToroInformation,
  // GTSAM's EDGE2/ODOMETRY files: covariance, g2o order c11 c12 c13 c22 c23 c33.
  kG2oCovariance,
};

// Reads a symmetric 3x3 matrix in `layout` and returns the information matrix
// (inverting a covariance). Fails on the line unless it is symmetric positive
// definite.
Eigen::Matrix3d readInformation3(LineTokens& tokens, MatrixLayout layout);
// 2x2: upper triangle a11 a12 a22; kToroInformation is not a 2x2 layout.
Eigen::Matrix2d readInformation2(LineTokens& tokens, MatrixLayout layout);

// True when `m` is symmetric (to 1e-9 relative) and positive definite.
bool isSymmetricPositiveDefinite(const Eigen::MatrixXd& m);
// Upper-triangular U with U^T U = info; `info` must be SPD.
Eigen::MatrixXd sqrtInformation(const Eigen::MatrixXd& info);
// log |info| of an SPD matrix (2 sum log L_ii of its Cholesky factor, which
// neither overflows nor underflows where the determinant itself would).
double logDeterminant(const Eigen::MatrixXd& info);

// Writes the upper triangle of an information matrix row-major (g2o order).
void writeUpperTriangle(std::ostream& os, const Eigen::MatrixXd& m);

}  // namespace hamal
