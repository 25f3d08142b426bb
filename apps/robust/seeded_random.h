// SeededRandom: the random numbers of the robust benchmark's spoiling tool
// (apps/robust/README.md), the same on every platform for a seed, so that a
// spoiled dataset is named by (source, policy, outliers, seed) alone.
//
// std::mt19937_64 is specified bit for bit by the standard; the
// std::*_distribution algorithms are not (libstdc++ and libc++ differ), so
// the integers (unbiased rejection) and the normals (Box-Muller) are drawn
// here, as apps/generator/manhattan_world.cc does for its world.
#pragma once

#include <cstdint>
#include <random>

namespace hamal::apps {

class SeededRandom {
 public:
  explicit SeededRandom(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, n); n must be positive.
  std::uint64_t below(std::uint64_t n) {
    // Rejecting the top partial block of 2^64 keeps every residue equally likely.
    const std::uint64_t limit = ~std::uint64_t{0} - (~std::uint64_t{0} % n);
    std::uint64_t x;
    do {
      x = engine_();
    } while (x >= limit);
    return x % n;
  }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(engine_() >> 11) * 0x1.0p-53; }
  // Standard normal (Box-Muller; one value per call, the pair's second kept).
  double normal();

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0;
};

}  // namespace hamal::apps
