#include "parallax/util/check.h"

#include <gtest/gtest.h>

#include "parallax/util/types.h"

namespace parallax {
namespace {

TEST(Check, ThrowsWithExpressionAndValues) {
  try {
    PARALLAX_CHECK_EQ(1 + 1, 3);
    FAIL() << "expected CheckError";
  } catch (const CheckError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("1 + 1 == 3"), std::string::npos);
    EXPECT_NE(what.find("(2 vs. 3)"), std::string::npos);
  }
  EXPECT_NO_THROW(PARALLAX_CHECK(true));
}

TEST(Types, PairIdRoundTripsAndOrders) {
  const image_pair_t pair_id = ImagePairToPairId(7, 3);
  EXPECT_EQ(pair_id, ImagePairToPairId(3, 7));
  const auto [id1, id2] = PairIdToImagePair(pair_id);
  EXPECT_EQ(id1, 3u);
  EXPECT_EQ(id2, 7u);
  EXPECT_EQ(ImagePairToPairId(1, 2), 2147483647ull + 2);
}

}  // namespace
}  // namespace parallax
