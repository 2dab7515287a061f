#include "parallax/math/random.h"

#include <gtest/gtest.h>

namespace parallax {
namespace {

TEST(Random, SeedMakesSequenceRepeatable) {
  SetPRNGSeed(42);
  const double a = RandomUniformReal(0, 1);
  const int64_t b = RandomUniformInteger(0, 1000);
  SetPRNGSeed(42);
  EXPECT_EQ(a, RandomUniformReal(0, 1));
  EXPECT_EQ(b, RandomUniformInteger(0, 1000));
}

TEST(Random, ShuffleKeepsElements) {
  std::vector<int> values = {0, 1, 2, 3, 4, 5, 6, 7};
  Shuffle(values.size(), &values);
  std::vector<int> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  for (int i = 0; i < 8; ++i) EXPECT_EQ(sorted[i], i);
}

}  // namespace
}  // namespace parallax
