// Tests of the small-block kernels of AprilSAM's factorisation
// (backends/aprilsam/dense_blocks.h, thesis sec. 3.4.1): the pose kernel of
// the left-looking loop gives addAtB's numbers to the bit, so that the
// factor, and every run, stay what they were.
#include "backends/aprilsam/dense_blocks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace hamal::aprilsam {
namespace {

TEST(DenseBlocks, PoseKernelIsAddAtBBitForBit) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 1000; ++trial) {
    double a[9], b[9], w[9];
    // Magnitudes over many decades, so that any change in the order of the
    // sums would show in the last bits.
    const double scale = std::pow(10.0, static_cast<int>(rng() % 12) - 6);
    for (int i = 0; i < 9; ++i) {
      a[i] = n01(rng) * scale;
      b[i] = n01(rng);
      w[i] = n01(rng) * scale;
    }
    double at[9];
    for (int i = 0; i < 3; ++i)
      for (int t = 0; t < 3; ++t) at[i + t * 3] = a[t + i * 3];
    for (const double sign : {1.0, -1.0}) {
      double expected[9], got[9];
      std::memcpy(expected, w, sizeof w);
      std::memcpy(got, w, sizeof w);
      addAtB(expected, a, b, 3, 3, 3, sign);
      if (sign < 0)
        addAtBPose<3, true>(got, at, b);
      else
        addAtBPose<3, false>(got, at, b);
      EXPECT_EQ(std::memcmp(expected, got, sizeof got), 0) << "trial " << trial << " sign " << sign;
    }
  }
}

}  // namespace
}  // namespace hamal::aprilsam
