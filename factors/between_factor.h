// BetweenFactor: the rigid-body transformation constraint between two poses
// (thesis sec. 2.2.3.1, eq. 2.28-2.32; g2o's EDGE_SE2, TORO's EDGE2, GTSAM's
// EDGE2/ODOMETRY).
//
// Two residuals are offered, because the literature uses both and they are
// different objectives whenever the information is not isotropic in x, y
// (docs/PROTOCOL.md, "chi2"):
//
//   kThesis (default): the thesis' residual, the one hamal's chi2 uses,
//     e = [ R(th_a)^T (t_b - t_a) - z_t ;  wrap(th_b - th_a - z_th) ]
//   kMeasurementFrame: g2o's and GTSAM's e = log(z^-1 (a^-1 b)), i.e. the
//     translation error rotated into the measurement's frame,
//     e = [ R(z_th)^T (R(th_a)^T (t_b - t_a) - z_t) ;  wrap(th_b - th_a - z_th) ]
//
// Both are whitened as U e with U^T U = Omega. The thesis writes r = z - F;
// hamal uses e = F - z: the same chi2, the Jacobian (eq. 2.32, analytic here)
// with the opposite sign.
//
// To optimise a whole graph with g2o's objective, read it and then call
// setBetweenResidual(graph, BetweenResidual::kMeasurementFrame) before
// building steps or back-ends from it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/factor.h"
#include "core/graph.h"
#include "core/information.h"
#include "core/mixture_component.h"
#include "core/pose2.h"
#include "core/registry.h"
#include "core/relative_pose_measurement.h"
#include "core/variable_prediction.h"

namespace hamal {

enum class BetweenResidual {
  kThesis,            // translation error in pose a's frame (eq. 2.28-2.31)
  kMeasurementFrame,  // translation error in the measurement's frame (g2o, GTSAM)
};

const char* betweenResidualName(BetweenResidual residual);  // "thesis", "measurement-frame"

class BetweenFactor : public Factor,
                      public VariablePrediction,
                      public RelativePoseMeasurement,
                      public MixtureComponent {
 public:
  // `measurement` is pose b seen from pose a (a^-1 b); `information` is its
  // 3x3 information matrix (x, y, theta), which must be SPD.
  BetweenFactor(Key a, Key b, const Pose2& measurement, const Eigen::Matrix3d& information,
                BetweenResidual residual = BetweenResidual::kThesis);

  // Written as g2o's EDGE_SE2 whatever format it was read from, with the
  // information matrix (a covariance read from a GTSAM file is written as its
  // inverse). The residual choice is not written: it is a way to optimise, not
  // part of the measurement.
  std::string tag() const override { return "EDGE_SE2"; }
  // "a b dx dy dth I11 I12 I13 I22 I23 I33", numbers with 17 significant
  // digits (set here, so any writer round-trips exactly).
  void writeFields(std::ostream& os) const override;
  // b from a (b = a z), or a from b (a = b z^-1).
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;
  // {a, b, measurement, information in a's frame}: information() for the
  // thesis residual, rotated by the measurement's heading for the
  // measurement-frame one (whose translation error is in z's frame).
  std::optional<RelativePose> relativePose() const override;
  // A thesis-residual BetweenFactor for `r`, whichever residual this one has.
  std::shared_ptr<Factor> relativePoseFactor(const RelativePose& r) const override;

  const Pose2& measurement() const { return measurement_; }
  const Eigen::Matrix3d& information() const { return information_; }
  double logDetInformation() const override { return logDeterminant(information_); }
  BetweenResidual residual() const { return residual_; }
  // Factor::equals and the same residual choice (not in the file form).
  bool equals(const Factor& other, double tolerance = 1e-9) const override;

 private:
  Pose2 measurement_;
  Eigen::Matrix3d information_;
  BetweenResidual residual_;
};

// Replaces every BetweenFactor of `graph` whose residual differs by one with
// `residual` (same keys, measurement, information and robust loss). Factor
// pointers taken from the graph earlier keep the old residual, so call this
// right after reading. Subclasses (a plugin's between with a loss and its own
// tag) are left as they are; a MaxMixtureFactor's between components are
// swapped too (the mixture is replaced). Returns how many factors were
// replaced.
int setBetweenResidual(Graph& graph, BetweenResidual residual);

// The file forms read as a BetweenFactor: g2o EDGE_SE2 "a b dx dy dth" +
// information I11 I12 I13 I22 I23 I33; TORO EDGE2 with information in TORO's
// order I11 I12 I22 I33 I13 I23; GTSAM EDGE2 and ODOMETRY with the covariance
// c11 c12 c13 c22 c23 c33.
std::vector<FactorInfo> betweenFactorInfos();

}  // namespace hamal
