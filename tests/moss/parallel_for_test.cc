// parallelFor (apps/moss/parallel_for.h): every item once, and an exception
// thrown on a worker thread reaches the caller instead of std::terminate.
#include "apps/moss/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

#include "core/error.h"

namespace hamal::moss {
namespace {

TEST(ParallelFor, CallsEveryItemOnce) {
  for (int threads : {0, 1, 3, 64}) {
    std::vector<std::atomic<int>> calls(100);
    parallelFor(threads, 100, [&](int k) { ++calls[k]; });
    for (const auto& c : calls) EXPECT_EQ(c.load(), 1) << threads << " threads";
  }
  parallelFor(4, 0, [](int) { FAIL() << "no item to call"; });
}

TEST(ParallelFor, AnExceptionOnAWorkerReachesTheCaller) {
  for (int threads : {1, 4}) {
    try {
      parallelFor(threads, 50, [](int k) {
        if (k == 17) throw Error("item 17 is bad");
      });
      FAIL() << "nothing was thrown";
    } catch (const Error& e) {
      EXPECT_STREQ(e.what(), "item 17 is bad");
    }
    EXPECT_THROW(parallelFor(threads, 8, [](int) { throw std::runtime_error("any"); }),
                 std::runtime_error);
  }
}

}  // namespace
}  // namespace hamal::moss
