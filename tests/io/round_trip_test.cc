// read(writeG2o(g)) == g with the built-in factor kinds, on real datasets and
// on a small graph with landmarks and a prior: the same keys, the same values
// bit for bit, the same factors (tag, keys, and chi2 at the same values).
// Converting M3500.toro to g2o goes through here, so a lost digit or a
// transposed information entry would show up as a chi2 difference.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "core/graph_io.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/prior_factor.h"
#include "factors/register_factors.h"
#include "tests/io/fake_factors.h"
#include "tests/testing/test_data.h"

namespace hamal::io_test {
namespace {

Registry builtinFactors() {
  Registry r;
  registerFactors(r);
  return r;
}

class RoundTrip : public ::testing::Test {
 protected:
  void SetUp() override {
    // One directory per test and process: ctest runs tests in parallel.
    dir_ = ::testing::TempDir() + "hamal_io_round_trip_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
           std::to_string(::getpid());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Writes `g` as g2o, reads it back, and compares.
  void expectRoundTrip(const Graph& g, const std::string& name) {
    const std::string path = dir_ + "/" + name + ".g2o";
    writeG2o(path, g.initial, g.factors);
    const Graph back = readGraph(path, registry_);
    EXPECT_EQ(back.keys(), g.keys());
    ASSERT_EQ(back.initial.keys(), g.initial.keys());
    for (Key k : g.initial.keys()) {
      ASSERT_EQ(back.initial.type(k), g.initial.type(k)) << k;
      for (int i = 0; i < g.initial.dim(k); ++i)
        ASSERT_EQ(back.initial.data(k)[i], g.initial.data(k)[i]) << k << "[" << i << "]";
    }
    ASSERT_EQ(back.factors.size(), g.factors.size());
    const Values& at = values(g);
    double total = 0;
    for (std::size_t i = 0; i < g.factors.size(); ++i) {
      const Factor& a = *g.factors[i];
      const Factor& b = *back.factors[i];
      ASSERT_EQ(b.tag(), a.tag()) << i;
      ASSERT_EQ(b.keys(), a.keys()) << i;
      const double ca = a.chi2(at), cb = b.chi2(at);
      ASSERT_TRUE(std::isfinite(ca)) << i;
      ASSERT_NEAR(cb, ca, 1e-12 * std::max(1.0, std::abs(ca))) << name << " factor " << i;
      total += ca;
    }
    // The comparison meant something: the values are not at the optimum.
    EXPECT_GT(total, 0.0);
  }

  // The graph's values, or (for files without vertices) odometry-like values
  // made up so that chi2 is non-zero and depends on every measurement.
  const Values& values(const Graph& g) {
    if (!g.initial.empty()) return g.initial;
    made_up_ = Values();
    for (Key k : g.keys()) {
      const double s = 0.37 * double(k.index());
      if (k.kind() == kPoseKind)
        made_up_.insert(k, Pose2(std::cos(s), std::sin(s), std::fmod(s, 3.0)));
      else
        made_up_.insert(k, Point2(std::sin(s), s));
    }
    return made_up_;
  }

  std::string dir_;
  Registry registry_ = builtinFactors();
  Values made_up_;
};

TEST_F(RoundTrip, M3500ToroToG2o) {
  HAMAL_REQUIRE_DATA(path, "M3500.toro");
  expectRoundTrip(readGraph(path, registry_), "m3500");
}

TEST_F(RoundTrip, Intel) {
  HAMAL_REQUIRE_DATA(path, "intel.g2o");
  expectRoundTrip(readGraph(path, registry_), "intel");
}

TEST_F(RoundTrip, VictoriaParkCovariancesBecomeInformation) {
  HAMAL_REQUIRE_DATA(path, "victoria_park.txt");
  expectRoundTrip(readGraph(path, registry_), "victoria");
}

TEST_F(RoundTrip, SmallGraphWithLandmarksAndAPrior) {
  Graph g;
  g.initial.insert(X(0), Pose2(0.1, -0.2, 0.3));
  g.initial.insert(X(1), Pose2(1.0 / 3.0, 0.7, -2.9));
  g.initial.insert(X(2), Pose2(2.2, 1.0 / 7.0, 3.1));
  g.initial.insert(L(3), Point2(4.0 / 9.0, -1.25));
  g.initial.insert(L(7), Point2(-3.5, 2.0 / 11.0));
  Eigen::Matrix3d info;
  info << 100.0 / 3.0, 1.5, 0.25, 1.5, 90.0, -0.5, 0.25, -0.5, 1000.0 / 7.0;
  Eigen::Matrix2d info2;
  info2 << 10.0 / 3.0, 0.1, 0.1, 5.0;
  g.add(std::make_shared<PriorFactor>(X(0), Pose2(0, 0, 0.01), info));
  g.add(std::make_shared<BetweenFactor>(X(0), X(1), Pose2(0.3, 0.9, -3.0), info));
  g.add(std::make_shared<BetweenFactor>(X(1), X(2), Pose2(1.9, -0.6, 1.0 / 3.0), info));
  g.add(std::make_shared<PosePointFactor>(X(1), L(3), Point2(0.1, -2.0 / 3.0), info2));
  g.add(std::make_shared<PosePointFactor>(X(2), L(7), Point2(-5.0, 1.0 / 13.0), info2));
  g.add(std::make_shared<PosePointFactor>(X(0), L(7), Point2(-3.0, 0.4), info2));
  expectRoundTrip(g, "small");
}

}  // namespace
}  // namespace hamal::io_test
