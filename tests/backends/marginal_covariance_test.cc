// Marginal covariances (core/marginals.h): every back-end that offers them
// (cholesky, aprilsam, aprilsam-top, ceres) must give, joint and per
// variable, the blocks of the dense inverse of H = J^T J built from
// core/linearization.h at the back-end's own point of linearisation (the
// estimate; AprilSAM's linearisation points), within 1e-9 relative, on a
// chain with a loop closure and a landmark and on the conformance small
// world; fixed variables' blocks are zero; a failed update, an unknown or
// repeated key are refused.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "backends/aprilsam/aprilsam_backend.h"
#include "backends/builtins.h"
#include "conformance/small_world.h"
#include "core/error.h"
#include "core/linearization.h"
#include "core/marginals.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "protocol/thesis_protocol.h"

namespace hamal {
namespace {

const char* const kBackends[] = {"cholesky", "aprilsam", "aprilsam-top", "ceres"};

// (H^-1)_KK with H = sum J^T J over `factors` at `at`, zero for `fixed`.
Eigen::MatrixXd denseCovariance(const std::vector<FactorPtr>& factors, const Values& at,
                                const std::set<Key>& fixed, const std::vector<Key>& keys) {
  std::map<Key, long> column;
  long n = 0;
  for (Key key : at.keys())
    if (!fixed.count(key)) {
      column[key] = n;
      n += at.dim(key);
    }
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, n);
  Linearization lin;
  for (const FactorPtr& f : factors) {
    std::vector<const double*> params;
    for (Key key : f->keys()) params.push_back(at.data(key));
    EXPECT_TRUE(linearize(*f, params.data(), &lin));
    for (std::size_t a = 0; a < f->keys().size(); ++a)
      for (std::size_t b = 0; b < f->keys().size(); ++b) {
        const Key ka = f->keys()[a], kb = f->keys()[b];
        if (fixed.count(ka) || fixed.count(kb)) continue;
        h.block(column[ka], column[kb], at.dim(ka), at.dim(kb)) +=
            lin.jacobians[a].transpose() * lin.jacobians[b];
      }
  }
  const Eigen::MatrixXd inverse = h.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  long size = 0;
  std::vector<long> places;
  for (Key key : keys) {
    places.push_back(size);
    size += at.dim(key);
  }
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(size, size);
  for (std::size_t i = 0; i < keys.size(); ++i)
    for (std::size_t j = 0; j < keys.size(); ++j) {
      if (fixed.count(keys[i]) || fixed.count(keys[j])) continue;
      out.block(places[i], places[j], at.dim(keys[i]), at.dim(keys[j])) =
          inverse.block(column[keys[i]], column[keys[j]], at.dim(keys[i]), at.dim(keys[j]));
    }
  return out;
}

// Where the back-end linearises: AprilSAM's linearisation points, else the
// estimate.
Values linearizationPoint(Backend& backend) {
  auto* april = dynamic_cast<AprilSamBackend*>(&backend);
  if (!april) return backend.estimate();
  Values at;
  for (Key key : backend.estimate().keys()) at.insertEntry(key, april->linearizationPoint(key));
  return at;
}

// Joint of `keys` and each variable alone, against the dense inverse.
void expectDenseInverse(Backend& backend, const std::string& spec,
                        const std::vector<FactorPtr>& factors, const std::set<Key>& fixed,
                        const std::vector<Key>& keys) {
  auto* marginals = dynamic_cast<MarginalCovariances*>(&backend);
  ASSERT_NE(marginals, nullptr) << spec;
  const Values at = linearizationPoint(backend);
  const Eigen::MatrixXd expected = denseCovariance(factors, at, fixed, keys);
  Eigen::MatrixXd joint;
  const Status s = marginals->jointMarginalCovariance(keys, &joint);
  ASSERT_TRUE(s.ok()) << spec << ": " << s.message;
  ASSERT_EQ(joint.rows(), expected.rows()) << spec;
  EXPECT_LE((joint - expected).cwiseAbs().maxCoeff(), 1e-9 * expected.cwiseAbs().maxCoeff())
      << spec << "\njoint:\n"
      << joint << "\ndense:\n"
      << expected;
  for (Key key : at.keys()) {
    Eigen::MatrixXd one;
    ASSERT_TRUE(marginals->marginalCovariance(key, &one).ok()) << spec << " " << key.str();
    const Eigen::MatrixXd want = denseCovariance(factors, at, fixed, {key});
    ASSERT_EQ(one.rows(), at.dim(key));
    if (fixed.count(key)) {
      EXPECT_TRUE(one.isZero(0)) << spec << " " << key.str();
      continue;
    }
    EXPECT_LE((one - want).cwiseAbs().maxCoeff(), 1e-9 * want.cwiseAbs().maxCoeff())
        << spec << " " << key.str() << "\n"
        << one << "\ndense:\n"
        << want;
  }
}

// A chain of eight poses with a prior, a loop closure x7-x0 and a landmark
// seen from x2 and x5.
Step chainWithLoopAndLandmark() {
  Step s = testing::chainStep(8);
  const Eigen::Matrix3d info = Eigen::Vector3d(50, 80, 200).asDiagonal();
  s.new_factors.push_back(
      std::make_shared<BetweenFactor>(X(7), X(0), Pose2(-6.9, 0.2, 0.05), info));
  Eigen::Matrix2d obs;
  obs << 40, 5, 5, 30;
  s.new_values.insert(L(0), Point2(2.5, 1.1));
  s.new_factors.push_back(std::make_shared<PosePointFactor>(X(2), L(0), Point2(0.4, 1.0), obs));
  s.new_factors.push_back(std::make_shared<PosePointFactor>(X(5), L(0), Point2(-2.6, 0.9), obs));
  return s;
}

class MarginalCovariance : public ::testing::TestWithParam<const char*> {
 protected:
  MarginalCovariance() { registerBuiltins(registry_); }
  Registry registry_;
};

TEST_P(MarginalCovariance, ChainWithLoopAndLandmarkMatchesTheDenseInverse) {
  auto backend = registry_.makeBackend(GetParam());
  const Step step = chainWithLoopAndLandmark();
  ASSERT_TRUE(backend->update(step).status.ok());
  expectDenseInverse(*backend, GetParam(), step.new_factors, {}, {X(7), L(0), X(3), X(0)});
}

TEST_P(MarginalCovariance, SmallWorldWithAFixedPoseMatchesTheDenseInverse) {
  const Graph g = testing::smallWorld();
  Step step;
  step.new_values = ThesisProtocol(g).initialValues();  // with the landmarks' guesses
  step.new_factors = g.factors;
  step.fixed = {X(0)};
  auto backend = registry_.makeBackend(GetParam());
  ASSERT_TRUE(backend->update(step).status.ok());
  expectDenseInverse(*backend, GetParam(), step.new_factors, {X(0)},
                     {X(23), L(2), X(0), X(11), L(0)});
}

// Step by step through the thesis protocol: AprilSAM's R, updated
// incrementally, by batches and (aprilsam-top) by re-eliminations of the
// top, is H at its linearisation points, which lag the estimate.
TEST_P(MarginalCovariance, ProtocolStepsMatchTheDenseInverse) {
  // aprilsam-top decides for a batch whenever 3 nodes moved by 0.01 and
  // re-eliminates the top every time (incremental_cholesky_test's setting).
  const std::string spec = std::string(GetParam()) == "aprilsam-top"
                               ? "aprilsam-top:nl_t=3,delta_t=0.01,top_share=1"
                               : GetParam();
  const Graph g = testing::smallWorld();
  ThesisProtocol protocol(g);
  auto backend = registry_.makeBackend(spec);
  std::vector<FactorPtr> factors;
  int top = 0;  // steps whose batch decision re-eliminated the top only
  for (std::size_t i = 0; i < protocol.size(); ++i) {
    const Step step = protocol.step(i, backend->estimate());
    factors.insert(factors.end(), step.new_factors.begin(), step.new_factors.end());
    const UpdateResult r = backend->update(step);
    ASSERT_TRUE(r.status.ok()) << spec << " step " << i;
    top += r.reason.find("top re-eliminated") != std::string::npos;
    std::vector<Key> keys = {protocol.pose(i)};
    if (i > 0) keys.push_back(protocol.pose(0));
    expectDenseInverse(*backend, spec + " step " + std::to_string(i), factors, {}, keys);
  }
  if (spec != GetParam()) EXPECT_GT(top, 0) << "the top's re-elimination never ran";
}

TEST_P(MarginalCovariance, AFailedUpdateGivesAStatusNotNumbers) {
  // No prior: nothing anchors the chain, so the update fails.
  Step step = testing::chainStep(4);
  step.new_factors.erase(step.new_factors.begin());
  auto backend = registry_.makeBackend(GetParam());
  ASSERT_FALSE(backend->update(step).status.ok());
  Eigen::MatrixXd untouched = Eigen::MatrixXd::Constant(1, 1, 42);
  const Status s =
      dynamic_cast<MarginalCovariances&>(*backend).marginalCovariance(X(1), &untouched);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message.find("last update"), std::string::npos) << s.message;
  EXPECT_EQ(untouched(0, 0), 42);
}

TEST_P(MarginalCovariance, UnknownOrRepeatedKeysThrow) {
  auto backend = registry_.makeBackend(GetParam());
  ASSERT_TRUE(backend->update(testing::chainStep(3)).status.ok());
  auto& marginals = dynamic_cast<MarginalCovariances&>(*backend);
  Eigen::MatrixXd out;
  EXPECT_THROW(marginals.marginalCovariance(X(9), &out), Error);
  EXPECT_THROW(marginals.jointMarginalCovariance({X(1), X(1)}, &out), Error);
}

INSTANTIATE_TEST_SUITE_P(Backends, MarginalCovariance, ::testing::ValuesIn(kBackends),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string name = info.param;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

}  // namespace
}  // namespace hamal
