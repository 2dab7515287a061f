#include "parallax/estimators/two_view_significance.h"

#include <gtest/gtest.h>

#include <cmath>

namespace parallax {
namespace {

TEST(TwoViewSignificance, BinomialTailMatchesTheSumOfTerms) {
  // P[X >= 3], X ~ Binomial(5, 0.3) = C(5,3) .3^3 .7^2 + C(5,4) .3^4 .7 + .3^5.
  const double expected = 10 * 0.027 * 0.49 + 5 * 0.0081 * 0.7 + 0.00243;
  EXPECT_NEAR(Log10BinomialTail(5, 3, 0.3), std::log10(expected), 1e-12);
  EXPECT_EQ(Log10BinomialTail(5, 0, 0.3), 0.0);
  EXPECT_EQ(Log10BinomialTail(5, 6, 0.3), -std::numeric_limits<double>::infinity());
  // Far in the tail, where the terms underflow a double, the log stays finite.
  EXPECT_LT(Log10BinomialTail(5000, 4000, 0.01), -3000);
}

TEST(TwoViewSignificance, ManyInliersAreSignificantAndFewAreNot) {
  // 200 matches with a 2 % chance each of being an inlier by accident.
  EXPECT_LT(Log10NumFalseAlarmsFromChance(200, 7, 60, 0.02, 3), -10);
  EXPECT_GT(Log10NumFalseAlarmsFromChance(200, 7, 12, 0.02, 3), 0);
  // More models per sample: more false alarms.
  EXPECT_GT(Log10NumFalseAlarmsFromChance(200, 5, 30, 0.02, 10),
            Log10NumFalseAlarmsFromChance(200, 5, 30, 0.02, 1));
}

TEST(TwoViewSignificance, ChancePairsAreAllPairsWhenFewAndSeededWhenMany) {
  std::vector<Eigen::Vector2d> points1, points2;
  for (int i = 0; i < 10; ++i) {
    points1.emplace_back(i, 0);
    points2.emplace_back(0, i);
  }
  std::vector<Eigen::Vector2d> chance1, chance2;
  ChancePairs(points1, points2, 1, &chance1, &chance2);
  ASSERT_EQ(chance1.size(), 90u);
  for (size_t k = 0; k < chance1.size(); ++k) EXPECT_NE(chance1[k].x(), chance2[k].y());

  for (int i = 10; i < 500; ++i) {
    points1.emplace_back(i, 0);
    points2.emplace_back(0, i);
  }
  ChancePairs(points1, points2, 1, &chance1, &chance2);
  ASSERT_EQ(chance1.size(), 4096u);
  for (size_t k = 0; k < chance1.size(); ++k) EXPECT_NE(chance1[k].x(), chance2[k].y());
  std::vector<Eigen::Vector2d> again1, again2, other1, other2;
  ChancePairs(points1, points2, 1, &again1, &again2);
  ChancePairs(points1, points2, 2, &other1, &other2);
  EXPECT_EQ(again1, chance1);
  EXPECT_NE(other1, chance1);
}

TEST(TwoViewSignificance, CollinearAndRepeatedInliersAreDegenerate) {
  std::vector<Eigen::Vector2d> line = {{0, 0}, {1, 1}, {2, 2.1}, {3, 3}, {4, 3.9}};
  std::vector<char> all(line.size(), 1);
  EXPECT_TRUE(AreNearlyCollinear(line, all, 1.0));
  EXPECT_FALSE(AreNearlyCollinear(line, all, 0.01));
  line.push_back({0, 10});
  all.push_back(1);
  EXPECT_FALSE(AreNearlyCollinear(line, all, 1.0));
  all.back() = 0;  // Masked out: the rest are collinear again.
  EXPECT_TRUE(AreNearlyCollinear(line, all, 1.0));

  // Keypoint 4 of image 1 matched four times counts once.
  const FeatureMatches matches = {{4, 0}, {4, 1}, {4, 2}, {4, 3}, {5, 4}};
  EXPECT_EQ(CountDistinctKeypoints(matches, std::vector<char>(5, 1)), 2u);
  EXPECT_EQ(CountDistinctKeypoints(matches, {1, 1, 0, 0, 0}), 1u);
}

}  // namespace
}  // namespace parallax
