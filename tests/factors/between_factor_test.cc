// BetweenFactor (thesis eq. 2.28-2.32): Jacobians, hand-computed residuals of
// both residual kinds, where they agree and differ (docs/PROTOCOL.md, "chi2"),
// predict() both ways, and setBetweenResidual on a graph.
#include "factors/between_factor.h"

#include <gtest/gtest.h>

#include <cmath>

#include "conformance/factor_round_trip.h"
#include "core/error.h"
#include "core/jacobian_check.h"
#include "factors/prior_factor.h"

namespace hamal {
namespace {

Eigen::Matrix3d anisotropicInformation() {
  Eigen::Matrix3d info;
  info << 40.0, 3.0, 1.0,  //
      3.0, 8.0, -0.5,      //
      1.0, -0.5, 20.0;
  return info;
}

// e^T Omega e with e from Pose2 (independent of the cost function's code).
double thesisChi2(const Pose2& a, const Pose2& b, const Pose2& z, const Eigen::Matrix3d& info) {
  const Pose2 d = a.between(b);
  const Eigen::Vector3d e(d.x - z.x, d.y - z.y, wrapAngle(d.theta - z.theta));
  return e.dot(info * e);
}

TEST(BetweenFactor, JacobiansMatchNumericOverRandomStates) {
  for (BetweenResidual kind : {BetweenResidual::kThesis, BetweenResidual::kMeasurementFrame}) {
    const BetweenFactor f(X(0), X(1), Pose2(1.3, -0.4, 2.9), anisotropicInformation(), kind);
    const JacobianCheckResult r = checkJacobians(f);
    EXPECT_TRUE(r.ok) << betweenResidualName(kind) << ": " << r.report;
    EXPECT_EQ(r.trials, 200);
  }
}

TEST(BetweenFactor, ThesisResidualByHand) {
  // a at (1, 2) facing +y; b 3 m ahead of it: in a's frame b is at (3, 0).
  const Pose2 a(1.0, 2.0, M_PI / 2), b(1.0, 5.0, M_PI / 2 + 0.3), z(2.0, 1.0, 0.1);
  Values v;
  v.insert(X(0), a);
  v.insert(X(1), b);
  const BetweenFactor f(X(0), X(1), z, Eigen::Matrix3d::Identity());
  double r[3];
  ASSERT_TRUE(f.evaluate(v, r));
  EXPECT_NEAR(r[0], 1.0, 1e-12);
  EXPECT_NEAR(r[1], -1.0, 1e-12);
  EXPECT_NEAR(r[2], 0.2, 1e-12);

  // Measurement frame: the translation error rotated by R(z_th)^T.
  const BetweenFactor g(X(0), X(1), z, Eigen::Matrix3d::Identity(),
                        BetweenResidual::kMeasurementFrame);
  ASSERT_TRUE(g.evaluate(v, r));
  EXPECT_NEAR(r[0], std::cos(0.1) * 1.0 + std::sin(0.1) * -1.0, 1e-12);
  EXPECT_NEAR(r[1], -std::sin(0.1) * 1.0 + std::cos(0.1) * -1.0, 1e-12);
  EXPECT_NEAR(r[2], 0.2, 1e-12);

  // Anisotropic information: the two objectives differ (101.4 is the thesis').
  const Eigen::Matrix3d aniso = Eigen::Vector3d(100.0, 1.0, 10.0).asDiagonal();
  const BetweenFactor ft(X(0), X(1), z, aniso);
  const BetweenFactor fm(X(0), X(1), z, aniso, BetweenResidual::kMeasurementFrame);
  EXPECT_NEAR(ft.chi2(v), 100.0 + 1.0 + 10.0 * 0.04, 1e-10);
  const double ex = std::cos(0.1) - std::sin(0.1), ey = -std::sin(0.1) - std::cos(0.1);
  EXPECT_NEAR(fm.chi2(v), 100.0 * ex * ex + ey * ey + 0.4, 1e-10);
  EXPECT_GT(std::abs(ft.chi2(v) - fm.chi2(v)), 1.0);

  // Isotropic in x, y: the same chi2.
  const Eigen::Matrix3d iso = Eigen::Vector3d(5.0, 5.0, 10.0).asDiagonal();
  EXPECT_NEAR(BetweenFactor(X(0), X(1), z, iso).chi2(v), 10.4, 1e-10);
  EXPECT_NEAR(BetweenFactor(X(0), X(1), z, iso, BetweenResidual::kMeasurementFrame).chi2(v), 10.4,
              1e-10);
}

TEST(BetweenFactor, WhitenedResidualGivesTheChi2OfTheFullInformation) {
  std::mt19937_64 rng(3);
  const Pose2 z(0.7, 0.2, -3.0);
  const BetweenFactor f(X(4), X(9), z, anisotropicInformation());
  for (int i = 0; i < 100; ++i) {
    const Values v = randomValues(f, rng);
    const double expected = thesisChi2(v.pose(X(4)), v.pose(X(9)), z, anisotropicInformation());
    EXPECT_NEAR(f.chi2(v), expected, 1e-9 * std::max(1.0, expected));
  }
}

TEST(BetweenFactor, ResidualKindsAgreeOnlyOnIsotropicXyInformation) {
  std::mt19937_64 rng(5);
  const Pose2 z(1.0, -2.0, 0.8);
  Eigen::Matrix3d iso = Eigen::Vector3d(7.0, 7.0, 3.0).asDiagonal();
  const BetweenFactor t_iso(X(0), X(1), z, iso);
  const BetweenFactor m_iso(X(0), X(1), z, iso, BetweenResidual::kMeasurementFrame);
  const BetweenFactor t_aniso(X(0), X(1), z, anisotropicInformation());
  const BetweenFactor m_aniso(X(0), X(1), z, anisotropicInformation(),
                              BetweenResidual::kMeasurementFrame);
  int differ = 0;
  for (int i = 0; i < 100; ++i) {
    const Values v = randomValues(t_iso, rng);
    EXPECT_NEAR(t_iso.chi2(v), m_iso.chi2(v), 1e-9 * t_iso.chi2(v));
    if (std::abs(t_aniso.chi2(v) - m_aniso.chi2(v)) > 1e-6 * t_aniso.chi2(v)) ++differ;
  }
  EXPECT_EQ(differ, 100);
}

// What LAGO reads: for either residual, the thesis residual whitened by the
// exposed information gives the factor's own chi2 at any state.
TEST(BetweenFactor, RelativePoseIsTheMeasurementWithItsInformationInTheFirstPosesFrame) {
  const Pose2 z(0.8, -0.3, 1.1);
  Eigen::Matrix3d info;
  info << 40, 7, 2, 7, 9, -1, 2, -1, 30;
  for (BetweenResidual kind : {BetweenResidual::kThesis, BetweenResidual::kMeasurementFrame}) {
    const BetweenFactor f(X(3), X(7), z, info, kind);
    const auto rel = f.relativePose();
    ASSERT_TRUE(rel.has_value());
    EXPECT_EQ(rel->from, X(3));
    EXPECT_EQ(rel->to, X(7));
    EXPECT_EQ(rel->measurement.theta, z.theta);
    const BetweenFactor thesis(X(3), X(7), rel->measurement, rel->information);
    for (int i = 0; i < 5; ++i) {
      Values v;
      v.insert(X(3), Pose2(0.3 * i, -0.2 * i, 0.5 - 0.4 * i));
      v.insert(X(7), Pose2(1 - 0.1 * i, 0.7 * i, 0.2 * i + 1.3));
      EXPECT_NEAR(thesis.chi2(v), f.chi2(v), 1e-9 * (1 + f.chi2(v))) << betweenResidualName(kind);
    }
  }
}

// What a consistency test asks a back-end's covariance with: a thesis
// between of the given fields, whatever residual the asking factor has.
TEST(BetweenFactor, RelativePoseFactorIsAThesisBetweenOfTheGivenMeasurement) {
  Eigen::Matrix3d info;
  info << 40, 7, 2, 7, 9, -1, 2, -1, 30;
  const RelativePose r{X(2), X(9), Pose2(0.5, 1.5, -0.7), info};
  for (BetweenResidual kind : {BetweenResidual::kThesis, BetweenResidual::kMeasurementFrame}) {
    const BetweenFactor asking(X(0), X(1), Pose2(3, 4, 2), Eigen::Matrix3d::Identity(), kind);
    const std::shared_ptr<Factor> made = asking.relativePoseFactor(r);
    ASSERT_NE(made, nullptr);
    EXPECT_TRUE(made->equals(BetweenFactor(X(2), X(9), r.measurement, info)));
    ASSERT_NE(dynamic_cast<const BetweenFactor*>(made.get()), nullptr);
    EXPECT_EQ(static_cast<const BetweenFactor&>(*made).residual(), BetweenResidual::kThesis);
    EXPECT_EQ(made->lossFunction(), nullptr);
  }
  // A prior measures no relative pose: it has no relativePoseFactor to ask.
  EXPECT_EQ(asRelativePoseMeasurement(PriorFactor(X(0), Pose2(), Eigen::Matrix3d::Identity())),
            nullptr);
}

TEST(BetweenFactor, AngleResidualIsWrapped) {
  Values v;
  v.insert(X(0), Pose2(0, 0, 3.1));
  v.insert(X(1), Pose2(0, 0, -3.1));
  const BetweenFactor f(X(0), X(1), Pose2(0, 0, 0.0), Eigen::Matrix3d::Identity());
  double r[3];
  ASSERT_TRUE(f.evaluate(v, r));
  EXPECT_NEAR(r[2], 2 * M_PI - 6.2, 1e-12);
}

TEST(BetweenFactor, PredictsEitherPoseFromTheOther) {
  const Pose2 a(3.0, -1.0, 2.5), z(1.2, 0.4, 2.0);
  const BetweenFactor f(X(0), X(1), z, anisotropicInformation());
  Values known;
  known.insert(X(0), a);
  Values::Entry guess;
  ASSERT_TRUE(f.predict(X(1), known, &guess));
  EXPECT_EQ(guess.type, VariableType::kPose2);
  known.insert(X(1), Pose2(guess.data[0], guess.data[1], guess.data[2]));
  EXPECT_LT(f.chi2(known), 1e-20);
  EXPECT_GT(guess.data[2], -M_PI);  // 2.5 + 2.0 wrapped
  EXPECT_LE(guess.data[2], M_PI);

  // And back: a from b.
  Values only_b;
  only_b.insert(X(1), known.pose(X(1)));
  ASSERT_TRUE(f.predict(X(0), only_b, &guess));
  EXPECT_NEAR(guess.data[0], a.x, 1e-12);
  EXPECT_NEAR(guess.data[1], a.y, 1e-12);
  EXPECT_NEAR(wrapAngle(guess.data[2] - a.theta), 0.0, 1e-12);

  // Neither known, or a key it does not touch: no guess.
  EXPECT_FALSE(f.predict(X(1), Values(), &guess));
  EXPECT_FALSE(f.predict(X(7), known, &guess));
}

TEST(BetweenFactor, RejectsANonSpdInformationBuiltInCode) {
  Eigen::Matrix3d bad = Eigen::Matrix3d::Identity();
  bad(2, 2) = -1.0;
  try {
    BetweenFactor(X(0), X(1), Pose2(), bad);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("BetweenFactor"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("positive definite"), std::string::npos) << e.what();
  }
}

TEST(BetweenFactor, SetBetweenResidualSwapsTheFactorsOfAGraph) {
  Graph graph;
  const Eigen::Matrix3d info = anisotropicInformation();
  graph.add(std::make_shared<PriorFactor>(X(0), Pose2(), Eigen::Matrix3d::Identity()));
  graph.add(std::make_shared<BetweenFactor>(X(0), X(1), Pose2(1, 0.5, 0.3), info));
  graph.add(std::make_shared<BetweenFactor>(X(1), X(2), Pose2(1, -0.5, -0.3), info));
  graph.factors[2]->setLoss(std::make_shared<ceres::HuberLoss>(1.0));
  const FactorPtr prior = graph.factors[0];
  Values v;
  v.insert(X(0), Pose2(0.1, 0.2, 0.3));
  v.insert(X(1), Pose2(1.5, 0.1, 1.0));
  v.insert(X(2), Pose2(2.0, 1.4, -0.7));

  EXPECT_EQ(setBetweenResidual(graph, BetweenResidual::kMeasurementFrame), 2);
  ASSERT_EQ(graph.factors.size(), 3u);
  EXPECT_EQ(graph.factors[0], prior);
  for (int i = 1; i < 3; ++i) {
    const auto* b = dynamic_cast<const BetweenFactor*>(graph.factors[i].get());
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(b->residual(), BetweenResidual::kMeasurementFrame);
    EXPECT_EQ(b->information(), info);
    EXPECT_NEAR(b->chi2(v),
                BetweenFactor(b->keys()[0], b->keys()[1], b->measurement(), info,
                              BetweenResidual::kMeasurementFrame)
                    .chi2(v),
                1e-12);
  }
  EXPECT_EQ(graph.factors[1]->lossFunction(), nullptr);
  ASSERT_NE(graph.factors[2]->lossFunction(), nullptr);
  double rho[3];
  graph.factors[2]->lossFunction()->Evaluate(4.0, rho);
  EXPECT_NEAR(rho[0], 3.0, 1e-12);  // Huber(1): 2 sqrt(4) - 1

  EXPECT_EQ(setBetweenResidual(graph, BetweenResidual::kMeasurementFrame), 0);
  EXPECT_EQ(setBetweenResidual(graph, BetweenResidual::kThesis), 2);
  EXPECT_NEAR(graph.factors[1]->chi2(v),
              thesisChi2(v.pose(X(0)), v.pose(X(1)), Pose2(1, 0.5, 0.3), info), 1e-9);
}

TEST(BetweenFactor, RoundTripsThroughItsFileLine) {
  EXPECT_TRUE(testing::roundTrips(BetweenFactor(
      X(10), X(11), Pose2(1.0 / 3.0, -2.0 / 3.0, M_PI / 7.0), anisotropicInformation())));
}

TEST(BetweenFactor, EqualsComparesMeasurementInformationKeysAndResidualWithinTolerance) {
  const BetweenFactor f(X(0), X(1), Pose2(1.3, -0.4, 2.9), anisotropicInformation());
  EXPECT_TRUE(f.equals(f, 0.0));
  EXPECT_TRUE(
      f.equals(BetweenFactor(X(0), X(1), Pose2(1.3 + 1e-12, -0.4, 2.9), anisotropicInformation())));
  EXPECT_FALSE(f.equals(
      BetweenFactor(X(0), X(1), Pose2(1.3 + 1e-12, -0.4, 2.9), anisotropicInformation()), 0.0));
  EXPECT_FALSE(
      f.equals(BetweenFactor(X(0), X(1), Pose2(1.3, -0.4, 2.9 + 1e-6), anisotropicInformation())));
  Eigen::Matrix3d other = anisotropicInformation();
  other(2, 2) += 1e-4;
  EXPECT_FALSE(f.equals(BetweenFactor(X(0), X(1), Pose2(1.3, -0.4, 2.9), other)));
  EXPECT_FALSE(
      f.equals(BetweenFactor(X(0), X(2), Pose2(1.3, -0.4, 2.9), anisotropicInformation())));
  EXPECT_FALSE(f.equals(BetweenFactor(X(0), X(1), Pose2(1.3, -0.4, 2.9), anisotropicInformation(),
                                      BetweenResidual::kMeasurementFrame)));
  EXPECT_FALSE(f.equals(PriorFactor(X(0), Pose2(1.3, -0.4, 2.9), anisotropicInformation())));
}

}  // namespace
}  // namespace hamal
