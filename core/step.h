// Step: what a back-end receives in one update (thesis Alg. 3.1, line 2:
// AugmentGraph(G, f)): the variables that appear for the first time, with
// their initial guesses, and the factors that complete at this step.
// A batch solve is one Step that holds everything.
//
// A step may also fix variables (g2o's FIX, a prior-map node, a landmark held
// at its label): a fixed variable keeps its value and never enters a
// back-end's system, so it needs no prior for the gauge. It may be one of the
// step's new variables or one added by an earlier step.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/factor.h"
#include "core/values.h"

namespace hamal {

struct Step {
  std::size_t index = 0;
  Values new_values;                   // guesses for the new variables
  std::vector<FactorPtr> new_factors;  // each touches only known or new variables
  std::vector<Key> fixed;              // new or known variables held constant from now on
};

// Checks a step against the variables a back-end already holds (`known`)
// before it records anything, so bad input throws hamal::Error and leaves
// the back-end as it was: a variable added twice, a null factor, a factor on
// a variable neither known nor new, or one whose parameter block size is not
// the variable's dimension, a fixed key that names no variable. `backend`
// prefixes the message. A factor that names one variable twice is refused
// too: Ceres aborts on it, and other solvers would give it a meaning nobody
// wrote.
void checkStep(const Step& step, const Values& known, const std::string& backend);

}  // namespace hamal
