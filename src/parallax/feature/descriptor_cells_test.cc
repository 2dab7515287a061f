#include "parallax/feature/descriptor_cells.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

#include "parallax/feature/matcher.h"

namespace parallax {
namespace {

// Byte descriptors (unit vectors x 512, at most 255, as SIFT's are stored) around
// `num_groups` random centres, `per_group` each, every component moved by Gaussian noise of
// `noise`: row g * per_group + i belongs to group g.
FeatureDescriptors GroupedDescriptors(int num_groups, int per_group, double noise,
                                      std::mt19937_64* generator) {
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const auto unit_bytes = [](Eigen::VectorXd values, FeatureDescriptors* out, int row) {
    values = values.cwiseMax(0.0);
    values.normalize();
    for (int k = 0; k < 128; ++k) {
      (*out)(row, k) = static_cast<uint8_t>(std::min(255.0, std::round(512.0 * values[k])));
    }
  };
  FeatureDescriptors bytes(num_groups * per_group, 128);
  for (int g = 0; g < num_groups; ++g) {
    Eigen::VectorXd centre(128);
    for (int k = 0; k < 128; ++k) centre[k] = std::abs(gaussian(*generator));
    centre.normalize();
    for (int i = 0; i < per_group; ++i) {
      Eigen::VectorXd values = centre;
      for (int k = 0; k < 128; ++k) values[k] += noise * gaussian(*generator);
      unit_bytes(values, &bytes, g * per_group + i);
    }
  }
  return bytes;
}

// Image 2 for a matching test: a noisy copy of each of image 1's rows, shuffled, and as many
// unrelated rows. Returns the true partner in image 2 of each row of image 1.
std::vector<int> NoisyCopies(const FeatureDescriptors& bytes1, double noise,
                             std::mt19937_64* generator, FeatureDescriptors* bytes2) {
  const int num = static_cast<int>(bytes1.rows());
  std::normal_distribution<double> gaussian(0.0, noise);
  std::vector<int> order(2 * num);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), *generator);
  const FeatureDescriptors unrelated = GroupedDescriptors(num, 1, 0.0, generator);
  bytes2->resize(2 * num, 128);
  for (int i = 0; i < num; ++i) {
    for (int k = 0; k < 128; ++k) {
      const double value = bytes1(i, k) + 512.0 * gaussian(*generator);
      (*bytes2)(order[i], k) = static_cast<uint8_t>(std::clamp(std::round(value), 0.0, 255.0));
    }
    bytes2->row(order[num + i]) = unrelated.row(i);
  }
  return std::vector<int>(order.begin(), order.begin() + num);
}

TEST(DescriptorCells, SeparatedGroupsGetOneCellEach) {
  std::mt19937_64 generator(7);
  constexpr int kGroups = 8, kPerGroup = 150;
  const FeatureDescriptors bytes = GroupedDescriptors(kGroups, kPerGroup, 0.02, &generator);
  DescriptorCellsOptions options;
  options.num_cells = kGroups;
  options.num_assignments = 3;
  const DescriptorCells cells = DescriptorCells::Train(bytes, options);
  ASSERT_EQ(cells.NumCells(), kGroups);
  const std::vector<uint16_t> nearest = cells.NearestCells(PrepareDescriptors(bytes), 3);
  ASSERT_EQ(nearest.size(), bytes.rows() * 3u);
  std::set<int> cells_of_groups;
  for (int g = 0; g < kGroups; ++g) {
    const int cell = nearest[g * kPerGroup * 3];
    cells_of_groups.insert(cell);
    for (int i = 0; i < kPerGroup; ++i) {
      const uint16_t* row = nearest.data() + (g * kPerGroup + i) * 3;
      EXPECT_EQ(row[0], cell) << "group " << g << " row " << i;
      EXPECT_TRUE(row[0] != row[1] && row[1] != row[2] && row[0] != row[2]);
    }
  }
  EXPECT_EQ(cells_of_groups.size(), static_cast<size_t>(kGroups));
}

TEST(DescriptorCells, TrainingIsDeterministicForASeed) {
  std::mt19937_64 generator(3);
  const FeatureDescriptors bytes = GroupedDescriptors(40, 50, 0.2, &generator);
  DescriptorCellsOptions options;
  options.num_cells = 16;
  options.max_training_descriptors = 1500;  // A sample of the 2,000 rows.
  const MatchableDescriptors prepared = PrepareDescriptors(bytes);
  const std::vector<uint16_t> first =
      DescriptorCells::Train(bytes, options).NearestCells(prepared, 2);
  EXPECT_EQ(first, DescriptorCells::Train(bytes, options).NearestCells(prepared, 2));
  options.seed = 1;
  EXPECT_NE(first, DescriptorCells::Train(bytes, options).NearestCells(prepared, 2));
}

// NearestCells against a full sort of each row's similarities to the centroids, computed here
// as the kernels compute them (float of the integer dot product, times the centroid's scale,
// times the row's), by value, largest first, then by cell.
void ExpectNearestCellsAreTheTopOfAFullSort(const DescriptorCells& cells,
                                            const FeatureDescriptors& bytes, int count,
                                            int num_threads) {
  const MatchableDescriptors rows = PrepareDescriptors(bytes);
  const MatchableDescriptors centroids = PrepareDescriptors(cells.Centroids());
  const std::vector<uint16_t> nearest = cells.NearestCells(rows, count, num_threads);
  ASSERT_EQ(nearest.size(), static_cast<size_t>(rows.NumRows()) * count);
  for (int row = 0; row < rows.NumRows(); ++row) {
    std::vector<std::pair<float, int>> ranked;
    for (int cell = 0; cell < cells.NumCells(); ++cell) {
      int32_t dot = 0;
      for (int k = 0; k < 128; ++k) dot += int32_t{bytes(row, k)} * centroids.bytes(cell, k);
      ranked.emplace_back(static_cast<float>(dot) * centroids.scales[cell] * rows.scales[row],
                          cell);
    }
    std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    for (int k = 0; k < count; ++k) {
      EXPECT_EQ(nearest[static_cast<size_t>(row) * count + k], ranked[k].second)
          << "row " << row << ", rank " << k;
    }
  }
}

TEST(DescriptorCells, NearestCellsAreTheTopOfAFullSortOnAnyNumberOfThreads) {
  std::mt19937_64 generator(5);
  const FeatureDescriptors bytes = GroupedDescriptors(12, 60, 0.3, &generator);
  DescriptorCellsOptions options;
  options.num_cells = 12;
  const DescriptorCells cells = DescriptorCells::Train(bytes, options);
  for (const int num_threads : {1, 2, 3}) {
    ExpectNearestCellsAreTheTopOfAFullSort(cells, bytes, 4, num_threads);
    ExpectNearestCellsAreTheTopOfAFullSort(cells, bytes, 1, num_threads);
  }
  // Training's assignment steps on several threads give the same cells.
  options.num_threads = 3;
  EXPECT_EQ(DescriptorCells::Train(bytes, options).Centroids(), cells.Centroids());
}

TEST(DescriptorCells, EqualSimilaritiesRankTheLowerCellFirst) {
  // Two distinct rows, twenty copies each, in four cells: at least two centroids are equal,
  // and every row ties between them.
  FeatureDescriptors bytes(40, 128);
  bytes.setZero();
  for (int i = 0; i < 40; ++i) bytes(i, i % 2) = 200;
  DescriptorCellsOptions options;
  options.num_cells = 4;
  const DescriptorCells cells = DescriptorCells::Train(bytes, options);
  ASSERT_EQ(cells.NumCells(), 4);
  bool some_equal = false;
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b)
      some_equal |= cells.Centroids().row(a) == cells.Centroids().row(b);
  }
  ASSERT_TRUE(some_equal);
  ExpectNearestCellsAreTheTopOfAFullSort(cells, bytes, 4, 1);
  ExpectNearestCellsAreTheTopOfAFullSort(cells, bytes, 2, 2);
}

TEST(MatchDescriptorsInCells, EveryCellSearchedIsTheExactMatcher) {
  std::mt19937_64 generator(11);
  const FeatureDescriptors bytes1 = GroupedDescriptors(30, 20, 0.3, &generator);
  FeatureDescriptors bytes2;
  NoisyCopies(bytes1, 0.02, &generator, &bytes2);
  const MatchableDescriptors descriptors1 = PrepareDescriptors(bytes1);
  const MatchableDescriptors descriptors2 = PrepareDescriptors(bytes2);
  DescriptorCellsOptions options;
  options.num_cells = 8;
  const DescriptorCells cells = DescriptorCells::Train(bytes1, options);
  for (const bool cross_check : {true, false}) {
    FeatureMatchingOptions matching;
    matching.cross_check = cross_check;
    matching.num_threads = 1;
    const FeatureMatches exact = MatchDescriptors(descriptors1, descriptors2, matching);
    // Filed under every cell, each descriptor of image 2 meets every query.
    const FeatureMatches in_cells = MatchDescriptorsInCells(
        FileDescriptorsByCell(descriptors1, cells, options.num_cells),
        FileDescriptorsByCell(descriptors2, cells, options.num_cells), descriptors2, matching);
    ASSERT_GT(exact.size(), 100u);
    ASSERT_EQ(in_cells.size(), exact.size()) << "cross-check " << cross_check;
    for (size_t k = 0; k < exact.size(); ++k) {
      EXPECT_EQ(in_cells[k].point2D_idx1, exact[k].point2D_idx1);
      EXPECT_EQ(in_cells[k].point2D_idx2, exact[k].point2D_idx2);
    }
  }
}

TEST(MatchDescriptorsInCells, FindsNearlyAllTrueMatchesSearchingAFractionOfThePairs) {
  std::mt19937_64 generator(5);
  // Many overlapping groups, as SIFT descriptors are: cells cut through them.
  const FeatureDescriptors bytes1 = GroupedDescriptors(200, 10, 0.25, &generator);
  FeatureDescriptors bytes2;
  const std::vector<int> partner = NoisyCopies(bytes1, 0.01, &generator, &bytes2);
  const MatchableDescriptors descriptors1 = PrepareDescriptors(bytes1);
  const MatchableDescriptors descriptors2 = PrepareDescriptors(bytes2);
  DescriptorCellsOptions options;  // 32 cells, 4 assignments.
  FeatureDescriptors both(bytes1.rows() + bytes2.rows(), 128);
  both << bytes1, bytes2;
  const DescriptorCells cells = DescriptorCells::Train(both, options);
  const CellFiledDescriptors filed1 =
      FileDescriptorsByCell(descriptors1, cells, options.num_assignments);
  const CellFiledDescriptors filed2 =
      FileDescriptorsByCell(descriptors2, cells, options.num_assignments);

  // The searched share: query-candidate pairs compared, against all pairs.
  double compared = 0;
  for (size_t c = 0; c < filed1.cells.size(); ++c) {
    compared += static_cast<double>(filed1.cells[c].query_rows.size()) *
                static_cast<double>(filed2.cells[c].searched_rows.size());
  }
  // 4 of 32 cells would be 1/8 if the cells were even; these groups fill them unevenly.
  EXPECT_LT(compared / (static_cast<double>(bytes1.rows()) * bytes2.rows()), 0.3);

  FeatureMatchingOptions matching;
  matching.num_threads = 1;
  const auto num_true = [&partner](const FeatureMatches& matches) {
    int count = 0;
    for (const FeatureMatch& match : matches) {
      count += partner[match.point2D_idx1] == static_cast<int>(match.point2D_idx2);
    }
    return count;
  };
  const FeatureMatches exact = MatchDescriptors(descriptors1, descriptors2, matching);
  const FeatureMatches in_cells = MatchDescriptorsInCells(filed1, filed2, descriptors2, matching);
  ASSERT_GT(num_true(exact), 1800);  // Of 2,000 planted.
  EXPECT_GE(num_true(in_cells), 0.95 * num_true(exact));
  // Wrong matches stay as rare as the exact matcher's.
  EXPECT_LE(in_cells.size() - num_true(in_cells), exact.size() - num_true(exact) + 20);
}

TEST(MatchDescriptorsInCells, AnEmptyImageHasNoMatches) {
  std::mt19937_64 generator(1);
  const FeatureDescriptors bytes = GroupedDescriptors(4, 20, 0.1, &generator);
  DescriptorCellsOptions options;
  options.num_cells = 4;
  options.num_assignments = 2;
  const DescriptorCells cells = DescriptorCells::Train(bytes, options);
  const MatchableDescriptors descriptors = PrepareDescriptors(bytes);
  const MatchableDescriptors none = PrepareDescriptors(FeatureDescriptors(0, 128));
  const CellFiledDescriptors filed = FileDescriptorsByCell(descriptors, cells, 2);
  const CellFiledDescriptors empty = FileDescriptorsByCell(none, cells, 2);
  EXPECT_TRUE(MatchDescriptorsInCells(filed, empty, none, FeatureMatchingOptions()).empty());
  EXPECT_TRUE(MatchDescriptorsInCells(empty, filed, descriptors, FeatureMatchingOptions()).empty());
}

}  // namespace
}  // namespace parallax
