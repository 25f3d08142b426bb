// L2GFactor (thesis sec. 5.3.2, eq. 5.2): Jacobians over many random states
// and map poses, the residual equals the between factor's from a map pose held
// fixed, the file line round-trips, and bad lines name file, line and reason.
#include "factors/l2g_factor.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <random>
#include <sstream>

#include "backends/builtins.h"
#include "conformance/factor_round_trip.h"
#include "core/error.h"
#include "core/graph_io.h"
#include "core/jacobian_check.h"
#include "core/registry.h"
#include "core/step.h"
#include "factors/between_factor.h"
#include "factors/register_factors.h"

namespace hamal {
namespace {

Eigen::Matrix3d information() {
  Eigen::Matrix3d info;
  info << 40.0, 3.0, 1.0,  //
      3.0, 25.0, -2.0,     //
      1.0, -2.0, 90.0;
  return info;
}

Pose2 randomPose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> xy(-10, 10), th(-3.14159, 3.14159);
  return {xy(rng), xy(rng), th(rng)};
}

TEST(L2GFactor, JacobiansMatchNumericOverRandomStatesAndMapPoses) {
  std::mt19937_64 rng(7);
  for (int m = 0; m < 25; ++m) {
    const L2GFactor f(X(3), 11, randomPose(rng), randomPose(rng), information());
    JacobianCheckOptions options;
    options.seed = 100 + m;
    const JacobianCheckResult r = checkJacobians(f, options);
    EXPECT_TRUE(r.ok) << r.report;
    EXPECT_EQ(r.trials, 200);
  }
}

// The residual convention is the between factor's (thesis kind) from b to a.
TEST(L2GFactor, ResidualEqualsTheBetweenFactorsFromTheMapPose) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Pose2 b = randomPose(rng), z = randomPose(rng), a = randomPose(rng);
    const L2GFactor l2g(X(1), 5, b, z, information());
    const BetweenFactor between(X(0), X(1), z, information());
    Values v;
    v.insert(X(0), b);
    v.insert(X(1), a);
    double r1[3], r2[3];
    ASSERT_TRUE(l2g.evaluate(v, r1));
    ASSERT_TRUE(between.evaluate(v, r2));
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r1[k], r2[k], 1e-12);
  }
}

TEST(L2GFactor, IsZeroAtTheComposedPoseAndPredictsIt) {
  const Pose2 b(2.0, -1.0, 0.7), z(0.5, 0.25, -0.2);
  const L2GFactor f(X(4), 9, b, z, information());
  Values::Entry guess;
  ASSERT_TRUE(f.predict(X(4), Values(), &guess));
  Values v;
  v.insertEntry(X(4), guess);
  EXPECT_NEAR(f.chi2(v), 0.0, 1e-20);
  EXPECT_NEAR(v.pose(X(4)).x, b.compose(z).x, 1e-15);
  EXPECT_FALSE(f.predict(X(5), Values(), &guess));
  EXPECT_EQ(f.mapNode(), 9u);
  EXPECT_NEAR(f.logDetInformation(), std::log(information().determinant()), 1e-12);
}

TEST(L2GFactor, RefusesAnInformationThatIsNotPositiveDefinite) {
  Eigen::Matrix3d bad = information();
  bad(2, 2) = -1.0;
  EXPECT_THROW(L2GFactor(X(0), 0, Pose2(), Pose2(), bad), Error);
}

class L2GLine : public ::testing::Test {
 protected:
  L2GLine() { registerFactors(registry_); }
  FactorPtr parse(const std::string& line) const {
    LineTokens tokens = LineTokens::split("l.g2o", 4, line);
    return registry_.findFactor("g2o", tokens.tag())->parse(tokens);
  }
  Registry registry_;
};

TEST_F(L2GLine, IsRegisteredListedAndRoundTripsExactly) {
  ASSERT_NE(registry_.findFactor("g2o", "EDGE_SE2_L2G"), nullptr);
  EXPECT_NE(registry_.describeFactors().find("EDGE_SE2_L2G"), std::string::npos);
  const L2GFactor f(X(12), 40, Pose2(1.0 / 3.0, -2.5, 0.1), Pose2(0.2, 1e-3, -0.05), information());
  EXPECT_TRUE(testing::roundTrips(f, &registry_));
  // The map node and its pose are part of the measurement.
  EXPECT_FALSE(f.equals(
      L2GFactor(X(12), 41, Pose2(1.0 / 3.0, -2.5, 0.1), Pose2(0.2, 1e-3, -0.05), information())));
  EXPECT_FALSE(f.equals(
      L2GFactor(X(12), 40, Pose2(1.0 / 3.0, -2.4, 0.1), Pose2(0.2, 1e-3, -0.05), information())));
}

TEST_F(L2GLine, AGraphWithL2GLinesReadsBack) {
  Graph g;
  g.initial.insert(X(0), Pose2(0, 0, 0));
  g.initial.insert(X(1), Pose2(1, 0.1, 0.05));
  g.add(std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0, 0), information()));
  g.add(std::make_shared<L2GFactor>(X(1), 7, Pose2(3, 4, 1), Pose2(-1, 0.5, 0.2), information()));
  std::stringstream file;
  writeG2o(file, g.initial, g.factors);
  const Graph back = readGraph(file, "l2g.g2o", registry_, Format::kAuto);
  ASSERT_EQ(back.factors.size(), 2u);
  EXPECT_EQ(back.factors[1]->tag(), "EDGE_SE2_L2G");
  EXPECT_EQ(back.factors[1]->chi2(g.initial), g.factors[1]->chi2(g.initial));
}

TEST_F(L2GLine, BadInputNamesFileLineAndReason) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"EDGE_SE2_L2G 0 1 0 0 0 1 0 0 100 0 0 100 0", "I33 is missing"},
      {"EDGE_SE2_L2G 0 1 0 0 0 1 0 0 100 0 0 100 0 100 5", "extra"},
      {"EDGE_SE2_L2G -1 1 0 0 0 1 0 0 100 0 0 100 0 100", "pose a"},
      {"EDGE_SE2_L2G 0 x 0 0 0 1 0 0 100 0 0 100 0 100", "map node b"},
      {"EDGE_SE2_L2G 0 1 nan 0 0 1 0 0 100 0 0 100 0 100", "bx"},
      {"EDGE_SE2_L2G 0 1 0 0 0 1 0 0 -100 0 0 100 0 100", "positive definite"},
  };
  for (const auto& [line, reason] : cases) {
    SCOPED_TRACE(line);
    try {
      parse(line);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("l.g2o:4: ", 0), 0u) << what;
      EXPECT_NE(what.find(reason), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace hamal

namespace hamal {
namespace {

// The header's claim: the unary L2G factor and the binary form (EDGE_SE2
// from a map node held fixed) have the same optimum, on every back-end.
TEST(L2GFactor, SameOptimumAsABetweenFactorFromAFixedMapNode) {
  Registry registry;
  registerBuiltins(registry);
  const Pose2 map0(1.0, 2.0, 0.3), map1(4.0, 2.5, -0.2);
  const Pose2 z0(0.2, -0.1, 0.05), z1(-0.3, 0.2, -0.1);
  Eigen::Matrix3d odo = Eigen::Vector3d(100, 100, 400).asDiagonal().toDenseMatrix();
  for (const std::string backend : {"cholesky", "ceres", "aprilsam"}) {
    SCOPED_TRACE(backend);
    Step unary, binary;
    for (Step* s : {&unary, &binary}) {
      s->new_values.insert(X(0), Pose2(1.1, 2.0, 0.3));
      s->new_values.insert(X(1), Pose2(2.4, 2.3, 0.2));
      s->new_values.insert(X(2), Pose2(3.6, 2.8, -0.3));
      s->new_factors.push_back(
          std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1.4, 0.1, -0.1), odo));
      s->new_factors.push_back(
          std::make_shared<BetweenFactor>(X(1), X(2), Pose2(1.3, 0.2, -0.2), odo));
    }
    unary.new_factors.push_back(std::make_shared<L2GFactor>(X(0), 0, map0, z0, information()));
    unary.new_factors.push_back(std::make_shared<L2GFactor>(X(2), 1, map1, z1, information()));
    binary.new_values.insert(X(100), map0);
    binary.new_values.insert(X(101), map1);
    binary.fixed = {X(100), X(101)};
    binary.new_factors.push_back(std::make_shared<BetweenFactor>(X(100), X(0), z0, information()));
    binary.new_factors.push_back(std::make_shared<BetweenFactor>(X(101), X(2), z1, information()));
    auto a = registry.makeBackend(backend), b = registry.makeBackend(backend);
    ASSERT_TRUE(a->update(unary).status.ok());
    ASSERT_TRUE(b->update(binary).status.ok());
    for (int i = 0; i < 3; ++i) {
      const Pose2 pa = a->estimate().pose(X(i)), pb = b->estimate().pose(X(i));
      EXPECT_NEAR(pa.x, pb.x, 1e-6);
      EXPECT_NEAR(pa.y, pb.y, 1e-6);
      EXPECT_NEAR(pa.theta, pb.theta, 1e-6);
    }
    EXPECT_EQ(b->estimate().pose(X(100)).x, map0.x);
  }
}

}  // namespace
}  // namespace hamal
