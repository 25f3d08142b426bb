// writeG2o (graph_io.h): what it writes reads back as the same graph, bit for
// bit, and what cannot be written that way is refused before anything on
// disk changes.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "core/graph_io.h"
#include "tests/io/fake_factors.h"

namespace hamal::io_test {
namespace {

Graph smallGraph() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-10, 10);
  Graph g;
  for (int i = 0; i < 4; ++i) g.initial.insert(X(i), Pose2(u(rng), u(rng), u(rng) / 4));
  g.initial.insert(L(10), Point2(u(rng), u(rng)));
  g.initial.insert(L(11), Point2(0.1, 1.0 / 3.0));
  Eigen::Matrix3d info;
  info << 2.0 / 3.0, 0.1, 0.01, 0.1, 1.0 / 7.0, 0.02, 0.01, 0.02, 3.0;
  for (int i = 0; i < 3; ++i)
    g.add(std::make_shared<FakeBetween>(X(i), X(i + 1), Eigen::Vector3d(u(rng), u(rng), u(rng) / 4),
                                        info));
  Eigen::Matrix2d info2;
  info2 << 1.0 / 3.0, 0.05, 0.05, 2.0;
  g.add(std::make_shared<FakeLandmark>(X(1), L(10), Eigen::Vector2d(u(rng), u(rng)), info2));
  g.add(std::make_shared<FakeLandmark>(X(3), L(11), Eigen::Vector2d(u(rng), u(rng)), info2));
  return g;
}

void expectSameGraph(const Graph& a, const Graph& b) {
  EXPECT_EQ(a.keys(), b.keys());
  ASSERT_EQ(a.initial.keys(), b.initial.keys());
  for (Key k : a.initial.keys()) {
    EXPECT_EQ(a.initial.type(k), b.initial.type(k)) << k;
    for (int i = 0; i < a.initial.dim(k); ++i)
      EXPECT_EQ(a.initial.data(k)[i], b.initial.data(k)[i]) << k << "[" << i << "]";
  }
  ASSERT_EQ(a.factors.size(), b.factors.size());
  for (std::size_t i = 0; i < a.factors.size(); ++i) {
    EXPECT_EQ(a.factors[i]->tag(), b.factors[i]->tag()) << i;
    EXPECT_EQ(a.factors[i]->keys(), b.factors[i]->keys()) << i;
    EXPECT_EQ(a.factors[i]->chi2(a.initial), b.factors[i]->chi2(a.initial)) << i;
  }
}

TEST(GraphWrite, RoundTripIsExact) {
  const Graph g = smallGraph();
  std::ostringstream out;
  out.precision(3);  // the caller's precision must not matter, and is restored
  writeG2o(out, g.initial, g.factors);
  EXPECT_EQ(out.precision(), 3);
  const Graph back = readText(out.str(), "back.g2o", fakeRegistry());
  expectSameGraph(g, back);
  // Vertices first, in key order (Values::keys), then the factors in order.
  std::istringstream lines(out.str());
  std::vector<Key> written;
  for (std::string tag, rest; lines >> tag && std::getline(lines, rest);) {
    std::istringstream fields(rest);
    std::uint64_t id = 0;
    fields >> id;
    if (tag == "VERTEX_SE2") written.push_back(X(id));
    if (tag == "VERTEX_XY") written.push_back(L(id));
    if (tag.rfind("VERTEX", 0) != 0) break;
  }
  EXPECT_EQ(written, g.initial.keys());
}

TEST(GraphWrite, FactorsWithoutValuesWriteNoVertices) {
  const Graph g = smallGraph();
  std::ostringstream out;
  writeG2o(out, Values(), g.factors);
  EXPECT_EQ(out.str().find("VERTEX"), std::string::npos);
  const Graph back = readText(out.str(), "back.g2o", fakeRegistry());
  EXPECT_TRUE(back.initial.empty());
  EXPECT_EQ(back.factors.size(), g.factors.size());
  EXPECT_EQ(back.keys(), g.keys());
}

TEST(GraphWrite, OneIdSpace) {
  Values v;
  v.insert(X(5), Pose2(0, 0, 0));
  v.insert(L(5), Point2(1, 1));
  std::ostringstream out;
  EXPECT_HAS(errorOf([&] { writeG2o(out, v, {}); }), "share id 5, and g2o has one id space");
  EXPECT_TRUE(out.str().empty());
  // The same through the factors' keys when there are no values.
  auto f = std::make_shared<FakeLandmark>(X(2), L(3), Eigen::Vector2d(0, 0),
                                          Eigen::Matrix2d::Identity());
  auto h = std::make_shared<FakeBetween>(X(3), X(4), Eigen::Vector3d(0, 0, 0),
                                         Eigen::Matrix3d::Identity());
  EXPECT_HAS(errorOf([&] { writeG2o(out, Values(), {f, h}); }), "l3 and x3 share id 3");
}

TEST(GraphWrite, RefusesWhatWouldReadBackDifferently) {
  std::ostringstream out;
  Values partial;
  partial.insert(X(0), Pose2(0, 0, 0));
  auto f = std::make_shared<FakeBetween>(X(0), X(1), Eigen::Vector3d(1, 0, 0),
                                         Eigen::Matrix3d::Identity());
  EXPECT_HAS(errorOf([&] { writeG2o(out, partial, {f}); }), "refers to x1, which has no value");
  Values odd;
  odd.insert(Key('c', 1), Pose2(0, 0, 0));
  EXPECT_HAS(errorOf([&] { writeG2o(out, odd, {}); }), "variable c1 is a Pose2");
  Values swapped;
  swapped.insert(L(1), Pose2(0, 0, 0));
  EXPECT_HAS(errorOf([&] { writeG2o(out, swapped, {}); }), "variable l1 is a Pose2");
}

TEST(GraphWrite, FixedVariablesRoundTripAsAFixLine) {
  const Graph g = smallGraph();
  const std::set<Key> fixed = {X(0), X(2), L(11)};
  std::ostringstream out;
  writeG2o(out, g.initial, g.factors, fixed);
  EXPECT_NE(out.str().find("\nFIX 11 0 2\n"), std::string::npos) << out.str();
  const Graph back = readText(out.str(), "back.g2o", fakeRegistry());
  expectSameGraph(g, back);
  EXPECT_EQ(back.fixed, fixed);
  // Without vertices the ids are found through the factors.
  std::ostringstream bare;
  writeG2o(bare, Values(), g.factors, fixed);
  EXPECT_EQ(readText(bare.str(), "bare.g2o", fakeRegistry()).fixed, fixed);
  // No FIX line when nothing is fixed.
  std::ostringstream none;
  writeG2o(none, g.initial, g.factors);
  EXPECT_EQ(none.str().find("FIX"), std::string::npos);
}

TEST(GraphWrite, RefusesAFixedVariableThatNothingNames) {
  const Graph g = smallGraph();
  std::ostringstream out;
  EXPECT_HAS(errorOf([&] { writeG2o(out, g.initial, g.factors, {X(9)}); }),
             "fixed variable x9 has no vertex and no factor");
  EXPECT_TRUE(out.str().empty());
}

TEST(GraphWrite, ToAFileAndBack) {
  const std::string dir = ::testing::TempDir() + "hamal_io_write";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/small.g2o";
  const Graph g = smallGraph();
  writeG2o(path, g.initial, g.factors);
  expectSameGraph(g, readGraph(path, fakeRegistry()));
  std::filesystem::remove_all(dir);
}

TEST(GraphWrite, AFailedWriteLeavesTheOldFile) {
  const std::string dir = ::testing::TempDir() + "hamal_io_failed_write";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/keep.g2o";
  { std::ofstream(path) << "old contents\n"; }
  Values bad;
  bad.insert(X(1), Pose2(0, 0, 0));
  bad.insert(L(1), Point2(0, 0));
  EXPECT_HAS(errorOf([&] { writeG2o(path, bad, {}); }), "one id space");
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "old contents");
  // No temporary file is left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(dir);
}

TEST(GraphWrite, UnwritablePath) {
  const Graph g = smallGraph();
  const std::string path = ::testing::TempDir() + "no/such/dir/x.g2o";
  EXPECT_HAS(errorOf([&] { writeG2o(path, g.initial, g.factors); }), path + ": cannot open");
}

}  // namespace
}  // namespace hamal::io_test
