// Tests of TopBackoff (top_backoff.h): a fallback batch is held back only
// after three in a row that left L no smaller, for doubling spans up to
// top_backoff, and progress starts the back-off over.
#include "backends/aprilsam/top_backoff.h"

#include <gtest/gtest.h>

namespace hamal::aprilsam {
namespace {

// Gauss-Newton converging: each batch's step moves fewer variables than the
// one before, so a batch runs at every update that asks for one.
TEST(TopBackoff, HoldsOnlyWithoutProgress) {
  TopBackoff b(64);
  long moved = 6000;
  for (long step = 10; step < 20; ++step) {
    EXPECT_FALSE(b.hold(step, moved)) << step;
    b.batched(step, moved);
    moved = moved * 2 / 3;
  }
  // A batch long ago (not the update before) says nothing of this one.
  TopBackoff c(64);
  c.batched(10, 100);
  EXPECT_FALSE(c.hold(12, 500));
}

// No progress: L as large after each batch as before it. Three such
// batches in a row, then the holds double (2, 4, 8, ...) up to the cap;
// between them one batch looks again.
TEST(TopBackoff, HoldsDoubleUpToTheCap) {
  TopBackoff b(8);
  long step = 100;
  for (; step < 103; ++step) {
    EXPECT_FALSE(b.hold(step, 5000)) << step;  // not yet three without progress
    b.batched(step, 5000);
  }
  --step;
  for (long expected : {2L, 4L, 8L, 8L}) {
    ++step;
    ASSERT_TRUE(b.hold(step, 5001)) << step;  // the batch before moved as many
    EXPECT_EQ(b.until(), step + expected);
    for (++step; step < b.until(); ++step) EXPECT_TRUE(b.hold(step, 5001)) << step;
    EXPECT_FALSE(b.hold(step, 5001)) << step;  // the hold is over: one batch looks again
    b.batched(step, 5001);
  }
}

// A batch that shrinks L runs the next batch too, and needs three batches
// without progress again; progress (no batch asked, or a top that runs)
// starts the holds over at 2.
TEST(TopBackoff, ProgressStartsOver) {
  TopBackoff b(64);
  for (long step = 0; step < 3; ++step) b.batched(step, 5000);
  ASSERT_TRUE(b.hold(3, 5000));
  EXPECT_EQ(b.until(), 5);
  EXPECT_FALSE(b.hold(5, 5000));
  b.batched(5, 5000);
  ASSERT_TRUE(b.hold(6, 5000));  // the stall goes on across the hold
  EXPECT_EQ(b.until(), 10);
  EXPECT_FALSE(b.hold(10, 5000));
  b.batched(10, 5000);
  EXPECT_FALSE(b.hold(11, 4000));  // the batch at 10 made progress
  b.batched(11, 4000);
  EXPECT_FALSE(b.hold(12, 4000));
  b.reset();
  for (long step = 20; step < 23; ++step) b.batched(step, 4000);
  ASSERT_TRUE(b.hold(23, 4000));
  EXPECT_EQ(b.until(), 25);
}

// top_backoff=0: a batch at every update that asks for one.
TEST(TopBackoff, ZeroIsOff) {
  TopBackoff b(0);
  for (long step = 0; step < 3; ++step) b.batched(step, 5000);
  EXPECT_FALSE(b.hold(3, 5000));
}

}  // namespace
}  // namespace hamal::aprilsam
