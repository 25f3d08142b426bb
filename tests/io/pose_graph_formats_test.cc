// writeGraph (core/graph_io.h) in TORO and GTSAM's formats: a pose graph of
// between factors read back in the same format is the same graph (the
// covariance GTSAM's format holds to rounding), and what the formats cannot
// hold (landmarks, other factor kinds, robust losses, FIX) is refused,
// naming it, before anything is written.
#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include "backends/builtins.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"

namespace hamal {
namespace {

const Registry& builtins() {
  static const Registry r = [] {
    Registry reg;
    registerBuiltins(reg);
    return reg;
  }();
  return r;
}

Graph poseGraph() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-5, 5);
  Graph g;
  for (int i = 0; i < 6; ++i) g.initial.insert(X(i), Pose2(u(rng), u(rng), u(rng) / 3));
  Eigen::Matrix3d info;
  info << 2.0 / 3.0, 0.1, 0.01, 0.1, 1.0 / 7.0, 0.02, 0.01, 0.02, 3.0;
  for (int i = 0; i < 5; ++i)
    g.add(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(u(rng), u(rng), u(rng) / 3), info));
  g.add(std::make_shared<BetweenFactor>(X(0), X(4), Pose2(1, 2, 0.5), 10 * info));
  return g;
}

TEST(PoseGraphFormats, ToroAndGtsamReadBackAsTheSameGraph) {
  const Graph g = poseGraph();
  for (Format format : {Format::kToro, Format::kGtsam}) {
    std::ostringstream out;
    writeGraph(out, g.initial, g.factors, format);
    std::istringstream in(out.str());
    const Graph back = readGraph(in, "back", builtins(), format);
    ASSERT_EQ(back.factors.size(), g.factors.size()) << formatName(format);
    ASSERT_EQ(back.initial.keys(), g.initial.keys());
    for (Key k : g.initial.keys())
      for (int t = 0; t < 3; ++t) EXPECT_EQ(back.initial.data(k)[t], g.initial.data(k)[t]);
    for (std::size_t i = 0; i < g.factors.size(); ++i) {
      const auto& a = dynamic_cast<const BetweenFactor&>(*g.factors[i]);
      const auto& b = dynamic_cast<const BetweenFactor&>(*back.factors[i]);
      EXPECT_EQ(a.keys(), b.keys());
      EXPECT_EQ(a.measurement().x, b.measurement().x);
      EXPECT_EQ(a.measurement().theta, b.measurement().theta);
      const double tol = format == Format::kToro ? 0 : 1e-12 * a.information().norm();
      EXPECT_LE((a.information() - b.information()).norm(), tol) << formatName(format);
      EXPECT_NEAR(a.chi2(g.initial), b.chi2(g.initial), 1e-10 * a.chi2(g.initial));
    }
  }
}

TEST(PoseGraphFormats, WhatTheFormatsCannotHoldIsRefusedByName) {
  Graph g = poseGraph();
  const auto expectRefused = [](const Graph& graph, const std::set<Key>& fixed,
                                const std::string& text) {
    std::ostringstream out;
    try {
      writeGraph(out, graph.initial, graph.factors, Format::kToro, fixed);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
    EXPECT_TRUE(out.str().empty());
  };
  expectRefused(g, {X(0)}, "x0 is fixed");
  Graph with_landmark = g;
  with_landmark.initial.insert(L(3), Point2(1, 1));
  expectRefused(with_landmark, {}, "variable l3 is not a pose");
  Graph with_point = g;
  with_point.initial.erase(L(3));
  with_point.add(
      std::make_shared<PosePointFactor>(X(1), L(3), Point2(1, 0), Eigen::Matrix2d::Identity()));
  with_point.initial = Values();
  expectRefused(with_point, {}, "is not a relative-pose measurement");
  Graph with_loss = g;
  auto lossy = std::make_shared<BetweenFactor>(X(1), X(3), Pose2(), Eigen::Matrix3d::Identity());
  lossy->setLoss(std::make_shared<ceres::CauchyLoss>(1.0));
  with_loss.add(lossy);
  expectRefused(with_loss, {}, "carries a robust loss");
  std::ostringstream out;
  EXPECT_THROW(writeGraph(out, g.initial, g.factors, Format::kAuto), Error);
}

}  // namespace
}  // namespace hamal
