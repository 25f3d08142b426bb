// DenseGaussNewton: the example plugin's back-end, "dense-gauss-newton".
//
// Gauss-Newton on the full normal equations (thesis sec. 2.2.4, eq. 2.13-2.16:
// A^T A dx = -A^T b), stored as a dense matrix and solved with Eigen's LDLT.
// Every update re-solves the whole graph. It is O(n^3) per iteration, meant
// for graphs of a few hundred variables: its purpose is to show how a
// back-end is written against the public interface (Backend, linearize(),
// Values::retract) and registered from a plugin, not to be fast.
//
// A factorisation that fails or meets a (near) zero pivot, such as a graph
// with no prior (gauge freedom), is reported as a numerical-failure Status
// that names the variable of the pivot; the estimate is left as it was.
#pragma once

#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "core/backend.h"
#include "core/factor.h"
#include "core/registry.h"

namespace hamal::example {

class DenseGaussNewton : public Backend {
 public:
  // max_iterations >= 1; stops earlier once the largest |dx| < tolerance.
  DenseGaussNewton(int max_iterations, double tolerance);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return estimate_; }

 private:
  int max_iterations_;
  double tolerance_;
  Values estimate_;
  std::vector<FactorPtr> factors_;
  std::vector<Key> variables_;           // in order of arrival
  std::unordered_map<Key, int> offset_;  // first column of each free variable
  std::unordered_set<Key> fixed_;        // held at their values (core/step.h)
  int dimension_ = 0;
};

// The registry entry, with options max_iterations and tolerance.
BackendInfo denseGaussNewtonInfo();

}  // namespace hamal::example
