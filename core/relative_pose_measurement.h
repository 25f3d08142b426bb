// RelativePoseMeasurement: the capability of a factor that holds a rigid
// relative-pose measurement between two Pose2 variables (thesis sec.
// 2.2.3.1, eq. 2.28-2.32). Initialisers that work on the pose graph alone
// (LAGO, protocol/lago_initialization.h), the robust front ends' odometry
// chains and consistency tests read it; a factor kind opts in by deriving
// from Factor and RelativePoseMeasurement. Every other factor is one they
// cannot use, and they say so.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>

#include "core/factor.h"
#include "core/key.h"
#include "core/pose2.h"

namespace hamal {

// A Gaussian measurement of pose `to` seen from pose `from` (from^-1 to),
// with its information in (x, y, theta) of from's frame.
struct RelativePose {
  Key from, to;
  Pose2 measurement;
  Eigen::Matrix3d information;
};

class RelativePoseMeasurement {
 public:
  virtual ~RelativePoseMeasurement() = default;

  // The measurement, only when the factor's residual is, to first order,
  // that measurement's error whitened by that information, so that an
  // initialiser treating it as an edge solves the factor's own least-squares
  // term; the robust loss is not part of it (an initialiser decides what to
  // do with a factor that has one). Empty for a kind derived from one that
  // measures a relative pose but no longer says so.
  virtual std::optional<RelativePose> relativePose() const = 0;
  // A factor of this kind for another relative-pose measurement `r`: keys
  // r.from and r.to, the thesis residual (the (x, y, theta) error of
  // from^-1 to against r.measurement in from's frame) whitened by
  // r.information, and no robust loss. It lets a caller ask a back-end's
  // covariance about a relative pose (FactorWeights::residualCovariance)
  // without naming a factor class. Null when the kind cannot make one.
  virtual std::shared_ptr<Factor> relativePoseFactor(const RelativePose& r) const = 0;
};

// `factor`'s relative-pose measurement capability, nullptr for a factor
// without.
inline const RelativePoseMeasurement* asRelativePoseMeasurement(const Factor& factor) {
  return dynamic_cast<const RelativePoseMeasurement*>(&factor);
}

// The relative pose `factor` measures; empty for a factor that gives none.
inline std::optional<RelativePose> relativePoseOf(const Factor& factor) {
  const RelativePoseMeasurement* m = asRelativePoseMeasurement(factor);
  return m ? m->relativePose() : std::nullopt;
}

}  // namespace hamal
