// Every public dataset of ../shared/data loads with the built-in factor kinds
// and the counts its README gives (third_party_notes/datasets.md), each with
// its format's information convention. Skips a file that is absent.
#include <gtest/gtest.h>

#include <map>

#include "core/graph_io.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/register_factors.h"
#include "tests/io/fake_factors.h"
#include "tests/testing/test_data.h"

namespace hamal::io_test {
namespace {

const Registry& builtinFactors() {
  static const Registry registry = [] {
    Registry r;
    registerFactors(r);
    return r;
  }();
  return registry;
}

struct Counts {
  int poses = 0, landmarks = 0, other = 0;
};

Counts countKeys(const Graph& g) {
  Counts c;
  for (Key k : g.keys()) {
    if (k.kind() == kPoseKind)
      ++c.poses;
    else if (k.kind() == kLandmarkKind)
      ++c.landmarks;
    else
      ++c.other;
  }
  return c;
}

void expectCounts(const Graph& g, int poses, std::size_t factors, bool vertices) {
  const Counts c = countKeys(g);
  EXPECT_EQ(c.poses, poses) << g.source;
  EXPECT_EQ(c.landmarks, 0) << g.source;
  EXPECT_EQ(c.other, 0) << g.source;
  EXPECT_EQ(g.factors.size(), factors) << g.source;
  EXPECT_EQ(g.initial.size(), vertices ? std::size_t(poses) : 0u) << g.source;
  EXPECT_TRUE(g.fixed.empty()) << g.source;
}

const BetweenFactor& between(const Graph& g, std::size_t i) {
  return dynamic_cast<const BetweenFactor&>(*g.factors.at(i));
}

TEST(Datasets, M3500Toro) {
  HAMAL_REQUIRE_DATA(path, "M3500.toro");
  const Graph g = readGraph(path, builtinFactors());  // toro from the name
  expectCounts(g, 3500, 5453, true);
  // "EDGE2 0 1 1.030390 0.011350 -0.012958 44.721360 0 44.721360 44.721360 0 0":
  // TORO's order I11 I12 I22 I33 I13 I23 makes that a diagonal information.
  EXPECT_EQ(between(g, 0).information(),
            Eigen::Vector3d(44.72136, 44.72136, 44.72136).asDiagonal().toDenseMatrix());
  EXPECT_EQ(between(g, 0).measurement().x, 1.030390);
  EXPECT_EQ(g.initial.pose(X(1)).x, 1.030390);
}

TEST(Datasets, ManhattanG2oHasNoVertices) {
  HAMAL_REQUIRE_DATA(path, "manhattan.g2o");
  const Graph g = readGraph(path, builtinFactors());
  expectCounts(g, 3500, 5453, false);
  // "... 44.635358 -7.962220 0.000000 376.516380 0.000000 9745.791650": g2o order.
  Eigen::Matrix3d info;
  info << 44.635358, -7.962220, 0, -7.962220, 376.516380, 0, 0, 0, 9745.791650;
  EXPECT_EQ(between(g, 0).information(), info);
}

TEST(Datasets, City10000) {
  HAMAL_REQUIRE_DATA(path, "city10000.g2o");
  expectCounts(readGraph(path, builtinFactors()), 10000, 20687, true);
}

TEST(Datasets, Intel) {
  HAMAL_REQUIRE_DATA(path, "intel.g2o");
  expectCounts(readGraph(path, builtinFactors()), 1728, 2512, true);
}

TEST(Datasets, Csail) {
  HAMAL_REQUIRE_DATA(path, "CSAIL.g2o");
  expectCounts(readGraph(path, builtinFactors()), 1045, 1172, false);
}

TEST(Datasets, W20000NeedsItsFormatSaid) {
  HAMAL_REQUIRE_DATA(path, "w20000.txt");
  const std::string msg = errorOf([&] { readGraph(path, builtinFactors()); });
  EXPECT_HAS(msg, path + ":1: EDGE2 lines are ambiguous");
  EXPECT_HAS(msg, "--format=toro or --format=gtsam");
  const Graph g = readGraph(path, builtinFactors(), Format::kGtsam);
  expectCounts(g, 20061, 26831, false);
  // "EDGE2 0 1 ... 3.16228 0 0 3.16228 0 5" is a covariance: information is its inverse.
  EXPECT_TRUE(between(g, 0).information().isApprox(
      Eigen::Vector3d(1 / 3.16228, 1 / 3.16228, 1 / 5.0).asDiagonal().toDenseMatrix(), 1e-14));
}

TEST(Datasets, VictoriaParkPosesAndLandmarksShareOneIdSpace) {
  HAMAL_REQUIRE_DATA(path, "victoria_park.txt");
  const Graph g = readGraph(path, builtinFactors());  // gtsam from its tags
  const Counts c = countKeys(g);
  EXPECT_EQ(c.poses, 6969);
  EXPECT_EQ(c.landmarks, 151);
  EXPECT_EQ(c.other, 0);
  EXPECT_TRUE(g.initial.empty());
  std::map<std::string, int> tags;
  for (const auto& f : g.factors) ++tags[f->tag()];
  EXPECT_EQ(tags, (std::map<std::string, int>{{"EDGE_SE2", 6968}, {"EDGE_SE2_XY", 3640}}));
  // "LANDMARK 4 5 11.5387 -3.2007 0.4 0 0.4": landmark 5, covariance 0.4 I.
  const auto& lm = dynamic_cast<const PosePointFactor&>(*g.factors.at(4));
  EXPECT_EQ(lm.keys(), (std::vector<Key>{X(4), L(5)}));
  EXPECT_TRUE(lm.information().isApprox(Eigen::Matrix2d::Identity() / 0.4, 1e-14));
  // One id space: the 7120 ids 0..7119 are each a pose or a landmark, never both.
  std::map<std::uint64_t, int> uses;
  for (Key k : g.keys()) ++uses[k.index()];
  EXPECT_EQ(uses.size(), 7120u);
  EXPECT_EQ(uses.rbegin()->first, 7119u);
}

}  // namespace
}  // namespace hamal::io_test
