#include "parallax/util/huge_page_buffer.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

namespace parallax {
namespace {

TEST(HugePageBuffer, ReservesAlignedWritableMemory) {
  HugePageBuffer buffer;
  EXPECT_EQ(buffer.Capacity(), 0u);
  constexpr size_t kBytes = 5'000'000;
  auto* data = static_cast<unsigned char*>(buffer.Reserve(kBytes));
  ASSERT_NE(data, nullptr);
  EXPECT_GE(buffer.Capacity(), kBytes);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(data) % 64, 0u);
  std::memset(data, 0x5a, kBytes);
  EXPECT_EQ(data[0], 0x5a);
  EXPECT_EQ(data[kBytes - 1], 0x5a);
}

TEST(HugePageBuffer, KeepsItsBlockUntilItMustGrow) {
  HugePageBuffer buffer;
  void* first = buffer.Reserve(3'000'000);
  static_cast<unsigned char*>(first)[100] = 7;
  // Smaller or equal requests reuse the block and its contents.
  EXPECT_EQ(buffer.Reserve(1'000), first);
  EXPECT_EQ(buffer.Reserve(buffer.Capacity()), first);
  EXPECT_EQ(static_cast<unsigned char*>(first)[100], 7);
  const size_t grown = buffer.Capacity() + 1;
  auto* second = static_cast<unsigned char*>(buffer.Reserve(grown));
  ASSERT_NE(second, nullptr);
  EXPECT_GE(buffer.Capacity(), grown);
  second[grown - 1] = 1;  // The whole request is usable.
  EXPECT_EQ(second[grown - 1], 1);
}

}  // namespace
}  // namespace parallax
