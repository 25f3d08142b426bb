// libFuzzer target: the step path, Backend::update (core/backend.h), of
// every built-in back-end, on a small graph decoded from arbitrary bytes
// (tests/fuzz/README.md): up to 6 poses and 3 landmarks whose
// initial values, measurements and information span 1e-18..1e60 and include
// NaN and infinity, and factors on any of them, a variable named twice or
// one no step adds included, fed in up to 6 steps.
//
// A back-end may refuse a step (hamal::Error, the input contract) or report
// a non-ok Status; it may not abort, crash, trip a sanitizer, throw anything
// else, or report ok with an estimate that is not finite.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "backends/builtins.h"
#include "core/backend.h"
#include "core/error.h"
#include "factors/between_factor.h"
#include "factors/pose_point_factor.h"
#include "factors/prior_factor.h"
#include "factors/range_bearing_factor.h"

namespace {

using hamal::Key;

const hamal::Registry& registry() {
  static const hamal::Registry* r = [] {
    auto* reg = new hamal::Registry;
    hamal::registerBuiltins(*reg);
    return reg;
  }();
  return *r;
}

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "step_path_fuzz: %s\n", what.c_str());
  std::abort();
}

// Reads the input byte by byte; past its end every byte is 0.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  int upTo(int n) { return byte() % (n + 1); }
  // Mostly ordinary numbers, sometimes extreme ones.
  double number() {
    const std::uint8_t mode = byte();
    const double small = (static_cast<int>(byte()) - 128) / 16.0;
    if (mode < 200) return small;
    if (mode < 240) return std::ldexp(small, static_cast<int>(byte() % 200));  // up to ~1e60
    if (mode < 248) return std::ldexp(small, -static_cast<int>(byte() % 64));  // down to ~1e-19
    if (mode < 252) return std::numeric_limits<double>::quiet_NaN();
    return (mode & 1 ? -1 : 1) * std::numeric_limits<double>::infinity();
  }
  // A positive weight 2^-60..2^60: the information stays SPD by construction
  // (diagonal plus a bounded correlation), its scale varies wildly.
  double weight() { return std::ldexp(1.0, static_cast<int>(byte() % 121) - 60); }
  Eigen::Matrix3d information3() {
    const Eigen::Vector3d d(weight(), weight(), weight());
    Eigen::Matrix3d m = d.asDiagonal();
    m(0, 1) = m(1, 0) = 0.5 * std::sqrt(d(0) * d(1)) * (byte() / 255.0 - 0.5);
    return m;
  }
  Eigen::Matrix2d information2() {
    const Eigen::Vector2d d(weight(), weight());
    Eigen::Matrix2d m = d.asDiagonal();
    m(0, 1) = m(1, 0) = 0.5 * std::sqrt(d(0) * d(1)) * (byte() / 255.0 - 0.5);
    return m;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

struct Graph {
  std::vector<hamal::Step> steps;
};

Graph decode(const std::uint8_t* data, std::size_t size) {
  Bytes in(data, size);
  const int poses = 1 + in.upTo(5);
  const int landmarks = in.upTo(3);
  const int factors = 1 + in.upTo(15);
  // Variable i of the step it enters in: poses first, then landmarks.
  std::vector<hamal::Step> steps(poses);
  for (int i = 0; i < poses; ++i) {
    steps[i].index = i;
    steps[i].new_values.insert(hamal::X(i), hamal::Pose2(in.number(), in.number(), in.number()));
  }
  for (int l = 0; l < landmarks; ++l)
    steps[in.upTo(poses - 1)].new_values.insert(hamal::L(l),
                                                hamal::Point2(in.number(), in.number()));
  // One more pose id than exists, so that a factor may name a variable no
  // step adds.
  auto pose = [&] { return hamal::X(in.upTo(poses)); };
  auto landmark = [&] { return hamal::L(in.upTo(landmarks)); };
  for (int f = 0; f < factors; ++f) {
    hamal::FactorPtr factor;
    switch (in.upTo(3)) {
      case 0: {
        const Key a = pose(), b = pose();
        factor = std::make_shared<hamal::BetweenFactor>(
            a, b, hamal::Pose2(in.number(), in.number(), in.number()), in.information3());
        break;
      }
      case 1:
        factor = std::make_shared<hamal::PriorFactor>(
            pose(), hamal::Pose2(in.number(), in.number(), in.number()), in.information3());
        break;
      case 2: {
        const Key p = pose(), l = landmark();
        factor = std::make_shared<hamal::PosePointFactor>(
            p, l, hamal::Point2(in.number(), in.number()), in.information2());
        break;
      }
      default: {
        const Key p = pose(), l = landmark();
        const double range = in.number(), bearing = in.number();
        factor =
            std::make_shared<hamal::RangeBearingFactor>(p, l, range, bearing, in.information2());
        break;
      }
    }
    steps[in.upTo(poses - 1)].new_factors.push_back(factor);
  }
  return {steps};
}

void checkEstimate(const hamal::Backend& backend, const std::string& name) {
  for (const auto& [key, entry] : backend.estimate())
    for (int i = 0; i < hamal::dimension(entry.type); ++i)
      if (!std::isfinite(entry.data[i]))
        bug(name + ": status ok with the estimate of " + key.str() + " not finite");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4096) return 0;
  Graph graph;
  try {
    graph = decode(data, size);
  } catch (const hamal::Error&) {
    return 0;  // a factor refused its own arguments (e.g. a NaN information)
  }
  for (const hamal::BackendInfo* info : registry().backends()) {
    std::unique_ptr<hamal::Backend> backend = registry().makeBackend(info->name);
    for (const hamal::Step& step : graph.steps) {
      hamal::UpdateResult result;
      try {
        result = backend->update(step);
      } catch (const hamal::Error&) {
        continue;  // refused by the input contract; the back-end is as it was
      } catch (const std::exception& e) {
        bug(info->name + " threw something other than hamal::Error: " + e.what());
      }
      if (result.status.ok()) checkEstimate(*backend, info->name);
    }
  }
  return 0;
}
