#include "parallax/util/threading.h"

#include <gtest/gtest.h>
#include <sched.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

namespace parallax {
namespace {

// A process bound to one core (as mpirun binds each of two ranks by default) works on one
// thread, not on as many as the machine has cores.
TEST(EffectiveNumThreads, CountsTheCoresTheThreadMayRunOn) {
  EXPECT_EQ(EffectiveNumThreads(3), 3);
  cpu_set_t original;
  ASSERT_EQ(sched_getaffinity(0, sizeof(original), &original), 0);
  EXPECT_EQ(EffectiveNumThreads(-1), CPU_COUNT(&original));
  int first = 0;
  while (!CPU_ISSET(first, &original)) ++first;
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(first, &one);
  ASSERT_EQ(sched_setaffinity(0, sizeof(one), &one), 0);
  EXPECT_EQ(EffectiveNumThreads(-1), 1);
  EXPECT_EQ(EffectiveNumThreads(0), 1);
  ASSERT_EQ(sched_setaffinity(0, sizeof(original), &original), 0);
  EXPECT_EQ(EffectiveNumThreads(-1), CPU_COUNT(&original));
}

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

TEST(ParallelFor, NestedCallsRunEveryIndex) {
  // A body that loops in parallel itself: the inner loops cannot wait on the threads that
  // run the outer one.
  std::vector<std::atomic<int>> visits(20 * 30);
  ParallelFor(0, 20, 3,
              [&](size_t i) { ParallelFor(0, 30, 3, [&](size_t j) { visits[i * 30 + j]++; }); });
  for (const auto& count : visits) EXPECT_EQ(count.load(), 1);
}

TEST(ParallelFor, CallersOnSeveralThreadsAtOnce) {
  // Loops started at the same moment from different threads all complete, whether they get
  // the shared workers or start their own.
  constexpr int kCallers = 4;
  std::vector<std::vector<std::atomic<int>>> visits(kCallers);
  for (auto& caller_visits : visits) caller_visits = std::vector<std::atomic<int>>(2000);
  std::vector<std::thread> callers;
  for (int c = 0; c < kCallers; ++c) {
    callers.emplace_back([&visits, c] {
      for (int round = 0; round < 20; ++round) {
        ParallelFor(0, 100, 2, [&](size_t i) { visits[c][round * 100 + i]++; });
      }
    });
  }
  for (auto& caller : callers) caller.join();
  for (const auto& caller_visits : visits) {
    for (const auto& count : caller_visits) EXPECT_EQ(count.load(), 1);
  }
}

TEST(ParallelFor, ManyShortLoopsInARow) {
  // As bundle adjustment calls it: many loops, each of a few items, one after another.
  std::atomic<long> sum{0};
  for (int round = 0; round < 2000; ++round) {
    ParallelFor(0, 3, 2, [&](size_t i) { sum += static_cast<long>(i) + 1; });
  }
  EXPECT_EQ(sum.load(), 2000 * 6);
}

}  // namespace
}  // namespace parallax
