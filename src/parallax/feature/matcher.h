#pragma once

#include <vector>

#include "parallax/feature/similarity_kernel.h"
#include "parallax/feature/types.h"

namespace parallax {

struct FeatureMatchingOptions {
  double max_ratio = 0.8;     // Lowe's ratio test on Euclidean distances.
  double max_distance = 0.7;  // Absolute bound on the (unit-vector) Euclidean distance.
  bool cross_check = true;    // Keep only mutual nearest neighbours.
  // Matches by increasing ratio of their distances (the most distinctive first, ties in
  // image 1's order): the quality order that progressive RANSAC sampling draws from
  // (RansacSampler::kProgressive). Otherwise in image 1's keypoint order.
  bool order_by_ratio = false;
  int num_threads = -1;  // -1: all cores.
  void Check() const;
};

// Descriptors ready for matching: the stored bytes and each row's 1 / norm, so that the
// cosine similarity of two rows is an exact integer dot product times their scales.
struct MatchableDescriptors {
  FeatureDescriptors bytes;   // N x 128, as stored.
  std::vector<float> scales;  // 1 / norm per row (0 for an all-zero row).
  std::vector<int32_t> sums;  // Sum of each row's bytes (SimilarityRows).
  // Every row in the similarity kernel's layout, once PackRows has run; empty otherwise, and
  // then MatchDescriptors packs image 1's rows for each pair.
  PackedSimilarityColumns packed;
  int NumRows() const { return static_cast<int>(bytes.rows()); }
};
MatchableDescriptors PrepareDescriptors(FeatureDescriptors descriptors);

// Packs the rows for this CPU's similarity kernel, for descriptors that are image 1 of many
// pairs: packed once, not once per pair (docs/performance.md, "Descriptors packed once per image").
void PackRows(MatchableDescriptors* descriptors);

// `rows` of `descriptors`, in that order, with their scales and sums (what PrepareDescriptors
// of those rows gives, without computing it again). `selected`'s storage is reused.
void SelectRows(const MatchableDescriptors& descriptors, const std::vector<int>& rows,
                MatchableDescriptors* selected);

// The descriptors as unit-norm float rows (an all-zero row stays zero): what vocabulary trees
// and other matchers take.
using UnitDescriptorRows = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
UnitDescriptorRows ToUnitRows(const FeatureDescriptors& descriptors);

// Nearest neighbours by ||a - b||^2 = 2 - 2 a.b for the unit vectors a and b, computed
// blockwise as a matrix product; ratio test, distance bound and optional cross-check.
FeatureMatches MatchDescriptors(const MatchableDescriptors& descriptors1,
                                const MatchableDescriptors& descriptors2,
                                const FeatureMatchingOptions& options);

// The same tests with approximate nearest neighbours: each descriptor of image 1 is compared
// only with the descriptors of image 2 filed under its cell (descriptor_cells.h), about
// num_assignments / num_cells of them; its best and second best, and the cross-check, are
// taken among those. filed2 files the rows of descriptors2. On one thread (the matching
// stage runs pairs in parallel).
struct CellFiledDescriptors;
FeatureMatches MatchDescriptorsInCells(const CellFiledDescriptors& filed1,
                                       const CellFiledDescriptors& filed2,
                                       const MatchableDescriptors& descriptors2,
                                       const FeatureMatchingOptions& options);

}  // namespace parallax
