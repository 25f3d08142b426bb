// L2GFactor: a scan match of a localization pose a against a prior-map node
// b whose global pose is known (thesis sec. 5.3.2, eq. 5.2, fig. 5.3-5.4): an
// observation of a's local-to-global transform T_g^a = T_b^a T_g^b.
//
// The residual is the between factor's (thesis eq. 2.28-2.31, factors/
// between_factor.h, kThesis) from the map pose b to a, with b a constant:
//     e = [ R(th_b)^T (t_a - t_b) - z_t ;  wrap(th_a - th_b - z_th) ]
// whitened as U e, U^T U = Omega. Its Jacobian with respect to a is U
// diag(R(th_b)^T, 1), the between factor's right block.
//
// Why the map pose is carried in the factor (unary) and not a variable. A
// prior-map node is never estimated during localization (sec. 5.3.2: "the
// portion of the graph corresponding to the known map is held fixed"). The
// binary form, a map node as a fixed variable, is exactly the existing
// BetweenFactor (EDGE_SE2 from b to a) plus a FIX of b, so it needs no new
// factor kind at all; what the binary form cannot do, and the unary one
// does, is keep the map out of the localization graph: a localization run
// then holds only its own poses, any back-end solves it with or without
// fixed-variable support, and a map of 204 nodes costs nothing per trial.
// MOSS (apps/moss) solves 10^4 maps x S trials, so that matters. The factor
// still records which map node it came from (`mapNode`), because MOSS' f of
// eq. 5.4 selects observations by their map node.
//
// File line (g2o format, hamal tag):
//   EDGE_SE2_L2G a b bx by bth dx dy dth I11 I12 I13 I22 I23 I33
// a: the localization pose's id (a variable, X(a)); b: the map node's id in
// the prior map (not a variable of this graph); (bx, by, bth): b's global
// pose; (dx, dy, dth): T_b^a, pose a seen from b; the information upper
// triangle row-major as EDGE_SE2.
//
// Written with the public plugin headers only (core/*.h), as a plugin would be.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "core/factor.h"
#include "core/information.h"
#include "core/mixture_component.h"
#include "core/pose2.h"
#include "core/registry.h"
#include "core/variable_prediction.h"

namespace hamal {

class L2GFactor : public Factor, public VariablePrediction, public MixtureComponent {
 public:
  // `map_pose`: T_g^b, the map node's global pose; `measurement`: T_b^a
  // (b^-1 a); `information`: 3x3 SPD (x, y, theta), else hamal::Error.
  L2GFactor(Key a, std::uint64_t map_node, const Pose2& map_pose, const Pose2& measurement,
            const Eigen::Matrix3d& information);

  std::string tag() const override { return "EDGE_SE2_L2G"; }
  void writeFields(std::ostream& os) const override;
  // a = b z, the L2G estimate T_g^a itself.
  bool predict(Key unknown, const Values& known, Values::Entry* guess) const override;
  double logDetInformation() const override { return logDeterminant(information_); }

  std::uint64_t mapNode() const { return map_node_; }
  const Pose2& mapPose() const { return map_pose_; }
  const Pose2& measurement() const { return measurement_; }
  const Eigen::Matrix3d& information() const { return information_; }
  // The global pose of a this observation says: T_g^b T_b^a.
  Pose2 globalPose() const { return map_pose_.compose(measurement_); }

 private:
  std::uint64_t map_node_;
  Pose2 map_pose_;
  Pose2 measurement_;
  Eigen::Matrix3d information_;
};

// ("g2o", "EDGE_SE2_L2G"), registered by default (factors/register_factors.cc).
FactorInfo l2gFactorInfo();

}  // namespace hamal
