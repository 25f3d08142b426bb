// Bad numbers through every built-in back-end: a factor that names one
// variable twice is refused before anything is recorded (Ceres would abort
// on it), a result whose chi2 is not finite is never
// "ok", and cholesky tells ill-conditioning (one factor's information far
// above the others') from a direction nothing constrains.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "backends/builtins.h"
#include "core/error.h"
#include "core/metrics.h"
#include "core/registry.h"
#include "factors/between_factor.h"
#include "factors/prior_factor.h"

namespace hamal {
namespace {

Registry builtins() {
  Registry r;
  registerBuiltins(r);
  return r;
}

std::vector<std::string> backendNames(const Registry& r) {
  std::vector<std::string> names;
  for (const BackendInfo* info : r.backends()) names.push_back(info->name);
  return names;
}

// A straight chain of `n` poses 1 m apart with a prior on x0, as one batch
// step, plus `extra` factors.
Step chain(int n, std::vector<FactorPtr> extra) {
  Step s;
  const Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  s.new_factors.push_back(std::make_shared<PriorFactor>(X(0), Pose2(), 1e4 * info));
  for (int i = 0; i < n; ++i) s.new_values.insert(X(i), Pose2(i + 0.01 * std::sin(i), 0, 0));
  for (int i = 0; i + 1 < n; ++i)
    s.new_factors.push_back(std::make_shared<BetweenFactor>(X(i), X(i + 1), Pose2(1, 0, 0), info));
  for (auto& f : extra) s.new_factors.push_back(f);
  return s;
}

bool contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

TEST(BadNumbers, AFactorOnOneVariableTwiceIsRefusedByEveryBackend) {
  const Registry registry = builtins();
  for (const std::string& name : backendNames(registry)) {
    SCOPED_TRACE(name);
    auto backend = registry.makeBackend(name);
    Step s = chain(3, {std::make_shared<BetweenFactor>(X(1), X(1), Pose2(1, 0, 0),
                                                       Eigen::Matrix3d::Identity())});
    try {
      backend->update(s);
      ADD_FAILURE() << "accepted an edge from x1 to itself";
    } catch (const Error& e) {
      EXPECT_TRUE(contains(e.what(), "factor EDGE_SE2 names variable x1 twice")) << e.what();
    }
    // Nothing was recorded: the same step without the bad edge is accepted.
    s.new_factors.pop_back();
    const UpdateResult r = backend->update(s);
    EXPECT_TRUE(r.status.ok()) << r.status.message;
  }
}

TEST(BadNumbers, AnAbsurdMeasurementIsNeverOk) {
  // No estimate gives this loop closure a finite chi2: every back-end must
  // say so, naming the factor or a variable, instead of "ok" with chi2 inf.
  const Registry registry = builtins();
  for (const std::string& name : backendNames(registry)) {
    SCOPED_TRACE(name);
    auto backend = registry.makeBackend(name);
    const UpdateResult r =
        backend->update(chain(6, {std::make_shared<BetweenFactor>(X(0), X(5), Pose2(1e300, 0, 0),
                                                                  Eigen::Matrix3d::Identity())}));
    EXPECT_FALSE(r.status.ok());
    EXPECT_FALSE(r.status.keys.empty()) << r.status.message;
    EXPECT_FALSE(r.status.message.empty());
  }
}

TEST(BadNumbers, ANonFiniteChi2IsNeverOk) {
  // Two priors that disagree by 10 m with information 1e306: each term is
  // finite where the solve starts and their sum is not. A back-end may solve
  // it (the midpoint is finite) or refuse it; it may not call an infinite
  // chi2 ok.
  const Registry registry = builtins();
  const Eigen::Matrix3d huge = 1e306 * Eigen::Matrix3d::Identity();
  for (const std::string& name : backendNames(registry)) {
    SCOPED_TRACE(name);
    auto backend = registry.makeBackend(name);
    Step s = chain(3, {});
    s.new_factors.push_back(std::make_shared<PriorFactor>(X(2), Pose2(12, 0, 0), huge));
    s.new_factors.push_back(std::make_shared<PriorFactor>(X(2), Pose2(-8, 0, 0), huge));
    const UpdateResult r = backend->update(s);
    double total = 0;
    for (const auto& f : s.new_factors) total += f->chi2(backend->estimate());
    if (r.status.ok()) {
      EXPECT_TRUE(std::isfinite(total)) << "ok with chi2 " << total;
    } else {
      EXPECT_FALSE(r.status.message.empty());
    }
  }
}

TEST(BadNumbers, ACostBeyondWhatRoundingResolvesIsNeverOk) {
  // Finite, but no estimate is resolved: a loop closure of 1e151 m over
  // 1 m odometry (the optimum's chi2 is 3.3e301), and one of 3 m with
  // information 1e150 (the rounding of its residual alone is 1e59 sigma).
  // Ceres and AprilSAM called both converged; cholesky refuses its
  // singular system.
  const Registry registry = builtins();
  const Eigen::Matrix3d unit = Eigen::Matrix3d::Identity();
  const std::vector<FactorPtr> absurd = {
      std::make_shared<BetweenFactor>(X(0), X(2), Pose2(1e151, 0, 0), unit),
      std::make_shared<BetweenFactor>(X(0), X(2), Pose2(0, 0, 3), 1e150 * unit)};
  std::vector<std::string> names = backendNames(registry);
  names.push_back("ceres:linear_solver=dense_qr");
  for (const std::string& name : names) {
    for (const FactorPtr& f : absurd) {
      SCOPED_TRACE(name + " " + std::to_string(f->chi2(chain(3, {}).new_values)));
      auto backend = registry.makeBackend(name);
      const UpdateResult r = backend->update(chain(3, {f}));
      EXPECT_EQ(r.status.code, Status::kNumericalFailure) << r.status.message;
      EXPECT_FALSE(r.status.keys.empty()) << r.status.message;
    }
  }
  auto ceres = registry.makeBackend("ceres");
  const UpdateResult r = ceres->update(chain(3, {absurd[0]}));
  // The 1e151 m spread over three edges: each is 1.1e301.
  EXPECT_TRUE(contains(r.status.message,
                       "has chi2 1.11e+301 at the estimate, a residual beyond "
                       "1/eps (4.5e+15) standard deviations"))
      << r.status.message;
  // The bound is far above any chi2 a sane graph reaches: a loop closure
  // 1e6 standard deviations off is still solved and ok.
  auto fine = registry.makeBackend("ceres");
  const UpdateResult off = fine->update(
      chain(3, {std::make_shared<BetweenFactor>(X(0), X(2), Pose2(2, 0, 0), 1e12 * unit)}));
  EXPECT_TRUE(off.status.ok()) << off.status.message;
}

TEST(BadNumbers, ANonFiniteGuessIsNeverOk) {
  // Found by tests/fuzz/step_path_fuzz: ceres, on an update without a
  // solve (every=2), reported ok while a new variable's guess was NaN, and
  // aprilsam-nopredictive while the guess of a variable no factor touched
  // was infinite. Such a step is bad input: every back-end refuses it
  // through checkStep and stays as it was.
  const Registry registry = builtins();
  for (const std::string& name : backendNames(registry)) {
    SCOPED_TRACE(name);
    auto backend = registry.makeBackend(name == "ceres" ? "ceres:every=2" : name);
    Step s = chain(3, {});
    s.new_values = Values();
    s.new_values.insert(X(0), Pose2());
    s.new_values.insert(X(1), Pose2(1, 0, 0));
    s.new_values.insert(X(2), Pose2(std::nan(""), 0, 0));
    EXPECT_THROW(backend->update(s), Error);
    EXPECT_EQ(backend->estimate().size(), 0u);
    // The same step with a finite guess then goes through.
    Step good = chain(3, {});
    const UpdateResult r = backend->update(good);
    EXPECT_TRUE(r.status.ok()) << r.status.message;
  }
}

TEST(BadNumbers, CholeskyNamesTheFactorThatMakesTheSystemIllConditioned) {
  // A loop closure with information 1e12 over odometry with 1: every
  // direction is constrained, the pivots are lost to rounding.
  const Registry registry = builtins();
  auto backend = registry.makeBackend("cholesky");
  const Eigen::Matrix3d strong = 1e12 * Eigen::Matrix3d::Identity();
  const UpdateResult r = backend->update(
      chain(50, {std::make_shared<BetweenFactor>(X(0), X(49), Pose2(49.5, 0.3, 0.1), strong)}));
  ASSERT_FALSE(r.status.ok());
  EXPECT_TRUE(contains(r.status.message, "ill-conditioned")) << r.status.message;
  EXPECT_TRUE(contains(r.status.message, "factor EDGE_SE2 on x0, x49")) << r.status.message;
  EXPECT_TRUE(contains(r.status.message, "condition estimate")) << r.status.message;
  EXPECT_FALSE(contains(r.status.message, "nothing constrains")) << r.status.message;
}

TEST(BadNumbers, CholeskyStillSaysWhenNothingConstrainsAVariable) {
  // x2 hangs on nothing but its initial value: a missing constraint, with
  // factors of alike scales, keeps the old diagnosis.
  const Registry registry = builtins();
  auto backend = registry.makeBackend("cholesky");
  Step s = chain(2, {});
  s.new_values.insert(X(2), Pose2(5, 0, 0));
  const UpdateResult r = backend->update(s);
  ASSERT_FALSE(r.status.ok());
  EXPECT_TRUE(contains(r.status.message, "x2")) << r.status.message;
  EXPECT_TRUE(contains(r.status.message, "nothing constrains it")) << r.status.message;
}

}  // namespace
}  // namespace hamal
