// The doubt rules of a robust answer (backends/robust/answer_doubt.h): each
// rule fires where it should and stays quiet where it should not, alone and
// inside GNC on hand-made graphs, and each status reaches the caller.
#include "backends/robust/answer_doubt.h"

#include <gtest/gtest.h>

#include <cmath>

#include "apps/common/cli.h"
#include "apps/robust/robust_loop_closures.h"
#include "backends/robust/graduated_non_convexity.h"
#include "core/error.h"
#include "core/graph.h"
#include "factors/between_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal::robust {
namespace {

bool names(const Status& s, const std::string& what) {
  return s.message.find(what) != std::string::npos;
}

TEST(AnswerDoubt, MostClosuresRejectedIsUncertain) {
  EXPECT_TRUE(rejectedShareDoubt(5, 10).ok());  // half is not most
  EXPECT_TRUE(rejectedShareDoubt(0, 0).ok());
  EXPECT_TRUE(rejectedShareDoubt(9, 9).ok());  // too few closures for a share
  const Status s = rejectedShareDoubt(6, 10);
  EXPECT_EQ(s.code, Status::kUncertain);
  EXPECT_TRUE(names(s, "6 of 10")) << s.message;
  // With the near misses' evidence (near_misses.h): a map that refutes the
  // rejected closures clearly keeps the answer ok; one that does not names
  // the expected false closures.
  EXPECT_TRUE(rejectedShareDoubt(6, 10, Refutation{0.49, 0}).ok());
  const Status loose = rejectedShareDoubt(6, 10, Refutation{0.5, 0});
  EXPECT_EQ(loose.code, Status::kUncertain);
  EXPECT_TRUE(names(loose, "does not refute")) << loose.message;
  EXPECT_TRUE(names(loose, "0.5 false closures expected")) << loose.message;
  EXPECT_EQ(rejectedShareDoubt(6, 10, Refutation{std::nan(""), 0}).code, Status::kUncertain);
  // A map that rests on a closure nothing else tests refutes nothing.
  const Status alone = rejectedShareDoubt(6, 10, Refutation{0.01, 2});
  EXPECT_EQ(alone.code, Status::kUncertain);
  EXPECT_TRUE(names(alone, "2 accepted closure(s) hold a direction of the map alone"))
      << alone.message;
  EXPECT_TRUE(rejectedShareDoubt(5, 10, Refutation{7.0, 3}).ok());  // not most
}

TEST(AnswerDoubt, DecisionsThatFlipMoreThanTwiceAreUncertain) {
  EXPECT_TRUE(flipDoubt({}).ok());
  EXPECT_TRUE(flipDoubt({0, 1, 2, 2}).ok());
  const Status s = flipDoubt({0, 3, 1, 5});
  EXPECT_EQ(s.code, Status::kUncertain);
  EXPECT_TRUE(names(s, "2 loop closure(s)")) << s.message;
  EXPECT_TRUE(names(s, "at most 5")) << s.message;
}

TEST(AnswerDoubt, ACheaperAlternativeByMoreThanTheMarginIsUncertain) {
  EXPECT_TRUE(alternativeDoubt(100, 95, 9.21).ok());  // within one closure's cost
  EXPECT_TRUE(alternativeDoubt(100, 120, 9.21).ok());
  EXPECT_TRUE(alternativeDoubt(100, std::nan(""), 9.21).ok());
  const Status s = alternativeDoubt(100, 80, 9.21);
  EXPECT_EQ(s.code, Status::kUncertain);
  EXPECT_TRUE(names(s, "80")) << s.message;
}

FactorPtr between(int a, int b, double dx, const Eigen::Matrix3d& info) {
  return std::make_shared<BetweenFactor>(X(a), X(b), Pose2(dx, 0, 0), info);
}

TEST(AnswerDoubt, TheTruncatedObjectiveCapsOnlyTheCandidates) {
  Values v;
  v.insert(X(0), Pose2(0, 0, 0));
  v.insert(X(1), Pose2(1, 0, 0));
  const Eigen::Matrix3d info = 100 * Eigen::Matrix3d::Identity();
  const FactorPtr odo = between(0, 1, 2, info);   // chi2 100
  const FactorPtr loop = between(0, 1, 3, info);  // chi2 400, capped
  EXPECT_DOUBLE_EQ(truncatedObjective({odo}, {loop.get()}, {9}, v), 109);
  EXPECT_THROW(truncatedObjective({odo}, {loop.get()}, {}, v), Error);
}

// A chain of 21 poses along x, closed between its ends by `right` closures
// that agree with the odometry and `wrong` ones `error` metres off. Heading
// is stiff, so the chain bends in x alone and least squares puts its end
// near the closures' mean.
Graph closedChain(int right, int wrong, double error, double odometry_info) {
  Graph g;
  const int n = 21;
  const Eigen::Matrix3d odometry = Eigen::Vector3d(odometry_info, odometry_info, 1e6).asDiagonal();
  const Eigen::Matrix3d closure = Eigen::Vector3d(100, 100, 1e4).asDiagonal();
  for (int i = 0; i < n; ++i) g.initial.insert(X(i), Pose2(i, 0, 0));
  for (int i = 0; i + 1 < n; ++i) g.add(between(i, i + 1, 1, odometry));
  for (int k = 0; k < right; ++k) g.add(between(0, n - 1, n - 1, closure));
  for (int k = 0; k < wrong; ++k) g.add(between(0, n - 1, n - 1 + error, closure));
  return g;
}

struct Outcome {
  UpdateResult result;
  double end = 0;  // x of the chain's last pose
  long adopted = 0;
};

Outcome batch(const Graph& g, const std::string& spec) {
  Registry base;
  apps::setUpRegistry(base, {});
  const Registry reg = apps::robustRegistry(base);
  std::unique_ptr<Backend> b = reg.makeBackend(spec);
  Outcome out;
  out.result = b->update(ThesisProtocol(g).batch());
  out.end = b->estimate().pose(X(20)).x;
  const auto* gnc = dynamic_cast<const GraduatedNonConvexity*>(b.get());
  EXPECT_NE(gnc, nullptr);
  if (gnc) out.adopted = gnc->alternativesAdopted();
  return out;
}

// Five wrong closures that agree with each other outvote three right ones
// at the least-squares start, so GNC keeps the wrong five; bending the
// chain 8.5 m (about 40) and rejecting the right three (3 c2, 74 in all)
// costs more than rejecting the wrong five (5 c2, 57), so the answer is a
// local minimum of the truncated objective. Re-solving with the rejected
// closures alone finds the cheaper one.
TEST(AnswerDoubt, GncThatEndsInALocalMinimumIsNotOk) {
  const Graph g = closedChain(3, 5, 8.5, 1 / 0.09);
  const Outcome off = batch(g, "cholesky:robust=gnc-tls,gnc_doubt=off");
  ASSERT_TRUE(off.result.status.ok()) << off.result.status.message;
  ASSERT_GT(off.end, 27) << "GNC no longer falls for the wrong group: the test needs a new graph";

  const Outcome report = batch(g, "cholesky:robust=gnc-tls,gnc_doubt=report");
  EXPECT_EQ(report.result.status.code, Status::kUncertain);
  EXPECT_TRUE(names(report.result.status, "cheaper alternative")) << report.result.status.message;
  EXPECT_GT(report.end, 27);  // reported, not changed

  const Outcome adopt = batch(g, "cholesky:robust=gnc-tls");
  EXPECT_TRUE(adopt.result.status.ok()) << adopt.result.status.message;
  EXPECT_EQ(adopt.adopted, 1);
  EXPECT_NEAR(adopt.end, 20, 0.01);
}

TEST(AnswerDoubt, GncAtTheGlobalMinimumStaysOk) {
  // The right closures outnumber the wrong ones: GNC ends at the right map.
  const Outcome r =
      batch(closedChain(4, 3, 8.5, 1 / 0.09), "cholesky:robust=gnc-tls,gnc_doubt=report");
  EXPECT_TRUE(r.result.status.ok()) << r.result.status.message;
  EXPECT_NEAR(r.end, 20, 0.01);
  // One closure that least squares would absorb: rejecting it is cheaper
  // than the bending, and the alternative (taking it) is not.
  const Outcome one = batch(closedChain(0, 1, 8.5, 1 / 0.09), "cholesky:robust=gnc-tls");
  EXPECT_TRUE(one.result.status.ok()) << one.result.status.message;
}

// Stiff odometry: every closure off by metres is rejected at once.
Graph stiffChainWith(int right, const std::vector<double>& errors) {
  Graph g = closedChain(right, 0, 0, 1e4);
  for (double e : errors)
    g.add(between(0, 20, 20 + e, Eigen::Vector3d(100, 100, 1e4).asDiagonal()));
  return g;
}

TEST(AnswerDoubt, GncThatRejectsMostClosuresIsUncertain) {
  const std::vector<double> six = {5, -5, 7, -7, 9, -9}, four = {5, -5, 7, -7};
  const Outcome most = batch(stiffChainWith(4, six), "cholesky:robust=gnc-tls");
  EXPECT_EQ(most.result.status.code, Status::kUncertain);
  EXPECT_TRUE(names(most.result.status, "6 of 10")) << most.result.status.message;
  const Outcome some = batch(stiffChainWith(6, four), "cholesky:robust=gnc-tls");
  EXPECT_TRUE(some.result.status.ok()) << some.result.status.message;
  // Off: the same answer, not judged.
  EXPECT_TRUE(
      batch(stiffChainWith(4, six), "cholesky:robust=gnc-tls,gnc_doubt=off").result.status.ok());
}

// AprilSAM gives the residual covariance that weighs the share rule
// (near_misses.h). On the stiff chain the map knows the relative pose of
// its ends to 0.02 m against the closures' 0.1 m: closures 5-9 m off are
// refuted hundreds of c2 beyond their test, so six of them rejected beside
// four right ones leave the answer ok. Closures 0.5-0.7 m off sit 2-4 c2
// beyond it: the map refutes them only just, so others of their kind could
// have been accepted, and six rejected of ten is doubt.
TEST(AnswerDoubt, MostRejectedIsDoubtOnlyWhereTheMapDoesNotRefuteThem) {
  const Outcome far = batch(stiffChainWith(4, {5, -5, 7, -7, 9, -9}), "aprilsam:robust=gnc-tls");
  EXPECT_TRUE(far.result.status.ok()) << far.result.status.message;
  EXPECT_NEAR(far.end, 20, 0.01);
  const Outcome near =
      batch(stiffChainWith(4, {0.5, -0.5, 0.6, -0.6, 0.7, -0.7}), "aprilsam:robust=gnc-tls");
  EXPECT_EQ(near.result.status.code, Status::kUncertain);
  EXPECT_TRUE(names(near.result.status, "6 of 10")) << near.result.status.message;
  EXPECT_TRUE(names(near.result.status, "does not refute")) << near.result.status.message;
  EXPECT_NEAR(near.end, 20, 0.01);
}

// One right closure across odometry of 1 m sigma a step: it alone knows
// where the chain's end is (leverage 0.9995), and the nine closures 5-9 m
// off are refuted only by the map it makes. Had it been false, the map
// would refute the true ones as clearly: six of ten rejected is doubt.
TEST(AnswerDoubt, MostRejectedIsDoubtWhereTheMapRestsOnAClosureAlone) {
  Graph g = closedChain(1, 0, 0, 1);
  for (double e : {5.0, -5.0, 6.0, -6.0, 7.0, -7.0, 8.0, -8.0, 9.0})
    g.add(between(0, 20, 20 + e, Eigen::Vector3d(100, 100, 1e4).asDiagonal()));
  const Outcome r = batch(g, "aprilsam:robust=gnc-tls");
  EXPECT_EQ(r.result.status.code, Status::kUncertain);
  EXPECT_TRUE(names(r.result.status, "9 of 10")) << r.result.status.message;
  EXPECT_TRUE(names(r.result.status, "1 accepted closure(s) hold a direction of the map alone"))
      << r.result.status.message;
}

TEST(AnswerDoubt, TheOptionIsCheckedByName) {
  Registry base;
  apps::setUpRegistry(base, {});
  const Registry reg = apps::robustRegistry(base);
  try {
    reg.makeBackend("cholesky:robust=gnc-tls,gnc_doubt=maybe");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_TRUE(std::string(e.what()).find("gnc_doubt") != std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hamal::robust
