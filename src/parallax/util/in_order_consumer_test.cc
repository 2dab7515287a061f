#include "parallax/util/in_order_consumer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace parallax {
namespace {

TEST(InOrderConsumer, ConsumesInIndexOrderWhateverOrderValuesArriveIn) {
  constexpr size_t kCount = 400;
  std::vector<size_t> order(kCount);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(7));

  std::vector<size_t> consumed;
  std::vector<std::string> values;
  InOrderConsumer<std::string> consumer(kCount, [&](size_t index, std::string& value) {
    consumed.push_back(index);
    values.push_back(std::move(value));
  });
  // Four producers, each putting every fourth of the shuffled indices.
  std::vector<std::thread> producers;
  for (size_t p = 0; p < 4; ++p) {
    producers.emplace_back([&, p] {
      for (size_t k = p; k < kCount; k += 4) consumer.Put(order[k], std::to_string(order[k]));
    });
  }
  for (std::thread& producer : producers) producer.join();
  consumer.Finish();

  ASSERT_EQ(consumed.size(), kCount);
  for (size_t i = 0; i < kCount; ++i) {
    EXPECT_EQ(consumed[i], i);
    EXPECT_EQ(values[i], std::to_string(i));
  }
  EXPECT_FALSE(consumer.Failed());
}

TEST(InOrderConsumer, FinishConsumesUpToTheFirstIndexNeverPut) {
  std::vector<size_t> consumed;
  InOrderConsumer<int> consumer(6, [&](size_t index, int&) { consumed.push_back(index); });
  for (const size_t index : {4u, 1u, 0u, 3u}) consumer.Put(index, 0);
  consumer.Finish();
  EXPECT_EQ(consumed, (std::vector<size_t>{0, 1}));
}

TEST(InOrderConsumer, AConsumerExceptionStopsConsumingAndIsRethrownByFinish) {
  std::vector<size_t> consumed;
  InOrderConsumer<int> consumer(5, [&](size_t index, int&) {
    if (index == 2) throw std::runtime_error("disk full");
    consumed.push_back(index);
  });
  for (size_t index = 0; index < 5; ++index) consumer.Put(index, 0);
  EXPECT_THROW(
      {
        try {
          consumer.Finish();
        } catch (const std::runtime_error& error) {
          EXPECT_STREQ(error.what(), "disk full");
          throw;
        }
      },
      std::runtime_error);
  EXPECT_TRUE(consumer.Failed());
  EXPECT_EQ(consumed, (std::vector<size_t>{0, 1}));
}

TEST(InOrderConsumer, TheDestructorStopsWithoutFinish) {
  std::vector<size_t> consumed;
  {
    InOrderConsumer<int> consumer(3, [&](size_t index, int&) {
      if (index == 1) throw std::runtime_error("ignored on the way out");
      consumed.push_back(index);
    });
    consumer.Put(0, 0);
    consumer.Put(1, 0);
  }
  EXPECT_EQ(consumed, (std::vector<size_t>{0}));
}

}  // namespace
}  // namespace parallax
