// Test-local factor kinds for the reader/writer tests: a linear "between" of
// two poses and a linear pose-landmark offset, registered under the tags of
// each format with that format's information convention (graph_io.h). They
// let the reader be tested without the real factors (factors/), so a reader
// bug and a factor bug never hide each other.
#pragma once

#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/factor.h"
#include "core/graph_io.h"
#include "core/information.h"
#include "core/line_tokens.h"
#include "core/registry.h"

namespace hamal::io_test {

// e = U (x_b - x_a - z): linear, so chi2 is easy to check by hand.
template <int N, int A, int B>
class LinearCost : public ceres::SizedCostFunction<N, A, B> {
 public:
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  LinearCost(const Vec& z, const Mat& sqrt_info) : z_(z), u_(sqrt_info) {}
  bool Evaluate(double const* const* p, double* residual, double**) const override {
    Vec e;
    for (int i = 0; i < N; ++i) e(i) = p[1][i] - p[0][i] - z_(i);
    Eigen::Map<Vec> r(residual);
    r = u_ * e;
    return true;
  }

 private:
  Vec z_;
  Mat u_;
};

class FakeBetween : public Factor {
 public:
  FakeBetween(Key a, Key b, const Eigen::Vector3d& z, const Eigen::Matrix3d& info)
      : Factor({a, b}, std::make_unique<LinearCost<3, 3, 3>>(z, sqrtInformation(info))),
        z_(z),
        info_(info) {}
  std::string tag() const override { return "EDGE_SE2"; }
  void writeFields(std::ostream& os) const override {
    os << keys()[0].index() << ' ' << keys()[1].index() << ' ' << z_(0) << ' ' << z_(1) << ' '
       << z_(2);
    writeUpperTriangle(os, info_);
  }
  Eigen::Vector3d z_;
  Eigen::Matrix3d info_;
};

class FakeLandmark : public Factor {
 public:
  FakeLandmark(Key pose, Key landmark, const Eigen::Vector2d& z, const Eigen::Matrix2d& info)
      : Factor({pose, landmark}, std::make_unique<LinearCost<2, 3, 2>>(z, sqrtInformation(info))),
        z_(z),
        info_(info) {}
  std::string tag() const override { return "EDGE_SE2_XY"; }
  void writeFields(std::ostream& os) const override {
    os << keys()[0].index() << ' ' << keys()[1].index() << ' ' << z_(0) << ' ' << z_(1);
    writeUpperTriangle(os, info_);
  }
  Eigen::Vector2d z_;
  Eigen::Matrix2d info_;
};

inline FactorPtr parseBetween(LineTokens& t, MatrixLayout layout) {
  const Key a = X(t.id("a")), b = X(t.id("b"));
  const double dx = t.number("dx"), dy = t.number("dy"), dth = t.number("dth");
  const Eigen::Matrix3d info = readInformation3(t, layout);
  t.expectEnd();
  return std::make_shared<FakeBetween>(a, b, Eigen::Vector3d(dx, dy, dth), info);
}

inline FactorPtr parseLandmark(LineTokens& t, MatrixLayout layout) {
  const Key a = X(t.id("pose")), l = L(t.id("landmark"));
  const double x = t.number("x"), y = t.number("y");
  const Eigen::Matrix2d info = readInformation2(t, layout);
  t.expectEnd();
  return std::make_shared<FakeLandmark>(a, l, Eigen::Vector2d(x, y), info);
}

// The registry the reader tests use in place of registerFactors().
inline Registry fakeRegistry() {
  Registry r;
  auto between = [](MatrixLayout layout) {
    return [layout](LineTokens& t) { return parseBetween(t, layout); };
  };
  auto landmark = [](MatrixLayout layout) {
    return [layout](LineTokens& t) { return parseLandmark(t, layout); };
  };
  r.addFactor({"g2o", "EDGE_SE2", "fake between", between(MatrixLayout::kG2oInformation)});
  r.addFactor({"g2o", "EDGE_SE2_XY", "fake landmark", landmark(MatrixLayout::kG2oInformation)});
  r.addFactor({"toro", "EDGE2", "fake between", between(MatrixLayout::kToroInformation)});
  r.addFactor({"gtsam", "EDGE2", "fake between", between(MatrixLayout::kG2oCovariance)});
  r.addFactor({"gtsam", "ODOMETRY", "fake between", between(MatrixLayout::kG2oCovariance)});
  r.addFactor({"gtsam", "LANDMARK", "fake landmark", landmark(MatrixLayout::kG2oCovariance)});
  return r;
}

inline Graph readText(const std::string& text, const std::string& name, const Registry& registry,
                      Format format = Format::kAuto) {
  std::istringstream in(text);
  return readGraph(in, name, registry, format);
}

// Whether `text` contains `part`, showing both when it does not.
inline ::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "'\n  does not contain\n'" << part << "'";
}
#define EXPECT_HAS(text, part) EXPECT_TRUE(::hamal::io_test::contains((text), (part)))

// The message of the hamal::Error `f` throws ("" and a test failure if none).
inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a hamal::Error: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no hamal::Error thrown";
  return "";
}

}  // namespace hamal::io_test
