// DormantPolicy: see dormant_policy.h.
#include "core/dormant_policy.h"

#include "core/error.h"

namespace hamal {

DormantPolicy::DormantPolicy(double scale, const std::string& who) : scale_(scale) {
  if (!(scale >= 0 && scale < 1))
    throw Error(who + ": option dormant_scale must be a number in [0, 1)");
}

OptionSpec DormantPolicy::optionSpec() {
  return {"dormant_scale", "1e-5",
          "a factor with modes whose active mode carries less information than this fraction "
          "of its nominal one (a max-mixture's null hypothesis, e.g. 1e-12) is kept out of the "
          "linear system and the ordering (no fill) while that mode is active: aprilsam reads "
          "the mode at the factor's linearisation point until its switch hook finds another, "
          "cholesky at the current estimate. Its cost still counts; the dropped gradient is "
          "that fraction of the nominal's. 0 keeps every factor in the system"};
}

DormantPolicy DormantPolicy::fromOptions(const Options& options, const std::string& who) {
  return DormantPolicy(options.getDouble("dormant_scale"),
                       options.owner().empty() ? who : options.owner());
}

}  // namespace hamal
