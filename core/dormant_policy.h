// DormantPolicy: the one rule by which a back-end keeps a factor with modes
// out of its linear system while its active mode carries almost no
// information (a max-mixture's null hypothesis, the robust model of thesis
// sec. 4.3.3.2). AprilSAM and cholesky both read it, so they keep the same
// factors out and offer the same option with the same default.
//
// A factor at mode m is dormant when the scale is > 0 and
// MultiModal::modeInformationScale(m) is below it; m = -1 (no mode can be
// evaluated) never is. Its gradient and Hessian are that information scale
// times the nominal's, so leaving it out moves the estimate by that fraction
// of what the nominal factor would pull; its cost still counts. Where the
// mode is read (the linearisation point or the current estimate) is the
// back-end's business.
#pragma once

#include <string>

#include "core/multi_modal.h"
#include "core/options.h"

namespace hamal {

class DormantPolicy {
 public:
  static constexpr double kDefaultScale = 1e-5;

  // Throws hamal::Error naming the option dormant_scale (after `who`) for a
  // scale outside [0, 1).
  explicit DormantPolicy(double scale = kDefaultScale, const std::string& who = "dormant policy");
  // The option "dormant_scale": its default and meaning.
  static OptionSpec optionSpec();
  // Reads "dormant_scale" from `options` (its owner, or `who` when it has none, in
  // the error).
  static DormantPolicy fromOptions(const Options& options, const std::string& who);

  double scale() const { return scale_; }
  // False for every factor (dormant_scale=0: everything stays in the system).
  bool enabled() const { return scale_ > 0; }
  // Whether `factor` at mode `mode` is left out.
  bool dormant(const MultiModal& factor, int mode) const {
    return scale_ > 0 && mode >= 0 && factor.modeInformationScale(mode) < scale_;
  }
  // The same at the mode `factor` has at `parameters` (one pointer per key);
  // the mode is not evaluated when the policy is off.
  bool dormantAt(const MultiModal& factor, const double* const* parameters) const {
    return scale_ > 0 && dormant(factor, factor.mode(parameters));
  }

 private:
  double scale_;
};

}  // namespace hamal
