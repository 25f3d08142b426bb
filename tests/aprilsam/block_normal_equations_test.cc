// Tests of BlockNormalEquations (backends/aprilsam/block_normal_equations.h,
// thesis eq. 3.5-3.7): the blocks of J^T J and -J^T r it assembles are the
// plain loops' numbers to the bit, for pose (3) and point (2) sides, so
// that its pose kernel leaves every batch, and every run, what it was.
#include "backends/aprilsam/block_normal_equations.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace hamal::aprilsam {
namespace {

// ja^T jc (column-major da x dc) for row-major m x da and m x dc, summed
// from zero in t's order: what the system must hold.
void plainJtJ(const double* ja, const double* jc, int m, int da, int dc, double* out) {
  for (int j = 0; j < dc; ++j)
    for (int i = 0; i < da; ++i) {
      double s = 0;
      for (int t = 0; t < m; ++t) s += ja[t * da + i] * jc[t * dc + j];
      out[i + j * da] = s;
    }
}

TEST(BlockNormalEquations, BlocksAreThePlainProductsBitForBit) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n01;
  // {residual, first key, second key} dimensions.
  const int kDims[][3] = {{3, 3, 3}, {3, 3, 2}, {3, 2, 3}, {2, 3, 3},
                          {2, 2, 3}, {3, 2, 2}, {3, 3, 3}};
  for (int trial = 0; trial < 300; ++trial) {
    const int* d = kDims[trial % 7];
    const int m = d[0];
    const int dims[2] = {d[1], d[2]};
    const int pos[2] = {0, 1};
    // Magnitudes over many decades, so that any change in the order of the
    // sums would show in the last bits.
    const double scale = std::pow(10.0, static_cast<int>(rng() % 12) - 6);
    Linearization lin;
    lin.residual.resize(m);
    for (int t = 0; t < m; ++t) lin.residual[t] = n01(rng);
    lin.jacobians.resize(2);
    for (int k = 0; k < 2; ++k) {
      lin.jacobians[k].resize(m, dims[k]);
      for (int i = 0; i < m * dims[k]; ++i) lin.jacobians[k].data()[i] = n01(rng) * scale;
    }
    // Added, and taken out again (sign -1) as a relinearisation does.
    const double sign = trial % 2 ? -1.0 : 1.0;
    BlockNormalEquations neq;
    neq.clear(2);
    neq.add(lin, pos, dims, sign);
    for (int a = 0; a < 2; ++a) {
      ASSERT_TRUE(neq.hasRow(a));
      for (const auto& block : neq.row(a)) {
        const int c = block.col;
        double expected[9];
        plainJtJ(lin.jacobians[a].data(), lin.jacobians[c].data(), m, dims[a], dims[c], expected);
        if (sign != 1.0)
          for (int t = 0; t < dims[a] * dims[c]; ++t) expected[t] *= sign;
        EXPECT_EQ(
            std::memcmp(expected, neq.values() + block.offset, sizeof(double) * dims[a] * dims[c]),
            0)
            << "trial " << trial << " block (" << a << ", " << c << ")";
      }
      for (int i = 0; i < dims[a]; ++i) {
        double s = 0;
        for (int t = 0; t < m; ++t) s += lin.jacobians[a].data()[t * dims[a] + i] * lin.residual[t];
        const double expected = 0.0 - sign * s;
        EXPECT_EQ(std::memcmp(&expected, neq.rhs(a) + i, sizeof expected), 0) << "trial " << trial;
      }
    }
  }
}

}  // namespace
}  // namespace hamal::aprilsam
