#include "parallax/feature/matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "parallax/feature/descriptor_cells.h"
#include "parallax/feature/similarity_kernel.h"
#include "parallax/util/check.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

constexpr float kMinusInfinity = -std::numeric_limits<float>::infinity();

// Tiles of the similarity matrix: one task owns up to kMaxRowBlock descriptors of image 1 and
// walks image 2 in chunks of kColBlock, so a kColBlock x kMaxRowBlock tile (256 KiB) stays in
// L2 between the product that writes it and the scans that read it.
constexpr int kMaxRowBlock = 256;
constexpr int kMinRowBlock = 32;
constexpr int kColBlock = 256;

// Best and second-best similarity (dot product) per descriptor of image 1 and the index of the
// best; the largest dot product is the smallest distance for unit vectors.
struct BestTwo {
  std::vector<float> best;
  std::vector<float> second;
  std::vector<int> best_index;
  // n descriptors with no neighbour yet.
  void Reset(int n) {
    best.assign(n, kMinusInfinity);
    second.assign(n, kMinusInfinity);
    best_index.assign(n, -1);
  }
};

// The maximum of row[0, n) and the first index where it occurs (-1 when n is 0): the maximum
// first, with four independent vector maxima, then the first position that equals it (ties
// go to the smallest index, as a sequential scan finds).
void RowMax(const float* row, int n, float* max_value, int* max_index) {
  float maximum = kMinusInfinity;
  int i = 0;
#if defined(__AVX2__)
  // gcc does not vectorise either reduction.
  constexpr int kLanes = 8;
  __m256 max0 = _mm256_set1_ps(kMinusInfinity), max1 = max0, max2 = max0, max3 = max0;
  for (; i + 4 * kLanes <= n; i += 4 * kLanes) {
    max0 = _mm256_max_ps(max0, _mm256_loadu_ps(row + i));
    max1 = _mm256_max_ps(max1, _mm256_loadu_ps(row + i + kLanes));
    max2 = _mm256_max_ps(max2, _mm256_loadu_ps(row + i + 2 * kLanes));
    max3 = _mm256_max_ps(max3, _mm256_loadu_ps(row + i + 3 * kLanes));
  }
  for (; i + kLanes <= n; i += kLanes) max0 = _mm256_max_ps(max0, _mm256_loadu_ps(row + i));
  alignas(32) float lanes[kLanes];
  _mm256_store_ps(lanes, _mm256_max_ps(_mm256_max_ps(max0, max1), _mm256_max_ps(max2, max3)));
  for (const float lane : lanes) maximum = std::max(maximum, lane);
#endif
  for (; i < n; ++i) maximum = std::max(maximum, row[i]);
  *max_value = maximum;
  *max_index = -1;
  int k = 0;
#if defined(__AVX2__)
  const __m256 target = _mm256_set1_ps(maximum);
  for (; k + kLanes <= n; k += kLanes) {
    const int equal =
        _mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(row + k), target, _CMP_EQ_OQ));
    if (equal != 0) {
      *max_index = k + __builtin_ctz(static_cast<unsigned>(equal));
      return;
    }
  }
#endif
  for (; k < n; ++k) {
    if (row[k] == maximum) {
      *max_index = k;
      return;
    }
  }
}

// One value of column i, row index2 (rows in increasing order), into the column's running
// best, second best and index of the best.
inline void TopTwoStep(float value, int index2, float* best, float* second, int* best_index) {
  const bool above_best = value > *best;
  const bool above_second = value > *second;
  *second = above_best ? *best : (above_second ? value : *second);
  *best = above_best ? value : *best;
  *best_index = above_best ? index2 : *best_index;
}

#if defined(__AVX2__)
// The same for 8 columns at once.
inline void TopTwoStep(__m256 value, __m256i index2, __m256* best, __m256* second,
                       __m256i* best_index) {
  const __m256 above_best = _mm256_cmp_ps(value, *best, _CMP_GT_OQ);
  const __m256 above_second = _mm256_cmp_ps(value, *second, _CMP_GT_OQ);
  *second = _mm256_blendv_ps(_mm256_blendv_ps(*second, value, above_second), *best, above_best);
  *best = _mm256_blendv_ps(*best, value, above_best);
  *best_index = _mm256_blendv_epi8(*best_index, index2, _mm256_castps_si256(above_best));
}
#endif

// The running top-2 of each column i < num_cols over the tile's rows (rows c0, c0 + 1, ... of
// image 2). Blocks of 16 columns walk all rows with their state in registers: one load per
// 8 values instead of four loads and three stores.
void UpdateTopTwo(const float* tile, int num_rows, int num_cols, int stride, int c0, float* best,
                  float* second, int* best_index) {
  int i = 0;
#if defined(__AVX2__)
  for (; i + 16 <= num_cols; i += 16) {
    __m256 best0 = _mm256_loadu_ps(best + i), best1 = _mm256_loadu_ps(best + i + 8);
    __m256 second0 = _mm256_loadu_ps(second + i), second1 = _mm256_loadu_ps(second + i + 8);
    __m256i index0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(best_index + i));
    __m256i index1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(best_index + i + 8));
    for (int j = 0; j < num_rows; ++j) {
      const float* row = tile + static_cast<ptrdiff_t>(j) * stride + i;
      const __m256i index2 = _mm256_set1_epi32(c0 + j);
      TopTwoStep(_mm256_loadu_ps(row), index2, &best0, &second0, &index0);
      TopTwoStep(_mm256_loadu_ps(row + 8), index2, &best1, &second1, &index1);
    }
    _mm256_storeu_ps(best + i, best0);
    _mm256_storeu_ps(best + i + 8, best1);
    _mm256_storeu_ps(second + i, second0);
    _mm256_storeu_ps(second + i + 8, second1);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(best_index + i), index0);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(best_index + i + 8), index1);
  }
#endif
  for (; i < num_cols; ++i) {
    for (int j = 0; j < num_rows; ++j) {
      TopTwoStep(tile[static_cast<ptrdiff_t>(j) * stride + i], c0 + j, best + i, second + i,
                 best_index + i);
    }
  }
}

// tile(j, i) = tile[j * stride + i] = descriptors2[c0 + j] . descriptors1[r0 + i] for
// i < num_cols: the running top-2 per i (UpdateTopTwo), and the best i per j (the
// cross-check) as a reduction along each row.
void ScanTile(const float* tile, int num_rows, int num_cols, int stride, int c0, float* best,
              float* second, int* best_index, float* col_best, int* col_best_index, int r0) {
  UpdateTopTwo(tile, num_rows, num_cols, stride, c0, best, second, best_index);
  if (col_best == nullptr) return;
  for (int j = 0; j < num_rows; ++j) {
    const float* row = tile + static_cast<ptrdiff_t>(j) * stride;
    float lanes_max;
    int first;
    RowMax(row, num_cols, &lanes_max, &first);
    float value = col_best[j];
    int index = col_best_index[j];
    if (first >= 0 && lanes_max > value) {
      value = lanes_max;
      index = r0 + first;
    }
    col_best[j] = value;
    col_best_index[j] = index;
  }
}

// The matches of image 1's rows from their top-2 (ratio test, distance bound) and, when
// best_row_of_col is given, the cross-check: row i's best column must have i as its best.
// ||a - b||^2 = 2 - 2 a.b; the square roots are taken once per row, at the end. A missing
// second neighbour (one descriptor in image 2) has similarity -inf, i.e. infinite distance.
FeatureMatches SelectMatches(const BestTwo& rows, const std::vector<int>* best_row_of_col,
                             const FeatureMatchingOptions& options) {
  const float max_ratio = static_cast<float>(options.max_ratio);
  const float max_distance = static_cast<float>(options.max_distance);
  FeatureMatches matches;
  std::vector<float> ratios;
  for (size_t i = 0; i < rows.best.size(); ++i) {
    const int j = rows.best_index[i];
    if (j < 0) continue;
    const float distance1 = std::sqrt(std::max(0.0f, 2.0f - 2.0f * rows.best[i]));
    const float distance2 = std::sqrt(std::max(0.0f, 2.0f - 2.0f * rows.second[i]));
    if (distance1 > max_distance) continue;
    if (!(distance1 < max_ratio * distance2)) continue;
    if (best_row_of_col != nullptr && (*best_row_of_col)[j] != static_cast<int>(i)) continue;
    matches.push_back({static_cast<point2D_t>(i), static_cast<point2D_t>(j)});
    if (options.order_by_ratio) ratios.push_back(distance1 / distance2);
  }
  if (!options.order_by_ratio) return matches;
  // distance2 > 0 here (distance1 < max_ratio * distance2); an infinite one gives ratio 0.
  std::vector<size_t> order(matches.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&ratios](size_t a, size_t b) { return ratios[a] < ratios[b]; });
  FeatureMatches ordered(matches.size());
  for (size_t k = 0; k < order.size(); ++k) ordered[k] = matches[order[k]];
  return ordered;
}

}  // namespace

void FeatureMatchingOptions::Check() const {
  PARALLAX_CHECK_GT(max_ratio, 0.0);
  PARALLAX_CHECK_LE(max_ratio, 1.0);
  PARALLAX_CHECK_GT(max_distance, 0.0);
  PARALLAX_CHECK(num_threads == -1 || num_threads > 0);
}

MatchableDescriptors PrepareDescriptors(FeatureDescriptors descriptors) {
  MatchableDescriptors matchable;
  matchable.bytes = std::move(descriptors);
  const FeatureDescriptors& stored = matchable.bytes;
  matchable.scales.resize(static_cast<size_t>(stored.rows()));
  matchable.sums.resize(static_cast<size_t>(stored.rows()));
  const auto dim = static_cast<ptrdiff_t>(stored.cols());
  for (Eigen::Index row = 0; row < stored.rows(); ++row) {
    // The integer sum of squares is exact, and so is its conversion (below 2^24 for 128 bytes).
    // Through a row pointer: Eigen's (row, k) kept the compiler from vectorising the sums.
    const uint8_t* bytes = stored.data() + row * dim;
    int32_t sum = 0, sum_of_squares = 0;
    for (ptrdiff_t k = 0; k < dim; ++k) {
      sum += bytes[k];
      sum_of_squares += int32_t{bytes[k]} * bytes[k];
    }
    matchable.sums[row] = sum;
    // An all-zero row gets scale 0: similarity 0, distance sqrt(2) to everything, never matched.
    matchable.scales[row] =
        sum_of_squares > 0 ? 1.0f / std::sqrt(static_cast<float>(sum_of_squares)) : 0.0f;
  }
  return matchable;
}

void SelectRows(const MatchableDescriptors& descriptors, const std::vector<int>& rows,
                MatchableDescriptors* selected) {
  const auto num_rows = static_cast<Eigen::Index>(rows.size());
  GatherDescriptorRows(descriptors.bytes, rows, &selected->bytes);
  selected->scales.resize(rows.size());
  selected->sums.resize(rows.size());
  for (Eigen::Index k = 0; k < num_rows; ++k) {
    selected->scales[k] = descriptors.scales[rows[k]];
    selected->sums[k] = descriptors.sums[rows[k]];
  }
  selected->packed = {};
}

void PackRows(MatchableDescriptors* descriptors) {
  PackSimilarityColumns(descriptors->bytes.data(), descriptors->scales.data(),
                        descriptors->NumRows(), static_cast<int>(descriptors->bytes.cols()),
                        BestSimilarityKernel(), &descriptors->packed);
}

UnitDescriptorRows ToUnitRows(const FeatureDescriptors& descriptors) {
  UnitDescriptorRows values = descriptors.cast<float>();
  for (Eigen::Index row = 0; row < values.rows(); ++row) {
    const float norm = values.row(row).norm();
    if (norm > 0.0f) values.row(row) /= norm;
  }
  return values;
}

FeatureMatches MatchDescriptors(const MatchableDescriptors& descriptors1,
                                const MatchableDescriptors& descriptors2,
                                const FeatureMatchingOptions& options) {
  options.Check();
  const FeatureDescriptors& bytes1 = descriptors1.bytes;
  const FeatureDescriptors& bytes2 = descriptors2.bytes;
  const int num1 = descriptors1.NumRows();
  const int num2 = descriptors2.NumRows();
  PARALLAX_CHECK_EQ(descriptors1.scales.size(), static_cast<size_t>(num1));
  PARALLAX_CHECK_EQ(descriptors2.scales.size(), static_cast<size_t>(num2));
  PARALLAX_CHECK_EQ(descriptors2.sums.size(), static_cast<size_t>(num2));
  if (num1 == 0 || num2 == 0) return {};
  PARALLAX_CHECK_EQ(bytes1.cols(), bytes2.cols());

  // Enough row blocks to keep every thread busy, but not so small that the product is
  // dominated by packing the image-2 chunks.
  const int num_threads = EffectiveNumThreads(options.num_threads);
  int row_block = (num1 + 4 * num_threads - 1) / (4 * num_threads);
  // A multiple of the kernel's panel width, so that no block but the last computes padding.
  row_block = std::clamp(
      (row_block + kSimilarityPanelWidth - 1) / kSimilarityPanelWidth * kSimilarityPanelWidth,
      kMinRowBlock, kMaxRowBlock);
  const int num_row_blocks = (num1 + row_block - 1) / row_block;

  BestTwo rows;
  rows.Reset(num1);
  // Best row of each column, per row block (merged in block order below).
  std::vector<float> col_best;
  std::vector<int> col_best_index;
  if (options.cross_check) {
    col_best.assign(static_cast<size_t>(num_row_blocks) * num2, kMinusInfinity);
    col_best_index.assign(static_cast<size_t>(num_row_blocks) * num2, -1);
  }

  const int dim = static_cast<int>(bytes1.cols());
  const SimilarityKernel kernel = BestSimilarityKernel();
  ParallelFor(0, num_row_blocks, num_threads, [&](size_t block) {
    const int r0 = static_cast<int>(block) * row_block;
    const int num_rows1 = std::min(row_block, num1 - r0);
    // The block's descriptors in the kernel's layout: packed once for all of image 2, or
    // once for every pair when the caller packed image 1 (PackRows).
    PackedSimilarityColumns block1;
    SimilarityColumns columns1;
    if (descriptors1.packed.num_columns > 0 && descriptors1.packed.kernel == kernel) {
      columns1 = descriptors1.packed.Panels(r0, num_rows1);
    } else {
      PackSimilarityColumns(bytes1.row(r0).data(), descriptors1.scales.data() + r0, num_rows1, dim,
                            kernel, &block1);
      columns1 = block1.All();
    }
    const int stride = columns1.num_columns;
    std::vector<float> tile(static_cast<size_t>(kColBlock) * stride);
    for (int c0 = 0; c0 < num2; c0 += kColBlock) {
      const int num_rows2 = std::min(kColBlock, num2 - c0);
      const SimilarityRows rows2{bytes2.row(c0).data(), descriptors2.scales.data() + c0,
                                 descriptors2.sums.data() + c0, num_rows2};
      ComputeSimilarities(columns1, rows2, tile.data());
      const size_t col_offset = block * static_cast<size_t>(num2) + c0;
      ScanTile(tile.data(), num_rows2, num_rows1, stride, c0, rows.best.data() + r0,
               rows.second.data() + r0, rows.best_index.data() + r0,
               options.cross_check ? col_best.data() + col_offset : nullptr,
               options.cross_check ? col_best_index.data() + col_offset : nullptr, r0);
    }
  });

  std::vector<int> best_row_of_col;
  if (options.cross_check) {
    best_row_of_col.assign(num2, -1);
    for (int j = 0; j < num2; ++j) {
      float best = kMinusInfinity;
      for (int block = 0; block < num_row_blocks; ++block) {
        const size_t k = static_cast<size_t>(block) * num2 + j;
        if (col_best_index[k] >= 0 && (best_row_of_col[j] < 0 || col_best[k] > best)) {
          best = col_best[k];
          best_row_of_col[j] = col_best_index[k];
        }
      }
    }
  }

  return SelectMatches(rows, options.cross_check ? &best_row_of_col : nullptr, options);
}

FeatureMatches MatchDescriptorsInCells(const CellFiledDescriptors& filed1,
                                       const CellFiledDescriptors& filed2,
                                       const MatchableDescriptors& descriptors2,
                                       const FeatureMatchingOptions& options) {
  options.Check();
  PARALLAX_CHECK_EQ(filed1.cells.size(), filed2.cells.size());
  PARALLAX_CHECK_EQ(filed2.num_rows, descriptors2.NumRows());
  const int num1 = filed1.num_rows;
  const int num2 = filed2.num_rows;
  if (num1 == 0 || num2 == 0) return {};
  PARALLAX_CHECK_EQ(filed1.dim, filed2.dim);

  BestTwo rows;
  rows.Reset(num1);
  // Best row of image 1 for each row of image 2, over the cells it is filed under.
  std::vector<float> col_best(num2, kMinusInfinity);
  std::vector<int> best_row_of_col(num2, -1);

  // Per cell: the running top-2 of its queries over the descriptors filed under it, and the
  // best query of each of those (positions in the cell's lists until mapped back to rows).
  BestTwo cell_rows;
  std::vector<float> cell_col_best, tile;
  std::vector<int> cell_col_index;
  MatchableDescriptors cell_searched;  // One cell's searched rows, in the kernel's row layout.
  for (size_t c = 0; c < filed1.cells.size(); ++c) {
    const CellFiledDescriptors::Cell& query = filed1.cells[c];
    const CellFiledDescriptors::Cell& searched = filed2.cells[c];
    const int num_query = static_cast<int>(query.query_rows.size());
    const int num_searched = static_cast<int>(searched.searched_rows.size());
    if (num_query == 0 || num_searched == 0) continue;
    const int stride = query.query_columns.num_columns;
    tile.resize(static_cast<size_t>(kColBlock) * stride);
    cell_rows.Reset(num_query);
    if (options.cross_check) {
      cell_col_best.assign(num_searched, kMinusInfinity);
      cell_col_index.assign(num_searched, -1);
    }
    SelectRows(descriptors2, searched.searched_rows, &cell_searched);
    for (int c0 = 0; c0 < num_searched; c0 += kColBlock) {
      const int num_rows2 = std::min(kColBlock, num_searched - c0);
      const SimilarityRows rows2{cell_searched.bytes.row(c0).data(),
                                 cell_searched.scales.data() + c0, cell_searched.sums.data() + c0,
                                 num_rows2};
      ComputeSimilarities(query.query_columns, rows2, tile.data());
      ScanTile(tile.data(), num_rows2, num_query, stride, c0, cell_rows.best.data(),
               cell_rows.second.data(), cell_rows.best_index.data(),
               options.cross_check ? cell_col_best.data() + c0 : nullptr,
               options.cross_check ? cell_col_index.data() + c0 : nullptr, 0);
    }
    // Each query is in one cell only, so its top-2 is complete here. The lists ascend, so
    // ties went to the lower row, as in MatchDescriptors.
    for (int i = 0; i < num_query; ++i) {
      const int row1 = query.query_rows[i];
      rows.best[row1] = cell_rows.best[i];
      rows.second[row1] = cell_rows.second[i];
      const int position = cell_rows.best_index[i];
      rows.best_index[row1] = position >= 0 ? searched.searched_rows[position] : -1;
    }
    for (int j = 0; options.cross_check && j < num_searched; ++j) {
      if (cell_col_index[j] < 0) continue;
      const int row2 = searched.searched_rows[j];
      const int row1 = query.query_rows[cell_col_index[j]];
      if (cell_col_best[j] > col_best[row2] ||
          (cell_col_best[j] == col_best[row2] && row1 < best_row_of_col[row2])) {
        col_best[row2] = cell_col_best[j];
        best_row_of_col[row2] = row1;
      }
    }
  }
  return SelectMatches(rows, options.cross_check ? &best_row_of_col : nullptr, options);
}

}  // namespace parallax
