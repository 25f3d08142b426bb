// ModeTracking: the mode in which AprilSAM's R holds each factor with modes
// (core/multi_modal.h: a max-mixture's active component, the robust model
// of thesis sec. 4.3.3.2), read through that interface alone so a plugin's
// factor with modes takes part as a max-mixture does.
//
// R keeps linearisations from old points, so a factor's mode at its
// linearisation point, not at the estimate, says what R holds: the
// component-switch hook (component_switch_hook.h) compares the two. A factor
// whose held mode is dormant (core/dormant_policy.h) has no rows in R and no
// edges in the batch's ordering graph. A nominal + null pair
// (MultiModal::isNullHypothesisPair) whose null mode R holds can be raised to
// its nominal by adding the missing share of its component's rows; until
// its variables are relinearised R then holds that component
// (held_nominal), not the mode its linearisation point shows.
//
// The dormant approximation: the dropped term's gradient and Hessian are
// scale x the nominal's (1e-12 x for the usual null hypothesis), so the
// estimate moves by that fraction of what the nominal factor would pull.
// When the switch hook finds a dormant factor active at the estimate it
// enters the system as its variables are relinearised (its rows added like
// a new factor's); switching off again subtracts its rows the same way. Its
// row structure then stays in R until the next batch, which leaves it out
// of the ordering and of R.
#pragma once

#include <vector>

#include "core/dormant_policy.h"
#include "core/factor.h"
#include "core/multi_modal.h"

namespace hamal::aprilsam {

struct ModeTracking {
  explicit ModeTracking(double dormant_scale) : policy(dormant_scale, "aprilsam") {}

  // A new factor's slots (every factor has them; only those with modes use
  // them), and its place in the lists of the factors with modes.
  void add(int f, const Factor& factor, const int* vars, int nvars) {
    const MultiModal* moded = asMultiModal(factor);
    any |= moded != nullptr;
    of_factor.push_back(moded);
    lin_mode.push_back(0);
    held_nominal.push_back(0);
    // The raised switch needs the nominal's factor (MultiModal::modeComponent).
    null_pair.push_back(moded && moded->isNullHypothesisPair() &&
                        moded->modeComponent(0) != nullptr);
    if (!moded) return;
    factors.push_back(f);
    for (int k = 0; k < nvars; ++k) of_var[vars[k]].push_back(f);
  }
  // Whether `factor` held at mode `m` is out of the system.
  bool dormant(const MultiModal& factor, int m) const { return policy.dormant(factor, m); }

  DormantPolicy policy;
  // Per factor: its modes (asMultiModal, asked once here), nullptr for one
  // without.
  std::vector<const MultiModal*> of_factor;
  std::vector<int> lin_mode;  // per factor: the mode R holds it linearised with
  // Per factor: a nominal + null pair, and whether R holds its nominal
  // component at a linearisation point where its null mode is active.
  std::vector<char> null_pair, held_nominal;
  std::vector<std::vector<int>> of_var;  // per variable: the factors with modes on it
  std::vector<int> factors;              // the factors with modes
  // Set by the batch's ordering, which has just written lin_mode for every
  // factor with modes at the batch's linearisation points, until the batch
  // has linearised them (so it does not evaluate every mode twice).
  bool at_lin_known = false;
  bool any = false;        // some factor has modes
  long dormant_count = 0;  // factors left out at the last batch
};

}  // namespace hamal::aprilsam
