// The built-in factor kinds, registered per file format and tag (registry.h;
// the formats' information conventions are in graph_io.h and information.h).
//
//   format  tag                      factor           fields after the tag
//   g2o     EDGE_SE2                 BetweenFactor    a b dx dy dth I11 I12 I13 I22 I23 I33
//   g2o     EDGE_SE2_PRIOR           PriorFactor      id x y th I11 I12 I13 I22 I23 I33
//   toro    EDGE2                    BetweenFactor    a b dx dy dth I11 I12 I22 I33 I13 I23
//   gtsam   EDGE2, ODOMETRY          BetweenFactor    a b dx dy dth c11 c12 c13 c22 c23 c33
//   g2o     EDGE_SE2_XY              PosePointFactor  pose lm zx zy I11 I12 I22
//   gtsam   LANDMARK                 PosePointFactor  pose lm zx zy c11 c12 c22
//   g2o     EDGE_SE2_RANGE_BEARING   RangeBearingFactor pose lm range bearing I11 I12 I22 (hamal)
//   g2o     EDGE_SE2_POSITION        PositionFactor   id x y I11 I12 I22 (hamal)
//   g2o     EDGE_XY_PRIOR            LandmarkPriorFactor id x y I11 I12 I22
//   g2o     EDGE_SE2_L2G             L2GFactor        a b bx by bth dx dy dth I11..I33 (hamal)
//   g2o     EDGE_MAXMIX              MaxMixtureFactor w_null scale_null <inner g2o line> (hamal)
//
// "(hamal)": tags g2o does not define; hamal writes and reads them in .g2o
// files. Every factor writes itself in g2o's format (Factor::tag), so a graph
// read from TORO or GTSAM files is written as g2o with information matrices.
//
// Each factor's parser sits beside its writeFields, in its own file, and
// comes here as one registration line (as g2o's G2O_REGISTER_TYPE). Poses are
// X(id), landmarks L(id) (key.h). Every parse reads the whole line and fails,
// naming the file, the line and the reason, on anything else.
#include "factors/register_factors.h"

#include "factors/between_factor.h"
#include "factors/l2g_factor.h"
#include "factors/landmark_prior_factor.h"
#include "factors/max_mixture_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/position_factor.h"
#include "factors/prior_factor.h"
#include "factors/range_bearing_factor.h"

namespace hamal {

void registerFactors(Registry& registry) {
  for (FactorInfo& info : betweenFactorInfos()) registry.addFactor(std::move(info));
  registry.addFactor(priorFactorInfo());
  for (FactorInfo& info : posePointFactorInfos()) registry.addFactor(std::move(info));
  registry.addFactor(rangeBearingFactorInfo());
  registry.addFactor(positionFactorInfo());
  registry.addFactor(landmarkPriorFactorInfo());
  registry.addFactor(maxMixtureFactorInfo());
  registry.addFactor(l2gFactorInfo());
}

}  // namespace hamal
