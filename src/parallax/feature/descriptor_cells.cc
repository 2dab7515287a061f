#include "parallax/feature/descriptor_cells.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

// Rows whose similarities to the centroids are computed at once (a 256 x 32 tile).
constexpr int kRowChunk = 256;

// The `count` largest of values[0, n) by index, largest first, ties to the lower index: an
// insertion into the kept list, which for 1 to 4 of 32 cells is a few compares per value
// where a partial sort of the indices was a visible share of training (docs/performance.md,
// "Matching cells: the largest indices by insertion").
void TopIndices(const float* values, int n, int count, uint16_t* out) {
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const float value = values[i];
    // Strictly greater: an equal value is at a higher index than the kept one, so after it.
    if (kept == count && !(value > values[out[kept - 1]])) continue;
    int position = kept < count ? kept++ : count - 1;
    for (; position > 0 && value > values[out[position - 1]]; --position) {
      out[position] = out[position - 1];
    }
    out[position] = static_cast<uint16_t>(i);
  }
}

// Cosine similarity of two rows, exactly as the kernels compute it.
float RowSimilarity(const MatchableDescriptors& rows, int a, int b) {
  int32_t dot = 0;
  for (Eigen::Index k = 0; k < rows.bytes.cols(); ++k) dot += rows.bytes(a, k) * rows.bytes(b, k);
  return static_cast<float>(dot) * rows.scales[a] * rows.scales[b];
}

// k-means++ seeding (Arthur & Vassilvitskii 2007) on the rows order[0, kMaxSeedingRows): each
// seed is drawn with probability proportional to its squared distance to the nearest seed so
// far, so that well-separated groups each get one. Returns rows.
std::vector<int> KMeansPlusPlusSeeds(const MatchableDescriptors& rows,
                                     const std::vector<int>& order, int count,
                                     std::mt19937_64* generator) {
  constexpr int kMaxSeedingRows = 20000;
  const int num_rows = std::min(static_cast<int>(order.size()), kMaxSeedingRows);
  std::vector<int> seeds = {
      static_cast<int>(std::uniform_int_distribution<int>(0, num_rows - 1)(*generator))};
  std::vector<double> distance(num_rows, std::numeric_limits<double>::infinity());
  while (static_cast<int>(seeds.size()) < count) {
    double total = 0;
    for (int i = 0; i < num_rows; ++i) {
      // ||a - b||^2 = 2 - 2 a.b for unit rows.
      const double to_last =
          std::max(0.0, 2.0 - 2.0 * RowSimilarity(rows, order[i], order[seeds.back()]));
      distance[i] = std::min(distance[i], to_last);
      total += distance[i];
    }
    int next = static_cast<int>(seeds.size()) % num_rows;  // All rows equal: any will do.
    if (total > 0) {
      double target = std::uniform_real_distribution<double>(0.0, total)(*generator);
      for (next = 0; next + 1 < num_rows && target >= distance[next]; ++next) {
        target -= distance[next];
      }
    }
    seeds.push_back(next);
  }
  for (int& seed : seeds) seed = order[seed];
  return seeds;
}

}  // namespace

void DescriptorCellsOptions::Check() const {
  PARALLAX_CHECK_GT(num_cells, 0);
  PARALLAX_CHECK_LE(num_cells, 256);
  PARALLAX_CHECK_GT(num_assignments, 0);
  PARALLAX_CHECK_GT(max_training_descriptors, 0);
  PARALLAX_CHECK_GT(kmeans_iterations, 0);
  PARALLAX_CHECK(num_threads == -1 || num_threads > 0);
}

DescriptorCells DescriptorCells::Train(FeatureDescriptors sample,
                                       const DescriptorCellsOptions& options) {
  options.Check();
  const int num_rows = static_cast<int>(sample.rows());
  const int dim = static_cast<int>(sample.cols());
  PARALLAX_CHECK_GT(num_rows, 0);
  std::mt19937_64 generator(options.seed);
  std::vector<int> order(num_rows);
  std::iota(order.begin(), order.end(), 0);
  const int num_training = std::min(num_rows, options.max_training_descriptors);
  Shuffle(static_cast<size_t>(num_training), &order, &generator);
  order.resize(num_training);
  const int num_cells = std::min(options.num_cells, num_training);
  // The training rows: the whole sample where it is small enough, else the rows the shuffle
  // chose, in its order. Seeding follows the shuffled order either way; the assignments and
  // the integer means do not depend on the order of the rows, so the cells are the same as
  // from a shuffled copy, without one (a fresh copy of a collection's sample cost more on
  // this kind of machine, in first touches of its memory, than the k-means steps).
  MatchableDescriptors rows;
  if (num_training < num_rows) {
    FeatureDescriptors training;
    GatherDescriptorRows(sample, order, &training);
    std::iota(order.begin(), order.end(), 0);
    rows = PrepareDescriptors(std::move(training));
  } else {
    rows = PrepareDescriptors(std::move(sample));
  }

  DescriptorCells cells;
  cells.centroids_.resize(num_cells, dim);
  const std::vector<int> seeds = KMeansPlusPlusSeeds(rows, order, num_cells, &generator);
  for (int cell = 0; cell < num_cells; ++cell)
    cells.centroids_.row(cell) = rows.bytes.row(seeds[cell]);
  std::vector<uint16_t> assignment(num_training, 0), previous;
  for (int iteration = 0; iteration < options.kmeans_iterations; ++iteration) {
    cells.Pack();
    previous = assignment;
    assignment = cells.NearestCells(rows, 1, options.num_threads);
    if (iteration > 0 && assignment == previous) break;
    // Each centroid moves to the mean of its rows (rounded to bytes); an empty cell stays.
    std::vector<int64_t> sums(static_cast<size_t>(num_cells) * dim, 0);
    std::vector<int64_t> counts(num_cells, 0);
    for (int i = 0; i < num_training; ++i) {
      const int cell = assignment[i];
      ++counts[cell];
      const uint8_t* row = rows.bytes.data() + static_cast<size_t>(i) * dim;
      int64_t* sum = sums.data() + static_cast<size_t>(cell) * dim;
      for (int k = 0; k < dim; ++k) sum[k] += row[k];
    }
    for (int cell = 0; cell < num_cells; ++cell) {
      if (counts[cell] == 0) continue;
      for (int k = 0; k < dim; ++k) {
        const int64_t sum = sums[static_cast<size_t>(cell) * dim + k];
        // Integer rounding to nearest: the centroid does not depend on float arithmetic.
        cells.centroids_(cell, k) =
            static_cast<uint8_t>((2 * sum + counts[cell]) / (2 * counts[cell]));
      }
    }
  }
  cells.Pack();
  return cells;
}

void DescriptorCells::Pack() {
  const MatchableDescriptors centroids = PrepareDescriptors(centroids_);
  PackSimilarityColumns(centroids.bytes.data(), centroids.scales.data(), NumCells(),
                        static_cast<int>(centroids_.cols()), BestSimilarityKernel(), &packed_);
}

std::vector<uint16_t> DescriptorCells::NearestCells(const MatchableDescriptors& descriptors,
                                                    int count, int num_threads) const {
  const int num_cells = NumCells();
  PARALLAX_CHECK_GT(num_cells, 0);
  PARALLAX_CHECK_GT(count, 0);
  PARALLAX_CHECK_LE(count, num_cells);
  PARALLAX_CHECK_EQ(descriptors.bytes.cols(), centroids_.cols());
  const PackedSimilarityColumns& packed = packed_;
  const int num_rows = descriptors.NumRows();
  std::vector<uint16_t> nearest(static_cast<size_t>(num_rows) * count);
  const int num_chunks = (num_rows + kRowChunk - 1) / kRowChunk;
  ParallelFor(0, static_cast<size_t>(num_chunks), num_threads, [&](size_t chunk_index) {
    thread_local std::vector<float> tile;
    tile.resize(static_cast<size_t>(kRowChunk) * packed.num_columns);
    const int r0 = static_cast<int>(chunk_index) * kRowChunk;
    const int chunk = std::min(kRowChunk, num_rows - r0);
    const SimilarityRows rows{descriptors.bytes.row(r0).data(), descriptors.scales.data() + r0,
                              descriptors.sums.data() + r0, chunk};
    ComputeSimilarities(packed, rows, tile.data());
    for (int j = 0; j < chunk; ++j) {
      TopIndices(tile.data() + static_cast<ptrdiff_t>(j) * packed.num_columns, num_cells, count,
                 nearest.data() + static_cast<size_t>(r0 + j) * count);
    }
  });
  return nearest;
}

CellFiledDescriptors FileDescriptorsByCell(const MatchableDescriptors& descriptors,
                                           const DescriptorCells& cells, int num_assignments) {
  CellFiledDescriptors filed;
  filed.num_rows = descriptors.NumRows();
  filed.dim = static_cast<int>(descriptors.bytes.cols());
  filed.cells.resize(cells.NumCells());
  if (filed.num_rows == 0) return filed;
  const std::vector<uint16_t> nearest = cells.NearestCells(descriptors, num_assignments);
  const int dim = filed.dim;
  for (int row = 0; row < filed.num_rows; ++row) {
    const uint16_t* row_cells = nearest.data() + static_cast<size_t>(row) * num_assignments;
    filed.cells[row_cells[0]].query_rows.push_back(row);
    for (int k = 0; k < num_assignments; ++k)
      filed.cells[row_cells[k]].searched_rows.push_back(row);
  }
  const SimilarityKernel kernel = BestSimilarityKernel();
  MatchableDescriptors query;
  for (CellFiledDescriptors::Cell& cell : filed.cells) {
    if (cell.query_rows.empty()) continue;
    SelectRows(descriptors, cell.query_rows, &query);
    PackSimilarityColumns(query.bytes.data(), query.scales.data(), query.NumRows(), dim, kernel,
                          &cell.query_columns);
  }
  return filed;
}

}  // namespace parallax
