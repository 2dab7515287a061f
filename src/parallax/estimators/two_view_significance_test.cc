#include "parallax/estimators/two_view_significance.h"

#include <gtest/gtest.h>

#include <cmath>

#include "parallax/geometry/essential_matrix.h"
#include "parallax/geometry/rigid3.h"
#include "parallax/math/random.h"

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

// SignificantInlierCount against a scan of the final test itself (Log10NumFalseAlarms, the
// same re-pairing seed): the first count of inliers that passes, 0 when the count given
// passes already, n + 1 when none would.
TEST(TwoViewSignificance, SignificantInlierCountIsTheFirstCountTheTestPasses) {
  SetPRNGSeed(5);
  const Rigid3d cam2_from_cam1(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY())),
                               Eigen::Vector3d(1, 0.1, 0.05));
  const Eigen::Matrix3d E = EssentialFromPose(cam2_from_cam1);
  const EssentialMatrixFivePointEstimator estimator;
  const uint64_t seed = 9;
  bool saw_passing = false, saw_count = false, saw_none = false;
  for (const int n : {30, 60, 120}) {
    // Unrelated keypoints: what a pair that does not overlap matches.
    std::vector<Eigen::Vector2d> points1, points2;
    for (int i = 0; i < n; ++i) {
      points1.emplace_back(RandomUniformReal(-0.5, 0.5), RandomUniformReal(-0.4, 0.4));
      points2.emplace_back(RandomUniformReal(-0.5, 0.5), RandomUniformReal(-0.4, 0.4));
    }
    for (const double max_error : {0.002, 0.02, 0.2}) {
      const SignificantInlierCount<EssentialMatrixFivePointEstimator> count(
          points1, points2, max_error, seed, /*max_log10_num_false_alarms=*/0.0);
      const auto passes = [&](size_t k) {
        return Log10NumFalseAlarms(estimator, points1, points2, E, max_error, k, seed) <= 0.0;
      };
      size_t first = static_cast<size_t>(n) + 1;
      for (size_t k = 0; k <= static_cast<size_t>(n); ++k) {
        if (passes(k)) {
          first = k;
          break;
        }
      }
      for (const size_t num_inliers : {size_t{3}, size_t{10}, size_t{20}}) {
        const size_t expected = passes(num_inliers) ? 0 : first;
        saw_passing |= expected == 0;
        saw_none |= expected == static_cast<size_t>(n) + 1;
        saw_count |= expected > num_inliers && expected <= static_cast<size_t>(n);
        EXPECT_EQ(count(E, num_inliers), expected)
            << n << " matches, error " << max_error << ", " << num_inliers << " inliers";
      }
    }
  }
  EXPECT_TRUE(saw_passing && saw_count && saw_none);  // Every case was exercised.
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
