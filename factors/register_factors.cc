// The built-in factor kinds, registered per file format and tag (registry.h;
// the formats' information conventions are in graph_io.h and information.h).
//
//   format  tag                      factor           fields after the tag
//   g2o     EDGE_SE2                 BetweenFactor    a b dx dy dth I11 I12 I13 I22 I23 I33
//   g2o     EDGE_SE2_PRIOR           PriorFactor      id x y th I11 I12 I13 I22 I23 I33
//   toro    EDGE2                    BetweenFactor    a b dx dy dth I11 I12 I22 I33 I13 I23
//   gtsam   EDGE2, ODOMETRY          BetweenFactor    a b dx dy dth c11 c12 c13 c22 c23 c33
//
// Poses are X(id), landmarks L(id) (key.h). Every parse reads the whole line
// and fails, naming the file, the line and the reason, on anything else.
#include <memory>
#include <string>

#include "core/builtins.h"
#include "core/information.h"
#include "core/key.h"
#include "core/line_tokens.h"
#include "factors/between_factor.h"
#include "factors/prior_factor.h"

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
  const double px = t.number(x), py = t.number(y), pth = t.number(th);
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
}

}  // namespace hamal
