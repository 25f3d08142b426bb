// The false-edge list file (apps/robust/false_edge_list.h): what is written
// reads back, a malformed line is an error naming file and line, and a list
// that does not match its graph, or its own header, is refused.
#include "apps/robust/false_edge_list.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

#include "core/error.h"
#include "factors/between_factor.h"

namespace hamal::apps {
namespace {

std::string tempPath(const std::string& name) {
  return ::testing::TempDir() + "/robust_" + std::to_string(getpid()) + "_" + name;
}

TEST(FalseEdgeList, WriteReadRoundTrip) {
  FalseEdgeList list;
  list.spoiling = {{"policy", "local-group"}, {"seed", "3"}};
  list.edges = {{5, 1, 4, 0}, {6, 2, 5, 0}, {7, 9, 30, 1}};
  const std::string path = tempPath("list.false");
  writeFalseEdges(path, list);
  const FalseEdgeList back = readFalseEdges(path);
  EXPECT_EQ(back.spoiling, list.spoiling);
  ASSERT_EQ(back.edges.size(), 3u);
  EXPECT_EQ(back.edges[2].factor, 7u);
  EXPECT_EQ(back.edges[2].from, 9u);
  EXPECT_EQ(back.edges[2].to, 30u);
  EXPECT_EQ(back.edges[2].group, 1u);
  std::remove(path.c_str());
}

TEST(FalseEdgeList, MalformedLinesNameFileAndLine) {
  const std::string path = tempPath("bad.false");
  {
    std::ofstream out(path);
    out << "# a comment\nfactor from to group\n5 1 4 0\n6 2 x 0\n";
  }
  try {
    readFalseEdges(path);
    FAIL() << "a non-numeric id was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":4:"), std::string::npos) << e.what();
  }
  {
    std::ofstream out(path);
    out << "5 1 4 0\n";
  }
  EXPECT_THROW(readFalseEdges(path), Error);  // no column line
  {
    std::ofstream out(path);
    out << "factor from to group\n5 1 4\n";
  }
  EXPECT_THROW(readFalseEdges(path), Error);  // truncated
  std::remove(path.c_str());
  EXPECT_THROW(readFalseEdges(path), Error);  // absent
}

TEST(FalseEdgeList, AListThatDoesNotMatchItsGraphIsRefused) {
  Graph g;
  g.source = "g";
  for (int i = 0; i < 4; ++i)
    g.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0),
                                          Eigen::Matrix3d::Identity()));
  g.add(std::make_shared<BetweenFactor>(X(0), X(3), Pose2(), Eigen::Matrix3d::Identity()));
  FalseEdgeList list;
  list.edges = {{4, 0, 3, 0}};
  EXPECT_NO_THROW(checkFalseEdges(list, g, "l"));
  list.edges = {{3, 0, 3, 0}};  // factor 3 is 3 -> 4
  EXPECT_THROW(checkFalseEdges(list, g, "l"), Error);
  list.edges = {{9, 0, 3, 0}};  // no factor 9
  EXPECT_THROW(checkFalseEdges(list, g, "l"), Error);
  list.edges = {{4, 0, 3, 0}, {4, 0, 3, 1}};  // twice
  EXPECT_THROW(checkFalseEdges(list, g, "l"), Error);
}

TEST(FalseEdgeList, AListThatDisagreesWithItsHeaderIsRefused) {
  const std::string path = tempPath("cut.false");
  const std::string header =
      "# hamal_spoil: false loop closures of the graph file beside this one\n"
      "# spoiling: outliers=3 seed=1 graph_factors=7\n"
      "factor from to group\n";
  const auto expectRefused = [&](const std::string& content, const std::string& reason) {
    std::ofstream(path) << content;
    try {
      readFalseEdges(path);
      FAIL() << "read: " << content;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path + ":2: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  // A line missing (cut at a line break), the header alone, a line too many.
  expectRefused(header + "4 0 3 0\n5 1 4 0\n", "outliers=3 but the list has 2 edges");
  expectRefused(header, "outliers=3 but the list has 0 edges");
  expectRefused(header + "4 0 3 0\n5 1 4 0\n6 2 5 0\n7 0 4 0\n", "has 4 edges");
  expectRefused("# a comment\n# spoiling: outliers=x\nfactor from to group\n",
                "outliers=x is not a count");
  std::ofstream(path) << header + "4 0 3 0\n5 1 4 0\n6 2 5 0\n";
  EXPECT_EQ(readFalseEdges(path).edges.size(), 3u);
  std::remove(path.c_str());
}

TEST(FalseEdgeList, AListOfAGraphOfOtherSizeIsRefused) {
  Graph g;
  g.source = "g";
  for (int i = 0; i < 4; ++i)
    g.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0),
                                          Eigen::Matrix3d::Identity()));
  g.add(std::make_shared<BetweenFactor>(X(0), X(3), Pose2(), Eigen::Matrix3d::Identity()));
  FalseEdgeList list;
  list.edges = {{4, 0, 3, 0}};
  list.spoiling = {{"graph_factors", "5"}};
  EXPECT_NO_THROW(checkFalseEdges(list, g, "l"));
  list.spoiling = {{"graph_factors", "6"}};  // the list of another spoiling's graph
  try {
    checkFalseEdges(list, g, "l");
    FAIL() << "a list of a graph of 6 factors was taken for one of 5";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("l: the list is of a graph of 6 factors, g has 5"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hamal::apps
