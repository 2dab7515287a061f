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

// Unit rows stored as SIFT descriptors are: x 512, rounded, at most 255.
FeatureDescriptors Quantised(const RowMatrixXf& values) {
  FeatureDescriptors bytes(values.rows(), values.cols());
  for (Eigen::Index i = 0; i < values.rows(); ++i) {
    for (Eigen::Index k = 0; k < values.cols(); ++k) {
      bytes(i, k) =
          static_cast<uint8_t>(std::clamp(std::round(512.0f * values(i, k)), 0.0f, 255.0f));
    }
  }
  return bytes;
}

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

// Distances between the stored descriptors as unit vectors, in double precision.
RowMatrixXd BruteForceDistances(const FeatureDescriptors& bytes1,
                                const FeatureDescriptors& bytes2) {
  const auto unit = [](const FeatureDescriptors& bytes) {
    RowMatrixXd values = bytes.cast<double>();
    for (Eigen::Index i = 0; i < values.rows(); ++i) values.row(i).normalize();
    return values;
  };
  const RowMatrixXd values1 = unit(bytes1), values2 = unit(bytes2);
  RowMatrixXd distances(values1.rows(), values2.rows());
  for (Eigen::Index i = 0; i < values1.rows(); ++i) {
    for (Eigen::Index j = 0; j < values2.rows(); ++j) {
      distances(i, j) = (values1.row(i) - values2.row(j)).norm();
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
void ExpectMatchesAgree(const FeatureDescriptors& bytes1, const FeatureDescriptors& bytes2,
                        const RowMatrixXd& distances, const FeatureMatchingOptions& options,
                        int max_ambiguous) {
  const ReferenceMatching reference = BruteForceMatch(distances, options);
  EXPECT_LE(reference.num_ambiguous, max_ambiguous);
  const FeatureMatches actual =
      MatchDescriptors(PrepareDescriptors(bytes1), PrepareDescriptors(bytes2), options);
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
  const FeatureDescriptors bytes1 = Quantised(values1), bytes2 = Quantised(values2);
  const RowMatrixXd distances = BruteForceDistances(bytes1, bytes2);
  for (const bool cross_check : {false, true}) {
    for (const int num_threads : {1, 2, 3}) {
      SCOPED_TRACE(testing::Message()
                   << "cross_check " << cross_check << " threads " << num_threads);
      ExpectMatchesAgree(bytes1, bytes2, distances, Options(0.8, 0.7, cross_check, num_threads), 3);
      ExpectMatchesAgree(bytes1, bytes2, distances, Options(0.95, 2.0, cross_check, num_threads),
                         3);
      ExpectMatchesAgree(bytes1, bytes2, distances, Options(0.8, 0.5, cross_check, num_threads), 3);
    }
  }
}

// order_by_ratio: the same matches, by increasing ratio of the distances to the nearest and
// second-nearest neighbours, the quality order progressive RANSAC sampling draws from.
TEST(MatchDescriptors, OrderedByRatioTheMostDistinctiveFirst) {
  const RowMatrixXf values1 = RandomUnitDescriptors(300);
  RowMatrixXf values2 = RandomUnitDescriptors(500);
  PlantMatches(values1, 200, 0.1, &values2);
  const FeatureDescriptors bytes1 = Quantised(values1), bytes2 = Quantised(values2);
  const RowMatrixXd distances = BruteForceDistances(bytes1, bytes2);
  FeatureMatchingOptions options = Options(0.9, 0.9, true, 2);
  const FeatureMatches by_index =
      MatchDescriptors(PrepareDescriptors(bytes1), PrepareDescriptors(bytes2), options);
  options.order_by_ratio = true;
  const FeatureMatches by_ratio =
      MatchDescriptors(PrepareDescriptors(bytes1), PrepareDescriptors(bytes2), options);
  ASSERT_GT(by_index.size(), 50u);
  const auto key = [](const FeatureMatch& a, const FeatureMatch& b) {
    return a.point2D_idx1 < b.point2D_idx1;
  };
  FeatureMatches sorted = by_ratio;
  std::sort(sorted.begin(), sorted.end(), key);
  EXPECT_EQ(sorted, by_index);
  const auto ratio = [&distances](const FeatureMatch& match) {
    double second = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < distances.cols(); ++j) {
      if (j != static_cast<Eigen::Index>(match.point2D_idx2)) {
        second = std::min(second, distances(match.point2D_idx1, j));
      }
    }
    return distances(match.point2D_idx1, match.point2D_idx2) / second;
  };
  for (size_t k = 1; k < by_ratio.size(); ++k) {
    EXPECT_LE(ratio(by_ratio[k - 1]), ratio(by_ratio[k]) + 1e-5) << k;
  }
  EXPECT_LT(ratio(by_ratio.front()), ratio(by_ratio.back()));
}

TEST(MatchDescriptors, NearestNeighbourOfEveryQueryWithoutFilters) {
  // With the ratio test and distance bound off, every query is matched to its nearest
  // neighbour (bar exact ties, which the ratio test at 1.0 still rejects).
  const FeatureDescriptors bytes1 = Quantised(RandomUnitDescriptors(300));
  const FeatureDescriptors bytes2 = Quantised(RandomUnitDescriptors(777));
  const FeatureMatchingOptions options = Options(1.0, 2.0, false, 2);
  ExpectMatchesAgree(bytes1, bytes2, BruteForceDistances(bytes1, bytes2), options, 2);
  EXPECT_GE(
      MatchDescriptors(PrepareDescriptors(bytes1), PrepareDescriptors(bytes2), options).size(),
      298u);
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
  const MatchableDescriptors descriptors1 = PrepareDescriptors(Quantised(values1));
  const MatchableDescriptors descriptors2 = PrepareDescriptors(Quantised(values2));
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
  const MatchableDescriptors descriptors1 = PrepareDescriptors(Quantised(values1));
  const MatchableDescriptors descriptors2 = PrepareDescriptors(Quantised(values2));
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, false, 1)),
            (FeatureMatches{{0, 0}, {1, 0}}));
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, true, 1)),
            (FeatureMatches{{0, 0}}));
}

TEST(MatchDescriptors, DistanceBound) {
  // (200, 0) and (120, 160) are unit vectors (1, 0) and (0.6, 0.8): distance sqrt(0.8), about
  // 0.894. The other row of image 2 is orthogonal (distance sqrt(2)): the ratio test passes.
  FeatureDescriptors bytes1 = FeatureDescriptors::Zero(1, 128);
  FeatureDescriptors bytes2 = FeatureDescriptors::Zero(2, 128);
  bytes1(0, 0) = 200;
  bytes2(0, 0) = 120;
  bytes2(0, 1) = 160;
  bytes2(1, 2) = 255;
  const MatchableDescriptors descriptors1 = PrepareDescriptors(bytes1);
  const MatchableDescriptors descriptors2 = PrepareDescriptors(bytes2);
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.9, true, 1)).size(), 1u);
  EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.89, true, 1)).size(), 0u);
}

TEST(MatchDescriptors, EmptyAndSingleDescriptorSets) {
  const MatchableDescriptors empty = PrepareDescriptors(FeatureDescriptors(0, 128));
  EXPECT_EQ(empty.NumRows(), 0);
  const FeatureDescriptors some_bytes = Quantised(RandomUnitDescriptors(5));
  const MatchableDescriptors some = PrepareDescriptors(some_bytes);
  const FeatureMatchingOptions options;
  EXPECT_TRUE(MatchDescriptors(empty, some, options).empty());
  EXPECT_TRUE(MatchDescriptors(some, empty, options).empty());
  EXPECT_TRUE(MatchDescriptors(empty, empty, options).empty());
  // One descriptor in image 2: no second neighbour, so the ratio test cannot reject.
  const MatchableDescriptors one = PrepareDescriptors(some_bytes.topRows(1));
  EXPECT_EQ(MatchDescriptors(some, one, options), (FeatureMatches{{0, 0}}));
}

TEST(MatchDescriptors, SameResultForAnyThreadCount) {
  const RowMatrixXf values1 = RandomUnitDescriptors(1500);
  RowMatrixXf values2 = RandomUnitDescriptors(900);
  PlantMatches(values1, 600, 0.05, &values2);
  const MatchableDescriptors descriptors1 = PrepareDescriptors(Quantised(values1));
  const MatchableDescriptors descriptors2 = PrepareDescriptors(Quantised(values2));
  const FeatureMatches single =
      MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, true, 1));
  EXPECT_GT(single.size(), 300u);
  for (const int num_threads : {2, 3, 7}) {
    EXPECT_EQ(MatchDescriptors(descriptors1, descriptors2, Options(0.8, 0.7, true, num_threads)),
              single);
  }
}

// Image 1's rows packed once (PackRows, as the matching stage does) give the matches that
// packing each row block gives, with and without the cross-check, on any thread count (row
// blocks of 32 to 256 rows, the last partial).
TEST(MatchDescriptors, PackedRowsGiveTheSameMatches) {
  const RowMatrixXf values1 = RandomUnitDescriptors(1100);
  RowMatrixXf values2 = RandomUnitDescriptors(700);
  PlantMatches(values1, 500, 0.05, &values2);
  const MatchableDescriptors unpacked = PrepareDescriptors(Quantised(values1));
  MatchableDescriptors packed = unpacked;
  PackRows(&packed);
  ASSERT_GE(packed.packed.num_columns, packed.NumRows());
  const MatchableDescriptors descriptors2 = PrepareDescriptors(Quantised(values2));
  for (const bool cross_check : {false, true}) {
    for (const int num_threads : {1, 2, 7}) {
      const FeatureMatchingOptions options = Options(0.8, 0.7, cross_check, num_threads);
      const FeatureMatches expected = MatchDescriptors(unpacked, descriptors2, options);
      EXPECT_GT(expected.size(), 250u);
      EXPECT_EQ(MatchDescriptors(packed, descriptors2, options), expected)
          << "cross_check " << cross_check << " threads " << num_threads;
    }
  }
  // A selection of rows is a new block: it drops the packing rather than mis-slice it.
  MatchableDescriptors selected;
  SelectRows(packed, {5, 3, 900}, &selected);
  EXPECT_EQ(selected.packed.num_columns, 0);
}

// Rows (3, 4, 0, ...), all 255, and all 0.
FeatureDescriptors ThreeRows() {
  FeatureDescriptors descriptors(3, 128);
  descriptors.setZero();
  descriptors(0, 0) = 3;
  descriptors(0, 1) = 4;
  descriptors.row(1).setConstant(255);
  return descriptors;
}

TEST(PrepareDescriptors, ScalesAreInverseNorms) {
  const FeatureDescriptors descriptors = ThreeRows();
  const MatchableDescriptors matchable = PrepareDescriptors(descriptors);
  ASSERT_EQ(matchable.NumRows(), 3);
  EXPECT_EQ(matchable.bytes, descriptors);
  ASSERT_EQ(matchable.scales.size(), 3u);
  EXPECT_FLOAT_EQ(matchable.scales[0], 0.2f);
  EXPECT_FLOAT_EQ(matchable.scales[1], 1.0f / (255.0f * std::sqrt(128.0f)));
  EXPECT_EQ(matchable.scales[2], 0.0f);  // A zero row never matches.
}

TEST(ToUnitRows, RowsBecomeUnitFloats) {
  const FeatureDescriptors descriptors = ThreeRows();
  const UnitDescriptorRows values = ToUnitRows(descriptors);
  ASSERT_EQ(values.rows(), 3);
  ASSERT_EQ(values.cols(), 128);
  EXPECT_FLOAT_EQ(values(0, 0), 0.6f);
  EXPECT_FLOAT_EQ(values(0, 1), 0.8f);
  EXPECT_NEAR(values.row(1).norm(), 1.0f, 1e-6f);
  EXPECT_EQ(values.row(2).norm(), 0.0f);  // Zero rows stay zero.
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
  const MatchableDescriptors a = PrepareDescriptors(Quantised(RandomUnitDescriptors(2)));
  const MatchableDescriptors b = PrepareDescriptors(FeatureDescriptors::Ones(2, 64));
  EXPECT_THROW(MatchDescriptors(a, b, FeatureMatchingOptions{}), CheckError);
}

}  // namespace
}  // namespace parallax
