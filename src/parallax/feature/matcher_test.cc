#include "parallax/feature/matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <ostream>

#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {

// Readable failure messages for match lists.
void PrintTo(const FeatureMatch& match, std::ostream* stream) {
  *stream << "(" << match.point2D_idx1 << ", " << match.point2D_idx2 << ")";
}

namespace {

using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Non-negative unit vectors, like SIFT descriptors.
RowMatrixXf RandomUnitDescriptors(int num) {
  RowMatrixXf values(num, 128);
  for (int i = 0; i < num; ++i) {
    for (int k = 0; k < 128; ++k) values(i, k) = static_cast<float>(std::abs(RandomGaussian(0, 1)));
    values.row(i).normalize();
  }
  return values;
}

// Copies `num_planted` rows of `values1` into random rows of `values2`, with Gaussian noise of
// standard deviation up to `max_noise` per component, renormalised. Noise 0.05 puts a copy
// about 0.5 away; unrelated descriptors are about 0.85 apart.
void PlantMatches(const RowMatrixXf& values1, int num_planted, double max_noise,
                  RowMatrixXf* values2) {
  std::vector<int> targets(values2->rows());
  std::iota(targets.begin(), targets.end(), 0);
  Shuffle(targets.size(), &targets);
  for (int k = 0; k < num_planted; ++k) {
    const int i = static_cast<int>(RandomUniformInteger(0, values1.rows() - 1));
    const double noise = RandomUniformReal(0.0, max_noise);
    for (int d = 0; d < 128; ++d) {
      (*values2)(targets[k], d) =
          std::max(0.0f, values1(i, d) + static_cast<float>(RandomGaussian(0, noise)));
    }
    values2->row(targets[k]).normalize();
  }
}

// The obvious O(N1 N2) loop in double precision, with the same definitions as the matcher.
struct ReferenceMatching {
  FeatureMatches matches;
  int num_ambiguous = 0;  // Queries too close to a decision boundary for float arithmetic.
  std::vector<bool> ambiguous;
};

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

RowMatrixXd BruteForceDistances(const RowMatrixXf& values1, const RowMatrixXf& values2) {
  const int num1 = static_cast<int>(values1.rows());
  const int num2 = static_cast<int>(values2.rows());
  RowMatrixXd distances(num1, num2);
  for (int i = 0; i < num1; ++i) {
    for (int j = 0; j < num2; ++j) {
      double sum = 0.0;
      for (int k = 0; k < 128; ++k) {
        const double difference = double{values1(i, k)} - double{values2(j, k)};
        sum += difference * difference;
      }
      distances(i, j) = std::sqrt(sum);
    }
  }
  return distances;
}

ReferenceMatching BruteForceMatch(const RowMatrixXd& distances,
                                  const FeatureMatchingOptions& options) {
  const int num1 = static_cast<int>(distances.rows());
  const int num2 = static_cast<int>(distances.cols());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  constexpr double kMargin = 1e-5;
  // Best row per column, and whether it is a near tie.
  std::vector<int> best_row(num2, -1);
  std::vector<bool> column_ambiguous(num2, false);
  for (int j = 0; j < num2; ++j) {
    double best = kInf, second = kInf;
    for (int i = 0; i < num1; ++i) {
      if (distances(i, j) < best) {
        second = best;
        best = distances(i, j);
        best_row[j] = i;
      } else if (distances(i, j) < second) {
        second = distances(i, j);
      }
    }
    column_ambiguous[j] = second - best < kMargin;
  }
  ReferenceMatching reference;
  reference.ambiguous.assign(num1, false);
  for (int i = 0; i < num1; ++i) {
    double best = kInf, second = kInf;
    int best_j = -1;
    for (int j = 0; j < num2; ++j) {
      if (distances(i, j) < best) {
        second = best;
        best = distances(i, j);
        best_j = j;
      } else if (distances(i, j) < second) {
        second = distances(i, j);
      }
    }
    if (best_j < 0) continue;
    const bool accept = best <= options.max_distance && best < options.max_ratio * second &&
                        (!options.cross_check || best_row[best_j] == i);
    const bool ambiguous = (second - best < kMargin) ||
                           std::abs(best - options.max_distance) < kMargin ||
                           std::abs(best - options.max_ratio * second) < kMargin ||
                           (options.cross_check && column_ambiguous[best_j]);
    if (ambiguous) {
      ++reference.num_ambiguous;
      reference.ambiguous[i] = true;
      continue;
    }
    if (accept)
      reference.matches.push_back({static_cast<point2D_t>(i), static_cast<point2D_t>(best_j)});
  }
  return reference;
}

// Matches of `actual` for queries the reference did not flag as ambiguous must be exactly the
// reference's.
void ExpectMatchesAgree(const RowMatrixXf& values1, const RowMatrixXf& values2,
                        const RowMatrixXd& distances, const FeatureMatchingOptions& options,
                        int max_ambiguous) {
  const ReferenceMatching reference = BruteForceMatch(distances, options);
  EXPECT_LE(reference.num_ambiguous, max_ambiguous);
  MatchableDescriptors descriptors1{values1}, descriptors2{values2};
  const FeatureMatches actual = MatchDescriptors(descriptors1, descriptors2, options);
  FeatureMatches decided;
  for (const FeatureMatch& match : actual) {
    if (!reference.ambiguous[match.point2D_idx1]) decided.push_back(match);
  }
  EXPECT_EQ(decided, reference.matches);
  EXPECT_GT(reference.matches.size(), 0u);
}

FeatureMatchingOptions Options(double max_ratio, double max_distance, bool cross_check,
                               int num_threads) {
  FeatureMatchingOptions options;
  options.max_ratio = max_ratio;
  options.max_distance = max_distance;
  options.cross_check = cross_check;
  options.num_threads = num_threads;
  return options;
}

TEST(MatchDescriptors, RandomDescriptorsAgreeWithBruteForce) {
  // Sizes that leave partial blocks in both directions.
  const RowMatrixXf values1 = RandomUnitDescriptors(613);
  RowMatrixXf values2 = RandomUnitDescriptors(1037);
  PlantMatches(values1, 400, 0.08, &values2);
  const RowMatrixXd distances = BruteForceDistances(values1, values2);
  for (const bool cross_check : {false, true}) {
    for (const int num_threads : {1, 2, 3}) {
      SCOPED_TRACE(testing::Message()
                   << "cross_check " << cross_check << " threads " << num_threads);
      ExpectMatchesAgree(values1, values2, distances, Options(0.8, 0.7, cross_check, num_threads),
                         3);
      ExpectMatchesAgree(values1, values2, distances, Options(0.95, 2.0, cross_check, num_threads),
                         3);
      ExpectMatchesAgree(values1, values2, distances, Options(0.8, 0.5, cross_check, num_threads),
                         3);
    }
  }
}

TEST(MatchDescriptors, NearestNeighbourOfEveryQueryWithoutFilters) {
  // With the ratio test and distance bound off, every query is matched to its nearest
  // neighbour (bar exact ties, which the ratio test at 1.0 still rejects).
  const RowMatrixXf values1 = RandomUnitDescriptors(300);
  const RowMatrixXf values2 = RandomUnitDescriptors(777);
  const FeatureMatchingOptions options = Options(1.0, 2.0, false, 2);
  ExpectMatchesAgree(values1, values2, BruteForceDistances(values1, values2), options, 2);
  MatchableDescriptors descriptors1{values1}, descriptors2{values2};
  EXPECT_GE(MatchDescriptors(descriptors1, descriptors2, options).size(), 298u);
}

TEST(MatchDescriptors, QuantisedPermutedCopiesAreFoundExactly) {
  // uint8 descriptors, image 2 a shuffled copy of image 1 with +-2 noise.
  const int num = 700;
  FeatureDescriptors descriptors1(num, 128), descriptors2(num, 128);
  for (int i = 0; i < num; ++i) {
    for (int k = 0; k < 128; ++k)
      descriptors1(i, k) = static_cast<uint8_t>(RandomUniformInteger(0, 120));
  }
  std::vector<int> permutation(num);
  std::iota(permutation.begin(), permutation.end(), 0);
  Shuffle(permutation.size(), &permutation);
  for (int i = 0; i < num; ++i) {
    for (int k = 0; k < 128; ++k) {
      descriptors2(permutation[i], k) = static_cast<uint8_t>(
          std::clamp<int64_t>(descriptors1(i, k) + RandomUniformInteger(-2, 2), 0, 255));
    }
  }
  const MatchableDescriptors matchable1 = PrepareDescriptors(descriptors1);
  const MatchableDescriptors matchable2 = PrepareDescriptors(descriptors2);
  for (const bool cross_check : {false, true}) {
    const FeatureMatches matches =
        MatchDescriptors(matchable1, matchable2, Options(0.8, 0.7, cross_check, -1));
    ASSERT_EQ(matches.size(), static_cast<size_t>(num));
    for (int i = 0; i < num; ++i) {
      EXPECT_EQ(matches[i].point2D_idx1, static_cast<point2D_t>(i));
      EXPECT_EQ(matches[i].point2D_idx2, static_cast<point2D_t>(permutation[i]));
    }
  }
}

TEST(MatchDescriptors, DuplicateNeighboursFailTheRatioTest) {
  RowMatrixXf values1 = RandomUnitDescriptors(3);
  RowMatrixXf values2(4, 128);
  values2.row(0) = values1.row(0);
  values2.row(1) = values1.row(0);  // Two equally near neighbours: ambiguous, rejected.
  values2.row(2) = values1.row(1);
  values2.row(3) = values1.row(2);
  MatchableDescriptors descriptors1{values1}, descriptors2{values2};
  const FeatureMatches matches =
      MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, false, 1));
  EXPECT_EQ(matches, (FeatureMatches{{1, 2}, {2, 3}}));
}

TEST(MatchDescriptors, CrossCheckKeepsMutualNearestNeighbours) {
  // Rows 0 and 1 of image 1 both prefer row 0 of image 2, whose nearest is row 0.
  RowMatrixXf base = RandomUnitDescriptors(3);
  RowMatrixXf values1(2, 128), values2(2, 128);
  values1.row(0) = base.row(0);
  values1.row(1) = (base.row(0) + 0.3f * base.row(1)).normalized();
  values2.row(0) = (base.row(0) + 0.05f * base.row(2)).normalized();
  values2.row(1) = base.row(2);
  MatchableDescriptors descriptors1{values1}, descriptors2{values2};
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, false, 1)),
            (FeatureMatches{{0, 0}, {1, 0}}));
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, true, 1)),
            (FeatureMatches{{0, 0}}));
}

TEST(MatchDescriptors, DistanceBound) {
  const RowMatrixXf values1 = RandomUnitDescriptors(1);
  RowMatrixXf values2 = RandomUnitDescriptors(2);
  // Distance 0.5 exactly: a unit vector at angle theta with 2 sin(theta/2) = 0.5.
  Eigen::RowVectorXf orthogonal =
      values2.row(0) - values2.row(0).dot(values1.row(0)) * values1.row(0);
  orthogonal.normalize();
  const float theta = 2.0f * std::asin(0.25f);
  values2.row(0) = std::cos(theta) * values1.row(0) + std::sin(theta) * orthogonal;
  values2.row(1) = -values1.row(0);  // Distance 2: the ratio test passes.
  MatchableDescriptors descriptors1{values1}, descriptors2{values2};
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.51, true, 1)).size(), 1u);
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.49, true, 1)).size(), 0u);
}

TEST(MatchDescriptors, EmptyAndSingleDescriptorSets) {
  const MatchableDescriptors empty = PrepareDescriptors(FeatureDescriptors(0, 128));
  EXPECT_EQ(empty.values.rows(), 0);
  MatchableDescriptors some{RandomUnitDescriptors(5)};
  const FeatureMatchingOptions options;
  EXPECT_TRUE(MatchDescriptors(empty, some, options).empty());
  EXPECT_TRUE(MatchDescriptors(some, empty, options).empty());
  EXPECT_TRUE(MatchDescriptors(empty, empty, options).empty());
  // One descriptor in image 2: no second neighbour, so the ratio test cannot reject.
  MatchableDescriptors one{some.values.topRows(1)};
  EXPECT_EQ(MatchDescriptors(some, one, options), (FeatureMatches{{0, 0}}));
}

TEST(MatchDescriptors, SameResultForAnyThreadCount) {
  const RowMatrixXf values1 = RandomUnitDescriptors(1500);
  RowMatrixXf values2 = RandomUnitDescriptors(900);
  PlantMatches(values1, 600, 0.05, &values2);
  MatchableDescriptors descriptors1{values1}, descriptors2{values2};
  const FeatureMatches single =
      MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, true, 1));
  EXPECT_GT(single.size(), 300u);
  for (const int num_threads : {2, 3, 7}) {
    EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, true, num_threads)),
              single);
  }
}

TEST(PrepareDescriptors, RowsBecomeUnitFloats) {
  FeatureDescriptors descriptors(3, 128);
  descriptors.setZero();
  descriptors(0, 0) = 3;
  descriptors(0, 1) = 4;
  descriptors.row(1).setConstant(255);
  const MatchableDescriptors matchable = PrepareDescriptors(descriptors);
  ASSERT_EQ(matchable.values.rows(), 3);
  ASSERT_EQ(matchable.values.cols(), 128);
  EXPECT_FLOAT_EQ(matchable.values(0, 0), 0.6f);
  EXPECT_FLOAT_EQ(matchable.values(0, 1), 0.8f);
  EXPECT_NEAR(matchable.values.row(1).norm(), 1.0f, 1e-6f);
  EXPECT_EQ(matchable.values.row(2).norm(), 0.0f);  // Zero rows stay zero.
}

TEST(FeatureMatchingOptions, Check) {
  FeatureMatchingOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_ratio = 1.5;
  EXPECT_THROW(options.Check(), CheckError);
  options = {};
  options.max_distance = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = {};
  options.num_threads = 0;
  EXPECT_THROW(options.Check(), CheckError);
  MatchableDescriptors a{RandomUnitDescriptors(2)}, b;
  b.values.resize(2, 64);
  b.values.setOnes();
  EXPECT_THROW(MatchDescriptors(a, b, FeatureMatchingOptions{}), CheckError);
}

}  // namespace
}  // namespace parallax
