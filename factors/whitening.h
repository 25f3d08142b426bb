// whitening(): the U of a factor's whitened residual U e, U^T U = Omega
// (thesis eq. 2.8), for factors built in code. Readers check the matrix
// against the file line; a factor built in code gets the same check here,
// so a wrong matrix is an Error naming the factor instead of NaN residuals.
#pragma once

#include <Eigen/Core>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/information.h"

namespace hamal {

inline Eigen::MatrixXd whitening(const Eigen::MatrixXd& information, const char* factor) {
  if (!isSymmetricPositiveDefinite(information)) {
    std::ostringstream os;
    os << factor << ": the information matrix is not symmetric positive definite: ["
       << information.format(Eigen::IOFormat(6, 0, ", ", "; ")) << "]";
    throw Error(os.str());
  }
  return sqrtInformation(information);
}

}  // namespace hamal
