// InlierDecisions: a capability a Backend may offer besides update(): a
// back-end that is robust by itself (GTSAM's GncOptimizer behind the GTSAM
// plugin, for one) says which of the factors it received it treats as
// outliers, and with what weight. The robust benchmark grades such a
// back-end by its own decisions, as it grades hamal's robust wrappers,
// instead of by a rule applied to its estimate (apps/robust/README.md).
//
// A back-end that offers it derives from both Backend and InlierDecisions; a
// caller finds it with dynamic_cast.
#pragma once

#include <vector>

namespace hamal {

class Factor;

class InlierDecisions {
 public:
  virtual ~InlierDecisions() = default;
  struct Decision {
    const Factor* factor = nullptr;  // as received in a Step (compared by address)
    double weight = 1;               // the factor's final weight in the objective
    bool rejected = false;           // the back-end's verdict: an outlier
    double threshold = 0;            // its inlier threshold c2 in chi2 units (0: none stated)
  };
  // One entry per factor the back-end decided about (those it may reject);
  // factors it always keeps need not be listed.
  virtual std::vector<Decision> inlierDecisions() const = 0;
};

}  // namespace hamal
