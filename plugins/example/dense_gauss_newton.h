// DenseGaussNewton: the example plugin's back-end, "dense-gauss-newton".
//
// Gauss-Newton on the full normal equations (thesis sec. 2.2.4, eq. 2.13-2.16:
// A^T A dx = -A^T b), stored as a dense matrix and solved with Eigen's LDLT.
// Every update re-solves the whole graph. It is O(n^3) per iteration, meant
// for graphs of a few hundred variables: its purpose is to show how a
// back-end is written against the public interface (Backend, linearize(),
// Values::retract) and registered from a plugin, not to be fast.
//
// The bookkeeping every back-end shares is hamal's BackendKit
// (core/backend_kit.h): the step checked before anything is recorded, the
// estimate, the factors, the variable index with fixed variables and the
// column layout, the finiteness of what it reports. This file adds one
// refusal of its own, a step that would take it past kMaxDimension scalar
// columns (it throws hamal::Error too and leaves the back-end as it was),
// and the numerics. A factorisation that fails or meets a (near) zero pivot, such
// as a graph with no prior (gauge freedom), is reported as a
// numerical-failure Status that names the variable of the pivot; the
// estimate is left as it was.
#pragma once

#include "core/backend.h"
#include "core/backend_kit.h"
#include "core/registry.h"

namespace hamal::example {

class DenseGaussNewton : public Backend {
 public:
  // max_iterations >= 1; stops earlier once the largest |dx| < tolerance.
  DenseGaussNewton(int max_iterations, double tolerance);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return kit_.estimate(); }

 private:
  int max_iterations_;
  double tolerance_;
  BackendKit kit_{"dense-gauss-newton"};
};

// The registry entry, with options max_iterations and tolerance.
BackendInfo denseGaussNewtonInfo();

}  // namespace hamal::example
