// Step checks: see step.h.
#include "core/step.h"

#include <cmath>

#include "core/error.h"

namespace hamal {

void checkStep(const Step& step, const Values& known, const std::string& backend) {
  const std::string at = backend + ": step " + std::to_string(step.index);
  for (const auto& kv : step.new_values) {
    if (known.contains(kv.first))
      throw Error(at + " adds variable " + kv.first.str() + ", which already exists");
    // A guess that is not finite would stay in the estimate of a back-end
    // that never moves the variable (no factor on it yet, or fixed).
    for (int i = 0; i < dimension(kv.second.type); ++i)
      if (!std::isfinite(kv.second.data[i]))
        throw Error(at + " adds variable " + kv.first.str() + " with a guess that is not finite");
  }
  for (const FactorPtr& f : step.new_factors) {
    if (!f) throw Error(at + " holds a null factor");
    for (std::size_t a = 0; a < f->keys().size(); ++a)
      for (std::size_t b = a + 1; b < f->keys().size(); ++b)
        if (f->keys()[a] == f->keys()[b])
          throw Error(at + ": factor " + f->tag() + " names variable " + f->keys()[a].str() +
                      " twice; a factor's variables must be distinct");
    const auto& sizes = f->costFunction()->parameter_block_sizes();
    for (std::size_t k = 0; k < f->keys().size(); ++k) {
      const Key key = f->keys()[k];
      const Values& holder = known.contains(key) ? known : step.new_values;
      if (!holder.contains(key))
        throw Error(at + ": factor " + f->tag() + " refers to unknown variable " + key.str());
      if (holder.dim(key) != sizes[k])
        throw Error(at + ": factor " + f->tag() + " expects " + std::to_string(sizes[k]) +
                    " parameters for " + key.str() + ", which has " +
                    std::to_string(holder.dim(key)));
    }
  }
  for (Key key : step.fixed)
    if (!known.contains(key) && !step.new_values.contains(key))
      throw Error(at + " fixes " + key.str() + ", which is neither known nor new");
}

}  // namespace hamal
