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
//   g2o     EDGE_SE2_L2G             L2GFactor        a b bx by bth dx dy dth I11 I12 I13 I22 I23
//   I33 (hamal) g2o     EDGE_MAXMIX              MaxMixtureFactor w_null scale_null <inner g2o
//   line> (hamal)
//
// "(hamal)": tags g2o does not define; hamal writes and reads them in .g2o
// files. Every factor writes itself in g2o's format (Factor::tag), so a graph
// read from TORO or GTSAM files is written as g2o with information matrices.
//
// Poses are X(id), landmarks L(id) (key.h). Every parse reads the whole line
// and fails, naming the file, the line and the reason, on anything else.
#include "factors/register_factors.h"

#include <memory>
#include <string>

#include "core/information.h"
#include "core/key.h"
#include "core/line_tokens.h"
#include "factors/between_factor.h"
#include "factors/l2g_factor.h"
#include "factors/landmark_prior_factor.h"
#include "factors/max_mixture_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/position_factor.h"
#include "factors/prior_factor.h"
#include "factors/range_bearing_factor.h"

namespace hamal {

namespace {

// Key packs the index into 56 bits: a larger id would alias another variable.
std::uint64_t checkedId(LineTokens& t, const char* what) {
  const std::uint64_t id = t.id(what);
  if (id > Key::kMaxIndex)
    t.fail(std::string(what) + " " + std::to_string(id) + " is larger than the largest id " +
           std::to_string(Key::kMaxIndex));
  return id;
}

Pose2 readPose(LineTokens& t, const char* x, const char* y, const char* th) {
  const double px = t.number(x), py = t.number(y), pth = t.angle(th);
  return {px, py, pth};
}

FactorPtr parseBetween(LineTokens& t, MatrixLayout layout) {
  const Key a = X(checkedId(t, "pose a")), b = X(checkedId(t, "pose b"));
  const Pose2 z = readPose(t, "dx", "dy", "dth");
  const Eigen::Matrix3d information = readInformation3(t, layout);
  t.expectEnd();
  return std::make_shared<BetweenFactor>(a, b, z, information);
}

FactorInfo betweenInfo(std::string format, std::string tag, MatrixLayout layout,
                       std::string description) {
  return {std::move(format), std::move(tag), std::move(description),
          [layout](LineTokens& t) { return parseBetween(t, layout); }};
}

FactorPtr parsePrior(LineTokens& t) {
  const Key k = X(checkedId(t, "pose"));
  const Pose2 z = readPose(t, "x", "y", "th");
  const Eigen::Matrix3d information = readInformation3(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<PriorFactor>(k, z, information);
}

FactorPtr parsePosePoint(LineTokens& t, MatrixLayout layout) {
  const Key pose = X(checkedId(t, "pose")), landmark = L(checkedId(t, "landmark"));
  const double zx = t.number("zx"), zy = t.number("zy");
  const Eigen::Matrix2d information = readInformation2(t, layout);
  t.expectEnd();
  return std::make_shared<PosePointFactor>(pose, landmark, Point2(zx, zy), information);
}

FactorPtr parseRangeBearing(LineTokens& t) {
  const Key pose = X(checkedId(t, "pose")), landmark = L(checkedId(t, "landmark"));
  const double range = t.number("range"), bearing = t.angle("bearing");
  const Eigen::Matrix2d information = readInformation2(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<RangeBearingFactor>(pose, landmark, range, bearing, information);
}

FactorPtr parsePosition(LineTokens& t) {
  const Key pose = X(checkedId(t, "pose"));
  const double x = t.number("x"), y = t.number("y");
  const Eigen::Matrix2d information = readInformation2(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<PositionFactor>(pose, Point2(x, y), information);
}

FactorPtr parseLandmarkPrior(LineTokens& t) {
  const Key landmark = L(checkedId(t, "landmark"));
  const double x = t.number("x"), y = t.number("y");
  const Eigen::Matrix2d information = readInformation2(t, MatrixLayout::kG2oInformation);
  t.expectEnd();
  return std::make_shared<LandmarkPriorFactor>(landmark, Point2(x, y), information);
}

}  // namespace

void registerFactors(Registry& registry) {
  registry.addFactor(
      betweenInfo("g2o", "EDGE_SE2", MatrixLayout::kG2oInformation,
                  "rigid-body constraint between poses a and b: a b dx dy dth + information, upper "
                  "triangle row-major (I11 I12 I13 I22 I23 I33)"));
  registry.addFactor(betweenInfo(
      "toro", "EDGE2", MatrixLayout::kToroInformation,
      "rigid-body constraint: a b dx dy dth + information in TORO order I11 I12 I22 I33 I13 "
      "I23"));
  registry.addFactor(betweenInfo(
      "gtsam", "EDGE2", MatrixLayout::kG2oCovariance,
      "rigid-body constraint: a b dx dy dth + COVARIANCE c11 c12 c13 c22 c23 c33 (w20000.txt)"));
  registry.addFactor(
      betweenInfo("gtsam", "ODOMETRY", MatrixLayout::kG2oCovariance,
                  "odometry between poses: a b dx dy dth + COVARIANCE c11 c12 c13 c22 c23 c33 "
                  "(victoria_park.txt)"));
  registry.addFactor({"g2o", "EDGE_SE2_PRIOR",
                      "prior on a pose: id x y th + information I11 I12 I13 I22 I23 I33",
                      parsePrior});
  registry.addFactor(
      {"g2o", "EDGE_SE2_XY",
       "landmark position seen in the pose's frame: pose lm zx zy + information "
       "I11 I12 I22",
       [](LineTokens& t) { return parsePosePoint(t, MatrixLayout::kG2oInformation); }});
  registry.addFactor(
      {"gtsam", "LANDMARK",
       "landmark position seen in the pose's frame: pose lm zx zy + COVARIANCE "
       "c11 c12 c22 (victoria_park.txt)",
       [](LineTokens& t) { return parsePosePoint(t, MatrixLayout::kG2oCovariance); }});
  registry.addFactor({"g2o", "EDGE_SE2_RANGE_BEARING",
                      "range and bearing (robot to landmark, robot frame) from a pose to a "
                      "landmark: pose lm range bearing + information I11 I12 I22 (hamal tag)",
                      parseRangeBearing});
  registry.addFactor({"g2o", "EDGE_SE2_POSITION",
                      "GPS position of a pose in the global frame: id x y + information I11 I12 "
                      "I22 (hamal tag)",
                      parsePosition});
  registry.addFactor({"g2o", "EDGE_XY_PRIOR",
                      "prior on a landmark position: id x y + information I11 I12 I22",
                      parseLandmarkPrior});
  registry.addFactor(maxMixtureFactorInfo());
  registry.addFactor(l2gFactorInfo());
}

}  // namespace hamal
