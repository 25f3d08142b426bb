// DynamicCovarianceScaling: see dynamic_covariance_scaling.h.
#include "backends/robust/dynamic_covariance_scaling.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace hamal::robust {

DynamicCovarianceScaling::DynamicCovarianceScaling(double phi) : phi_(phi) {
  if (!(phi > 0) || !std::isfinite(phi))
    throw Error("dcs: Phi must be a finite number > 0, not " + std::to_string(phi));
}

double DynamicCovarianceScaling::weight(double s) const {
  if (s <= phi_) return 1;
  const double scale = 2 * phi_ / (phi_ + s);
  return scale >= 1 ? 1 : scale * scale;
}

void DynamicCovarianceScaling::Evaluate(double s, double rho[3]) const {
  if (s <= phi_) {
    rho[0] = s;
    rho[1] = 1;
    rho[2] = 0;
    return;
  }
  const double d = phi_ + s;
  rho[0] = 3 * phi_ - 4 * phi_ * phi_ / d;
  rho[1] = 4 * phi_ * phi_ / (d * d);
  rho[2] = -8 * phi_ * phi_ / (d * d * d);
}

}  // namespace hamal::robust
