#include "parallax/optim/progressive_sampler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "parallax/util/check.h"

namespace parallax {
namespace {

TEST(ProgressiveSampler, FirstTheBestThenAGrowingSetWithItsNewestPoint) {
  std::mt19937_64 generator(5);
  ProgressiveSampler sampler(50, 3, 1000);
  std::vector<size_t> sample;
  sampler.Sample(&generator, &sample);
  EXPECT_EQ(std::set<size_t>(sample.begin(), sample.end()), (std::set<size_t>{0, 1, 2}));
  size_t previous_n = sampler.NumPointsSampled();
  EXPECT_EQ(previous_n, 3u);
  for (int trial = 1; trial < 3000; ++trial) {
    sampler.Sample(&generator, &sample);
    const size_t n = sampler.NumPointsSampled();
    ASSERT_EQ(sample.size(), 3u);
    EXPECT_EQ(std::set<size_t>(sample.begin(), sample.end()).size(), 3u);  // Distinct.
    EXPECT_LT(*std::max_element(sample.begin(), sample.end()), n);
    EXPECT_GE(n, previous_n);
    EXPECT_LE(n, previous_n + 1);
    // While the set grows, each sample holds its newest point.
    if (n < 50) {
      EXPECT_NE(std::find(sample.begin(), sample.end(), n - 1), sample.end());
    }
    previous_n = n;
  }
  EXPECT_EQ(previous_n, 50u);
}

// Sampling grows to the n best once uniform sampling would have drawn as many samples from
// the n - 1 best, T_N C(n - 1, m) / C(N, m) (plus the rounding up of each step): for N = 100,
// m = 2 and T_N = 10,000, the 50th point joins after 10,000 (49 48) / (100 99) = 2,376 trials.
TEST(ProgressiveSampler, GrowsAsUniformSamplingWouldReachEachSet) {
  std::mt19937_64 generator(6);
  ProgressiveSampler sampler(100, 2, 10000);
  std::vector<size_t> sample;
  int trials_to_half = 0;
  while (sampler.NumPointsSampled() < 50) {
    sampler.Sample(&generator, &sample);
    ++trials_to_half;
  }
  EXPECT_GE(trials_to_half, 2376);
  EXPECT_LE(trials_to_half, 2376 + 50);
}

TEST(ProgressiveSampler, TheSeedDecidesTheSamples) {
  const auto draw = [](uint64_t seed) {
    std::mt19937_64 generator(seed);
    ProgressiveSampler sampler(30, 4, 500);
    std::vector<std::vector<size_t>> samples(200);
    for (auto& sample : samples) sampler.Sample(&generator, &sample);
    return samples;
  };
  EXPECT_EQ(draw(1), draw(1));
  EXPECT_NE(draw(1), draw(2));
}

TEST(ProgressiveSampler, AllPointsAtOnceAndBadArguments) {
  std::mt19937_64 generator(7);
  ProgressiveSampler sampler(4, 4, 100);
  std::vector<size_t> sample;
  for (int trial = 0; trial < 5; ++trial) {
    sampler.Sample(&generator, &sample);
    EXPECT_EQ(std::set<size_t>(sample.begin(), sample.end()), (std::set<size_t>{0, 1, 2, 3}));
  }
  EXPECT_THROW(ProgressiveSampler(3, 4, 100), CheckError);
  EXPECT_THROW(ProgressiveSampler(10, 0, 100), CheckError);
  EXPECT_THROW(ProgressiveSampler(10, 2, 0), CheckError);
}

}  // namespace
}  // namespace parallax
