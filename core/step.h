// Step: what a back-end receives in one update (thesis Alg. 3.1, line 2:
// AugmentGraph(G, f)): the variables that appear for the first time, with
// their initial guesses, and the factors that complete at this step.
// A batch solve is one Step that holds everything.
#pragma once

#include <cstddef>
#include <vector>

#include "core/factor.h"
#include "core/values.h"

namespace hamal {

struct Step {
  std::size_t index = 0;
  Values new_values;                   // guesses for the new variables
  std::vector<FactorPtr> new_factors;  // each touches only known or new variables
};

}  // namespace hamal
