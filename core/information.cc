// Information matrices: see information.h.
#include "core/information.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <ostream>
#include <sstream>

#include "core/line_tokens.h"

namespace hamal {

bool isSymmetricPositiveDefinite(const Eigen::MatrixXd& m) {
  if (m.rows() != m.cols() || !m.allFinite()) return false;
  const double scale = m.cwiseAbs().maxCoeff();
  if (!((m - m.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale)) return false;
  Eigen::LLT<Eigen::MatrixXd> llt(m);
  if (llt.info() != Eigen::Success) return false;
  // LLT succeeds on some matrices that are singular to working precision.
  const Eigen::VectorXd d = llt.matrixL().toDenseMatrix().diagonal();
  return d.minCoeff() > 1e-12 * std::sqrt(scale);
}

Eigen::MatrixXd sqrtInformation(const Eigen::MatrixXd& info) {
  return Eigen::LLT<Eigen::MatrixXd>(info).matrixU();
}

double logDeterminant(const Eigen::MatrixXd& info) {
  const Eigen::LLT<Eigen::MatrixXd> llt(info);
  return 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
}

namespace {
void checkSpd(const LineTokens& tokens, const Eigen::MatrixXd& m, const char* what) {
  if (!isSymmetricPositiveDefinite(m)) {
    std::ostringstream os;
    os << "the " << what << " matrix is not symmetric positive definite: ["
       << Eigen::MatrixXd(m).format(Eigen::IOFormat(6, 0, ", ", "; ")) << "]";
    tokens.fail(os.str());
  }
}
}  // namespace

Eigen::Matrix3d readInformation3(LineTokens& t, MatrixLayout layout) {
  Eigen::Matrix3d m;
  if (layout == MatrixLayout::kToroInformation) {
    const double i11 = t.number("I11"), i12 = t.number("I12"), i22 = t.number("I22"),
                 i33 = t.number("I33"), i13 = t.number("I13"), i23 = t.number("I23");
    m << i11, i12, i13, i12, i22, i23, i13, i23, i33;
  } else {
    const bool cov = layout == MatrixLayout::kG2oCovariance;
    const double a11 = t.number(cov ? "c11" : "I11"), a12 = t.number(cov ? "c12" : "I12"),
                 a13 = t.number(cov ? "c13" : "I13"), a22 = t.number(cov ? "c22" : "I22"),
                 a23 = t.number(cov ? "c23" : "I23"), a33 = t.number(cov ? "c33" : "I33");
    m << a11, a12, a13, a12, a22, a23, a13, a23, a33;
  }
  const bool cov = layout == MatrixLayout::kG2oCovariance;
  checkSpd(t, m, cov ? "covariance" : "information");
  if (cov) {
    m = Eigen::Matrix3d(m.inverse());
    m = 0.5 * (m + m.transpose()).eval();
  }
  return m;
}

Eigen::Matrix2d readInformation2(LineTokens& t, MatrixLayout layout) {
  if (layout == MatrixLayout::kToroInformation) t.fail("TORO has no 2x2 information layout");
  const bool cov = layout == MatrixLayout::kG2oCovariance;
  const double a11 = t.number(cov ? "c11" : "I11"), a12 = t.number(cov ? "c12" : "I12"),
               a22 = t.number(cov ? "c22" : "I22");
  Eigen::Matrix2d m;
  m << a11, a12, a12, a22;
  checkSpd(t, m, cov ? "covariance" : "information");
  if (cov) m = Eigen::Matrix2d(m.inverse());
  return m;
}

void writeUpperTriangle(std::ostream& os, const Eigen::MatrixXd& m) {
  for (int r = 0; r < m.rows(); ++r)
    for (int c = r; c < m.cols(); ++c) os << ' ' << m(r, c);
}

}  // namespace hamal
