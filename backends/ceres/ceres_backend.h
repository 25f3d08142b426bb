// CeresBackend: the Ceres batch baseline (docs/PROTOCOL.md, "Batch solves";
// thesis sec. 3.5.1 compares AprilSAM against batch solvers). One persistent
// ceres::Problem grows with every Step; every `every` updates it is solved to
// convergence, warm-started from the current estimate (with every=1: a
// batch re-solve at every step, sqrt-SAM style).
//
// The Problem holds the factors' own cost and loss functions without taking
// ownership (the Factor owns them, kept alive by the BackendKit) and the
// kit's estimate's Values::data() pointers as parameter blocks (stable, see
// values.h). The kit (core/backend_kit.h) checks each step and the
// finiteness of what is reported; Ceres keeps its own column layout.
#pragma once

#include <ceres/problem.h>
#include <ceres/solver.h>

#include <memory>
#include <vector>

#include "core/backend.h"
#include "core/backend_kit.h"
#include "core/options.h"
#include "core/registry.h"

namespace hamal {

class CeresBackend : public Backend {
 public:
  // The options this back-end declares (names, defaults, help).
  static std::vector<OptionSpec> optionSpecs();
  // Throws hamal::Error on an option value that does not parse.
  explicit CeresBackend(const Options& options);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return kit_.estimate(); }

 private:
  BackendKit kit_{"ceres"};
  std::unique_ptr<ceres::Problem> problem_;
  ceres::Solver::Options solver_options_;
  long every_ = 1;
  long updates_ = 0;
};

}  // namespace hamal
