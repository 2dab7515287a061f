#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "parallax/estimators/two_view_geometry.h"
#include "parallax/feature/matcher.h"
#include "parallax/scene/database.h"

namespace parallax {

// Which image pairs are matched.
enum class PairMode {
  kExhaustive,  // Every pair.
  kSequential,  // Each image with the next `sequential_overlap` images in name order.
};

// "exhaustive" / "sequential"; nullopt for anything else.
std::optional<PairMode> PairModeFromName(const std::string& name);

struct FeatureMatchingPipelineOptions {
  FeatureMatchingOptions matching;  // Ratio test, distance bound, cross-check.
  TwoViewGeometryOptions geometry;  // Geometric verification (RANSAC threshold, inliers).
  PairMode pair_mode = PairMode::kExhaustive;
  int sequential_overlap = 10;  // Neighbours per image in sequential mode.
  int num_threads = -1;         // Pairs processed in parallel; -1: all cores.
  // Pairs written per transaction; a killed run loses at most one batch.
  int batch_size = 500;
  // Exhaustive mode walks blocks of this many images so that only about two blocks of
  // prepared descriptors are held in memory at once.
  int block_size = 50;
  void Check() const;
};

// Putative and verified match counts of one pair.
struct PairMatchStats {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  int num_putative = 0;
  int num_inliers = 0;
  int config = TwoViewGeometry::kUndefined;
};

struct FeatureMatchingStats {
  size_t num_pairs = 0;               // Pairs the mode selects.
  size_t num_skipped = 0;             // Already verified in the database (resumed run).
  size_t num_matched = 0;             // Matched (or read back) and verified in this run.
  size_t num_verified = 0;            // Of those, pairs with an accepted geometry.
  std::vector<PairMatchStats> pairs;  // One per pair processed in this run.
  double seconds = 0;
  // Time spent in descriptor matching and in verification, summed over threads.
  double matching_thread_seconds = 0;
  double verification_thread_seconds = 0;
};

// Image pairs in processing order, smaller position in `image_ids` first. `image_ids` are
// sorted by image name by the caller.
std::vector<std::pair<image_t, image_t>> ExhaustivePairs(const std::vector<image_t>& image_ids,
                                                         int block_size);
std::vector<std::pair<image_t, image_t>> SequentialPairs(const std::vector<image_t>& image_ids,
                                                         int overlap);

// Stages 2 and 3: matches SIFT descriptors of the selected pairs (ratio test, cross-check)
// and verifies them geometrically (F/E/H with LO-RANSAC), writing matches and
// two_view_geometries in batches, one transaction each. Pairs that already have a two-view
// geometry are skipped (resume); pairs with stored matches but no geometry are verified
// from those matches. Keypoints are used as stored (COLMAP's +0.5 pixel-centre convention).
FeatureMatchingStats MatchAndVerify(const FeatureMatchingPipelineOptions& options,
                                    Database* database);

}  // namespace parallax
