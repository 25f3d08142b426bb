// Tests of PooledArray (backends/aprilsam/pooled_array.h), the storage of
// R's pooled rows and of the normal equations' blocks: its contents survive
// every growth and release, across the line between heap arrays and arrays
// in their own huge-page mappings, and copies and moves own their numbers.
#include "backends/aprilsam/pooled_array.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <utility>

namespace hamal::aprilsam {
namespace {

// Fills [from, to) with values derived from the index, so that a lost or
// shifted number shows.
void fill(PooledArray<double>& a, std::size_t from, std::size_t to) {
  for (std::size_t i = from; i < to; ++i) a[i] = 0.5 * static_cast<double>(i) + 1.0;
}

::testing::AssertionResult holds(const PooledArray<double>& a, std::size_t n) {
  if (a.capacity() < n) return ::testing::AssertionFailure() << "capacity " << a.capacity();
  for (std::size_t i = 0; i < n; ++i)
    if (a[i] != 0.5 * static_cast<double>(i) + 1.0)
      return ::testing::AssertionFailure() << "number " << i << " is " << a[i];
  return ::testing::AssertionSuccess();
}

// 2 MiB of doubles: the size from which an array has its own mapping.
constexpr std::size_t kHugeDoubles = (std::size_t{1} << 21) / sizeof(double);

TEST(PooledArray, GrowthKeepsEveryNumberAcrossTheMappingThreshold) {
  PooledArray<double> a;
  EXPECT_EQ(a.capacity(), 0u);
  std::size_t used = 0;
  // One number at a time up to 3 huge pages: every doubling, the move from
  // the heap to a mapping and the growth of a mapping.
  while (used < 3 * kHugeDoubles) {
    const std::size_t before = a.capacity();
    a.reserve(used + 1);
    ASSERT_GE(a.capacity(), used + 1);
    if (a.capacity() != before) {
      // Geometric growth: a run of pushes reallocates O(log n) times.
      ASSERT_GE(a.capacity(), std::min<std::size_t>(2 * before, 16 + 2 * before));
      ASSERT_TRUE(holds(a, used)) << "after growing to " << a.capacity();
    }
    a[used] = 0.5 * static_cast<double>(used) + 1.0;
    ++used;
  }
  EXPECT_TRUE(holds(a, used));
#if defined(__linux__)
  // A large array is sized in whole huge pages and starts on one.
  EXPECT_EQ(a.capacity() % kHugeDoubles, 0u);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(a.data()) % (std::size_t{1} << 21), 0u);
#endif
}

TEST(PooledArray, ReserveNeverShrinksAndReleaseKeepsTheNumbersInUse) {
  PooledArray<double> a;
  a.reserve(4 * kHugeDoubles);
  fill(a, 0, 4 * kHugeDoubles);
  const std::size_t big = a.capacity();
  a.reserve(10);
  EXPECT_EQ(a.capacity(), big);
  // Down to a smaller mapping, then back to the heap, then up again.
  a.release(kHugeDoubles + 5);
  EXPECT_GE(a.capacity(), kHugeDoubles + 5);
  EXPECT_LT(a.capacity(), big);
  EXPECT_TRUE(holds(a, kHugeDoubles + 5));
  a.release(1000);
  EXPECT_EQ(a.capacity(), 1000u);
  EXPECT_TRUE(holds(a, 1000));
  a.reserve(3 * kHugeDoubles);
  EXPECT_TRUE(holds(a, 1000));
  fill(a, 1000, 3 * kHugeDoubles);
  EXPECT_TRUE(holds(a, 3 * kHugeDoubles));
  a.release(0);
  EXPECT_EQ(a.capacity(), 0u);
  a.reserve(7);
  fill(a, 0, 7);
  EXPECT_TRUE(holds(a, 7));
}

TEST(PooledArray, CopiesAndMovesOwnTheirNumbers) {
  for (std::size_t n : {std::size_t{100}, 2 * kHugeDoubles + 3}) {
    PooledArray<double> a;
    a.reserve(n);
    fill(a, 0, n);
    PooledArray<double> b(a);
    EXPECT_TRUE(holds(b, n)) << n;
    EXPECT_NE(a.data(), b.data());
    b[0] = -1;  // the copy is its own
    EXPECT_TRUE(holds(a, n));
    PooledArray<double> c;
    c.reserve(3 * kHugeDoubles);  // assigned over a larger array
    c = a;
    EXPECT_TRUE(holds(c, n));
    PooledArray<double> d(std::move(c));
    EXPECT_TRUE(holds(d, n));
    PooledArray<double> e;
    e = std::move(d);
    EXPECT_TRUE(holds(e, n));
    PooledArray<double> f;
    f.reserve(5);
    f.swap(e);
    EXPECT_TRUE(holds(f, n));
    EXPECT_GE(e.capacity(), 5u);
  }
}

TEST(PooledArray, HoldsIntsToo) {
  PooledArray<int> a;
  for (int i = 0; i < 1 << 20; ++i) {
    a.reserve(static_cast<std::size_t>(i) + 1);
    a[i] = i ^ 0x5a5a;
  }
  for (int i = 0; i < 1 << 20; ++i) ASSERT_EQ(a[i], i ^ 0x5a5a) << i;
}

}  // namespace
}  // namespace hamal::aprilsam
