// The Jacobian check: a factor's analytic Jacobians against central finite
// differences of its own residual, at many random states (public, so
// that plugin authors test their factors the way hamal tests its own; as g2o's
// jacobians_slam2d.cpp and GTSAM's EXPECT_CORRECT_FACTOR_JACOBIANS). The
// normal equations of every back-end (thesis eq. 2.12-2.14) are built from
// these Jacobians, so a wrong entry silently slows or breaks convergence.
//
// It depends on no test framework: it returns a result to assert on, e.g.
//   const JacobianCheckResult r = checkJacobians(factor);
//   EXPECT_TRUE(r.ok) << r.report;
//
// Tolerance. Each entry's error is |analytic - numeric| / max(1, |numeric|)
// (absolute for small entries, relative for large ones). Central differences
// with step h = 1e-6 have truncation error ~h^2 |f'''| / 6 ~ 1e-12 and
// rounding error ~eps |r| / h ~ 2e-10 |r| on these smooth functions, about
// 1e-8 for the residual sizes of the default states and O(1) information; a
// wrong Jacobian entry is off by O(1) of its value. The default tolerance
// 1e-6 sits between the two. With large information (whitened residuals of
// 1e3 or more) raise `tolerance` or scale the information down for the check.
//
// The parameters are perturbed as the cost function sees them (plain
// additive, angles unwrapped: Ceres and the back-ends differentiate with
// respect to the raw parameter blocks). A residual that wraps an angle jumps
// by 2 pi where the wrap boundary falls within h of the state; with random
// states that happens with probability ~1e-7 per trial.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>

#include "core/factor.h"
#include "core/values.h"

namespace hamal {

struct JacobianCheckOptions {
  int trials = 200;         // random states checked
  double step = 1e-6;       // central-difference step h
  double tolerance = 1e-6;  // on |analytic - numeric| / max(1, |numeric|)
  std::uint64_t seed = 1;   // the check is deterministic for a seed
  // Rejects states where the factor is singular or undefined (a range-bearing
  // landmark on the pose); rejected states are resampled. A state where the
  // cost function's Evaluate returns false is resampled too.
  std::function<bool(const Values&)> accept;
  int max_resamples = 1000;  // per trial, before the check gives up (not ok)
};

struct JacobianCheckResult {
  bool ok = false;
  int trials = 0;              // states checked
  int rejected = 0;            // states resampled (filter or failed Evaluate)
  double max_abs_error = 0.0;  // max |analytic - numeric| over all entries
  double max_rel_error = 0.0;  // max of the scaled error the tolerance applies to
  // The entry with the largest scaled error (trial -1: none).
  struct Entry {
    int trial = -1;
    int block = -1;  // parameter block = index into factor.keys()
    int row = -1;    // residual index
    int col = -1;    // parameter index within the block
    double analytic = 0.0, numeric = 0.0;
    Values state;
  } worst;
  std::string report;  // one readable paragraph, for a test's failure message
};

// Makes the state of one trial; must hold every key of the factor with the
// parameter block size its cost function expects.
using ValuesSampler = std::function<Values(std::mt19937_64& rng)>;

// One random variable: a Pose2 with x, y in [-10, 10] m and theta in
// (-pi, pi], or a Point2 with x, y in [-10, 10] m.
Values::Entry randomEntry(VariableType type, std::mt19937_64& rng);
// Random values for every key of `factor`, the type told by the parameter
// block size (3: Pose2, 2: Point2). Throws hamal::Error for other sizes:
// pass a ValuesSampler then.
Values randomValues(const Factor& factor, std::mt19937_64& rng);

JacobianCheckResult checkJacobians(const Factor& factor, const JacobianCheckOptions& options = {});
JacobianCheckResult checkJacobians(const Factor& factor, const ValuesSampler& sample,
                                   const JacobianCheckOptions& options = {});

}  // namespace hamal
