#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "parallax/estimators/two_view_geometry.h"
#include "parallax/feature/descriptor_cells.h"
#include "parallax/feature/matcher.h"
#include "parallax/pipeline/pair_selection.h"
#include "parallax/scene/database.h"

namespace parallax {

// Preemptive matching (Wu, "Towards Linear-time Incremental Structure from Motion", 3DV 2013):
// a pair whose few largest-scale features barely match is not worth the full match. Large
// features are the ones both views of an overlapping pair see (small ones vanish at the
// coarser scale of either view), so few matches among them mean little overlap.
struct PreemptiveMatchingOptions {
  // Off by default: on templeRing every setting that saves time also loses verified pairs
  // of 17 to 80 inliers (its largest features are the silhouette's, see docs/pair-selection.md).
  bool enabled = false;
  // Largest-scale features per image matched first (Wu: 100).
  int num_features = 100;
  // Fewer matches among those and the full match is skipped (Wu: 4).
  int min_matches = 4;
  // Lowe's ratio for the test's matches; 0: the full match's.
  double max_ratio = 0.0;
  void Check() const;
};

// Approximate nearest neighbours in descriptor matching (feature/descriptor_cells.h): each
// descriptor is compared only with the other image's descriptors near it, a few cells of a
// coarse k-means partition, instead of all of them.
struct ApproximateMatchingOptions {
  enum class Mode {
    kAuto,  // On for retrieval or GPS pairs, and for images of 512 or more descriptors.
    kOn,
    kOff,
  };
  Mode mode = Mode::kAuto;
  DescriptorCellsOptions cells;
  // The cells are trained on descriptors of up to this many images spread over the
  // collection (cells.max_training_descriptors of them in all).
  int max_training_images = 100;
  void Check() const;
};

// "auto", "on", "off"; nullopt for anything else.
std::optional<ApproximateMatchingOptions::Mode> ApproximateMatchingModeFromName(
    const std::string& name);

struct MatchingStageOptions {
  FeatureMatchingOptions matching;  // Ratio test, distance bound, cross-check.
  TwoViewGeometryOptions geometry;  // Geometric verification (RANSAC threshold, inliers).
  PairSelectionOptions pairs;       // Which pairs (exhaustive, retrieval, GPS, ...).
  PreemptiveMatchingOptions preemptive;
  ApproximateMatchingOptions approximate;
  int num_threads = -1;  // Pairs processed in parallel; -1: all cores.
  // The stage's one seed: each pair's verification RANSAC draws from a seed derived from it
  // and the pair's ids, and a vocabulary tree trained for retrieval samples with it.
  uint64_t seed = 0;
  // Pairs written per transaction; a killed run loses at most one batch.
  int batch_size = 500;
  void Check() const;
};

// Putative and verified match counts of one pair.
struct PairMatchStats {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  int num_putative = 0;
  int num_inliers = 0;
  int config = TwoViewGeometry::kUndefined;
  int num_preemptive_matches = -1;   // Matches among the largest features (-1: not tested).
  bool preemptive_rejected = false;  // The full match was skipped.
};

struct MatchingStageResult {
  PairSelection selection;             // How the pairs were chosen (pairs themselves cleared).
  bool preemptive = false;             // Whether the preemptive test ran.
  bool approximate = false;            // Whether descriptors were matched in cells.
  size_t num_pairs = 0;                // Pairs the mode selects ("considered").
  size_t num_skipped = 0;              // Already verified in the database (resumed run).
  size_t num_matched = 0;              // Matched (or read back) and verified in this run.
  size_t num_preemptive_rejected = 0;  // Of those, pairs the preemptive test stopped.
  size_t num_verified = 0;             // Of those, pairs with an accepted geometry.
  std::vector<PairMatchStats> pairs;   // One per pair processed in this run.
  double seconds = 0;
  // Time spent in descriptor matching and in verification, summed over threads.
  double matching_thread_seconds = 0;
  double verification_thread_seconds = 0;
};

// How the pairs of each round are shared among the ranks of a distributed run
// (distributed/). Every rank runs the stage; the coordinator chooses the pairs, each rank
// matches and verifies its share reading the features from the database and storing the
// results in its own shard, and the coordinator merges the shards into the database.
class PairSharing {
 public:
  virtual ~PairSharing() = default;
  // Whether this rank chooses the pairs and merges the results.
  virtual bool IsCoordinator() const = 0;
  // Every rank gets the coordinator's `pairs`, which it took `choosing_seconds` to choose
  // (the other ranks waited meanwhile; they pass 0).
  virtual void Share(std::vector<std::pair<image_t, image_t>>* pairs,
                     double choosing_seconds) const = 0;
  // This rank's share of `pairs` (the same list on every rank), in their order.
  virtual std::vector<std::pair<image_t, image_t>> ShareOf(
      const std::vector<std::pair<image_t, image_t>>& pairs) const = 0;
  // Where this rank stores its matches and geometries (valid until the next Merge).
  virtual Database* Store() = 0;
  // Returns once every rank has stored its share; on the coordinator, after moving every
  // pair the shards hold and `database` does not into `database`, with their statistics.
  virtual std::vector<PairMatchStats> Merge(Database* database) = 0;
};

// Stages 2 and 3: matches SIFT descriptors of the selected pairs (ratio test, cross-check)
// and verifies them geometrically (F/E/H with LO-RANSAC), writing matches and
// two_view_geometries in batches, one transaction each. Pairs that already have a two-view
// geometry are skipped (resume); pairs with stored matches but no geometry are verified
// from those matches. Keypoints are used as stored (COLMAP's +0.5 pixel-centre convention).
// With `sharing`, this is one rank's part of a distributed run; the coordinator's result
// counts the pairs of every rank as matched (thread times are its own).
MatchingStageResult RunMatchingStage(const MatchingStageOptions& options, Database* database,
                                     PairSharing* sharing = nullptr);

}  // namespace parallax
