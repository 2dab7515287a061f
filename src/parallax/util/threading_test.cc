#include "parallax/util/threading.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

namespace parallax {
namespace {

TEST(ParallelFor, VisitsEveryIndexOnce) {
  std::vector<std::atomic<int>> visits(1000);
  ParallelFor(0, visits.size(), 4, [&](size_t i) { visits[i]++; });
  for (const auto& count : visits) EXPECT_EQ(count.load(), 1);
}

TEST(ParallelFor, RethrowsWorkerException) {
  EXPECT_THROW(ParallelFor(0, 100, 3,
                           [](size_t i) {
                             if (i == 50) throw std::runtime_error("boom");
                           }),
               std::runtime_error);
}

TEST(ParallelFor, EmptyRangeDoesNothing) {
  int calls = 0;
  ParallelFor(5, 5, 2, [&](size_t) { ++calls; });
  EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace parallax
