// MixtureComponent: the capability of a factor that can be a max-mixture's
// component next to a factor of another kind (factors/max_mixture_factor.h,
// thesis sec. 4.3.3.2). The mixture weighs such components by |Omega_j|^(1/2),
// so it needs log |Omega| of the information each one's whitened residual
// carries (U^T U); nothing else does. A Gaussian factor kind opts in by
// deriving from Factor and MixtureComponent.
#pragma once

#include <limits>

#include "core/factor.h"

namespace hamal {

class MixtureComponent {
 public:
  virtual ~MixtureComponent() = default;

  // log |Omega| of the factor's information.
  virtual double logDetInformation() const = 0;
};

// `factor`'s log |Omega|; NaN ("cannot tell") for a factor that is not a
// MixtureComponent.
inline double logDetInformationOf(const Factor& factor) {
  const auto* c = dynamic_cast<const MixtureComponent*>(&factor);
  return c ? c->logDetInformation() : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace hamal
