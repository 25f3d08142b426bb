// MultiModal: the capability of a factor whose residual depends on a
// discrete choice made where it is evaluated (a max-mixture's active
// component, the robust model of thesis sec. 4.3.3.2). A factor kind opts in
// by deriving from Factor and MultiModal; every other factor has no modes.
//
// A back-end that keeps linearisations from old points (AprilSAM's R)
// compares the mode at a factor's linearisation point with the mode at its
// current estimate and relinearises the factor's variables when they differ,
// as GTSAM's ISAM2UpdateParams::extraReelimKeys lets a caller ask; back-ends
// that relinearise every iteration (ceres, cholesky) need nothing. Back-ends
// read modes through this interface alone, so a plugin's factor with modes
// takes part as a max-mixture does.
//
// asMultiModal() is a dynamic_cast: a back-end asks once when a factor is
// added and keeps the pointer for its inner loops.
#pragma once

#include "core/factor.h"

namespace hamal {

class MultiModal {
 public:
  virtual ~MultiModal() = default;

  // The mode at `parameters` (one pointer per key of the factor); -1 when
  // none can be evaluated.
  virtual int mode(const double* const* parameters) const = 0;
  // The information a mode carries relative to the factor's nominal one (a
  // max-mixture's null hypothesis: its scale, e.g. 1e-12). Its gradient and
  // Hessian are that scale times the nominal's, so a back-end may keep a
  // factor whose mode is far below 1 out of its system while that mode is
  // active (core/dormant_policy.h). 1 for an unknown mode (-1).
  virtual double modeInformationScale(int mode) const = 0;
  // The factor a mode is made of: mode `mode`'s residual is this factor's
  // whitened residual times sqrt(modeInformationScale(mode)), with zero or
  // constant entries besides (a max-mixture's component). A back-end that
  // holds a factor in one mode can then add or take out another mode's
  // share without knowing the factor's class. nullptr when the mode is not
  // one factor's term.
  virtual const Factor* modeComponent(int mode) const = 0;
  // A nominal + null hypothesis pair: exactly two modes, 0 the nominal
  // (modeComponent(0) at its full information) and 1 the null hypothesis
  // (the same factor at modeInformationScale(1)). A back-end that holds the
  // null mode can raise it to the nominal by adding (1 - scale) of the
  // component's rows at the same linearisation point.
  virtual bool isNullHypothesisPair() const = 0;
};

// `factor`'s modes, nullptr for a factor without.
inline const MultiModal* asMultiModal(const Factor& factor) {
  return dynamic_cast<const MultiModal*>(&factor);
}

}  // namespace hamal
