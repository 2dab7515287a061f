#pragma once

#include <cstdint>
#include <vector>

#include "parallax/feature/matcher.h"
#include "parallax/feature/similarity_kernel.h"

namespace parallax {

// A coarse partition of descriptor space for approximate matching: an inverted file (FAISS's
// IVF; Jegou, Douze & Schmid, "Product quantization for nearest neighbor search", PAMI 2011).
// A descriptor of one image is compared only with the descriptors of the other that are filed
// under its nearest cell, and each of those is filed under its few nearest cells (multiple
// assignment), so that a neighbour just across a cell border is still found.
struct DescriptorCellsOptions {
  int num_cells = 32;  // k of the spherical k-means.
  // Cells each descriptor of the searched image is filed under, nearest first (all of them
  // when there are fewer).
  int num_assignments = 4;
  int max_training_descriptors = 100000;
  int kmeans_iterations = 10;
  uint64_t seed = 0;  // The training sample and the first centroids.
  // Threads of training's assignment steps (-1: all cores); the cells do not depend on it.
  int num_threads = 1;
  void Check() const;
};

// The cells: centroids stored as bytes like the descriptors, so that a descriptor's similarity
// to each is an exact integer dot product (SimilarityKernel) and a descriptor falls in the
// same cell on every CPU, as the matches that depend on it must.
class DescriptorCells {
 public:
  DescriptorCells() = default;  // No cells: NearestCells fails its check.

  // Spherical k-means (cosine similarity) on up to max_training_descriptors rows of `sample`,
  // chosen with the seed, from k-means++ seeds drawn with it.
  static DescriptorCells Train(FeatureDescriptors sample, const DescriptorCellsOptions& options);

  int NumCells() const { return static_cast<int>(centroids_.rows()); }
  const FeatureDescriptors& Centroids() const { return centroids_; }

  // The `count` most similar cells of each row, most similar first (ties: lower cell):
  // result[row * count + k].
  // Row chunks run on up to num_threads threads (the result does not depend on how many).
  std::vector<uint16_t> NearestCells(const MatchableDescriptors& descriptors, int count,
                                     int num_threads = 1) const;

 private:
  void Pack();  // packed_ from centroids_.

  FeatureDescriptors centroids_;  // num_cells x dimension.
  PackedSimilarityColumns packed_;
};

// One image's descriptors filed by cell for MatchDescriptorsInCells. As a query image, each
// descriptor is in its nearest cell, packed for the similarity kernel; as the searched image,
// each descriptor is listed under each of its num_assignments nearest cells (the rows
// themselves are gathered from the image's MatchableDescriptors when searched, so that a
// descriptor is stored once). Row lists ascend.
struct CellFiledDescriptors {
  struct Cell {
    std::vector<int> query_rows;
    PackedSimilarityColumns query_columns;
    std::vector<int> searched_rows;
  };
  int num_rows = 0;
  int dim = 0;
  std::vector<Cell> cells;
};

CellFiledDescriptors FileDescriptorsByCell(const MatchableDescriptors& descriptors,
                                           const DescriptorCells& cells, int num_assignments);

}  // namespace parallax
