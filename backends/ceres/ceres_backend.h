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
//
// Marginal covariances (core/marginals.h) are ceres::Covariance's on the same
// problem at the estimate (SPARSE_QR with SuiteSparse, the loss applied as
// in the solve); a Pose2 block is (x, y, theta), the parameters themselves,
// as hamal's retraction. A constant (fixed) block's covariance is zero, as
// Ceres gives it. Refused (a Status) when the last update did not end ok or
// Ceres finds the Jacobian rank deficient.
#pragma once

#include <ceres/problem.h>
#include <ceres/solver.h>

#include <memory>
#include <vector>

#include "core/backend.h"
#include "core/backend_kit.h"
#include "core/marginals.h"
#include "core/options.h"
#include "core/registry.h"

namespace hamal {

class CeresBackend : public Backend, public MarginalCovariances {
 public:
  // The options this back-end declares (names, defaults, help).
  static std::vector<OptionSpec> optionSpecs();
  // Throws hamal::Error on an option value that does not parse.
  explicit CeresBackend(const Options& options);

  UpdateResult update(const Step& step) override;
  const Values& estimate() const override { return kit_.estimate(); }
  // ceres::Covariance at the estimate (see above).
  Status jointMarginalCovariance(const std::vector<Key>& keys,
                                 Eigen::MatrixXd* covariance) override;

 private:
  UpdateResult solve(const Step& step);

  BackendKit kit_{"ceres"};
  std::unique_ptr<ceres::Problem> problem_;
  ceres::Solver::Options solver_options_;
  long every_ = 1;
  long updates_ = 0;
  Status last_status_;  // of the last update that got past the kit's check
};

}  // namespace hamal
