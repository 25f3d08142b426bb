// The reader on well-formed input (graph_io.h): vertex lines, FIX, comments,
// and each format's information convention, with test-local factor kinds
// (fake_factors.h) so the reader is tested apart from factors/.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "core/graph_io.h"
#include "tests/io/fake_factors.h"

namespace hamal::io_test {
namespace {

int countKind(const Graph& g, char kind) {
  int n = 0;
  for (Key k : g.keys()) n += k.kind() == kind;
  return n;
}

TEST(GraphRead, G2oVerticesEdgesLandmarksAndFix) {
  const std::string text =
      "# a comment\n"
      "\n"
      "VERTEX_SE2 0 0 0 0\n"
      "   \t \n"
      "VERTEX_SE2 1 1.5 -2.25 0.5\n"
      "VERTEX_XY 7 3 4\n"
      "  # an indented comment\n"
      "FIX 0\n"
      "EDGE_SE2 0 1 1 0 0 10 0 0 20 0 30\n"
      "EDGE_SE2_XY 1 7 0.5 0.25 4 1 5\n";
  const Graph g = readText(text, "small.g2o", fakeRegistry());
  EXPECT_EQ(g.source, "small.g2o");
  ASSERT_EQ(g.initial.size(), 3u);
  EXPECT_EQ(g.initial.pose(X(1)).x, 1.5);
  EXPECT_EQ(g.initial.pose(X(1)).y, -2.25);
  EXPECT_EQ(g.initial.pose(X(1)).theta, 0.5);
  EXPECT_EQ(g.initial.point(L(7)), Point2(3, 4));
  ASSERT_EQ(g.factors.size(), 2u);
  EXPECT_EQ(g.factors[0]->keys(), (std::vector<Key>{X(0), X(1)}));
  EXPECT_EQ(g.factors[1]->keys(), (std::vector<Key>{X(1), L(7)}));
  EXPECT_EQ(g.fixed, (std::set<Key>{X(0)}));
  EXPECT_EQ(countKind(g, kPoseKind), 2);
  EXPECT_EQ(countKind(g, kLandmarkKind), 1);

  // g2o's information order I11 I12 I13 I22 I23 I33 reaches the factor.
  const auto& between = dynamic_cast<const FakeBetween&>(*g.factors[0]);
  EXPECT_EQ(between.info_, Eigen::Vector3d(10, 20, 30).asDiagonal().toDenseMatrix());
  const auto& lm = dynamic_cast<const FakeLandmark&>(*g.factors[1]);
  Eigen::Matrix2d expected;
  expected << 4, 1, 1, 5;
  EXPECT_EQ(lm.info_, expected);
}

TEST(GraphRead, FixOnAGraphWithoutVerticesNamesTheEdgeVariable) {
  const Graph g = readText("EDGE_SE2_XY 3 4 1 1 1 0 1\nFIX 4\n", "f.g2o", fakeRegistry());
  EXPECT_EQ(g.fixed, (std::set<Key>{L(4)}));
  EXPECT_TRUE(g.initial.empty());
}

TEST(GraphRead, ToroUsesItsOwnInformationOrder) {
  // I11 I12 I22 I33 I13 I23
  const Graph g = readText("VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEDGE2 0 1 1 0 0 10 1 20 30 2 3\n",
                           "m.toro", fakeRegistry());
  ASSERT_EQ(g.factors.size(), 1u);
  Eigen::Matrix3d expected;
  expected << 10, 1, 2, 1, 20, 3, 2, 3, 30;
  EXPECT_EQ(dynamic_cast<const FakeBetween&>(*g.factors[0]).info_, expected);
  EXPECT_EQ(g.initial.pose(X(1)).x, 1.0);
}

TEST(GraphRead, GtsamOdometryAndLandmarksAreCovariancesInOneIdSpace) {
  const std::string text =
      "ODOMETRY 0 1 1 0 0 0.5 0 0 0.25 0 0.125\n"
      "LANDMARK 1 2 3 4 0.5 0 0.25\n"
      "ODOMETRY 1 3 1 0 0 0.5 0 0 0.25 0 0.125\n";
  const Graph g = readText(text, "vp.txt", fakeRegistry());
  EXPECT_TRUE(g.initial.empty());
  ASSERT_EQ(g.factors.size(), 3u);
  // The LANDMARK line's second id is a landmark; the odometry skips it.
  EXPECT_EQ(g.factors[1]->keys(), (std::vector<Key>{X(1), L(2)}));
  EXPECT_EQ(g.keys(), (std::vector<Key>{L(2), X(0), X(1), X(3)}));
  EXPECT_EQ(dynamic_cast<const FakeBetween&>(*g.factors[0]).info_,
            Eigen::Vector3d(2, 4, 8).asDiagonal().toDenseMatrix());
  EXPECT_EQ(dynamic_cast<const FakeLandmark&>(*g.factors[1]).info_,
            Eigen::Vector2d(2, 4).asDiagonal().toDenseMatrix());
}

TEST(GraphRead, GtsamFilesMayListG2oAndToroVertices) {
  const std::string text =
      "VERTEX_SE2 0 0 0 0\n"
      "VERTEX2 1 1 0 0\n"
      "VERTEX_XY 2 5 6\n"
      "ODOMETRY 0 1 1 0 0 1 0 0 1 0 1\n"
      "LANDMARK 1 2 4 6 1 0 1\n";
  const Graph g = readText(text, "g.txt", fakeRegistry(), Format::kGtsam);
  EXPECT_EQ(g.initial.size(), 3u);
  EXPECT_EQ(g.initial.point(L(2)), Point2(5, 6));
  EXPECT_EQ(g.factors.size(), 2u);
}

TEST(GraphRead, WindowsLineEndingsAndNoFinalNewline) {
  const Graph g =
      readText("VERTEX_SE2 0 0 0 0\r\nVERTEX_SE2 1 1 0 0\r\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1",
               "crlf.g2o", fakeRegistry());
  EXPECT_EQ(g.initial.size(), 2u);
  EXPECT_EQ(g.factors.size(), 1u);
}

TEST(GraphRead, ChiSquareOfTheReadFactorsAtTheReadValues) {
  // x1 - x0 - z = (0.5, 0, 0) with information diag(4, ...): chi2 = 1.
  const Graph g = readText(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1.5 0 0\n"
      "EDGE_SE2 0 1 1 0 0 4 0 0 1 0 1\n",
      "c.g2o", fakeRegistry());
  EXPECT_NEAR(g.factors[0]->chi2(g.initial), 1.0, 1e-15);
}

TEST(GraphRead, ReadsFromDiskLikeFromAStream) {
  const std::string path = ::testing::TempDir() + "graph_read_disk.g2o";
  {
    std::ofstream out(path);
    out << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n";
  }
  const Graph g = readGraph(path, fakeRegistry());
  EXPECT_EQ(g.source, path);
  EXPECT_EQ(g.initial.size(), 2u);
  EXPECT_EQ(g.factors.size(), 1u);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace hamal::io_test
