#pragma once

#include <unordered_map>
#include <utility>
#include <vector>

#include "parallax/pipeline/matching_stage.h"
#include "parallax/util/progress.h"

namespace parallax {

// What matching and verification need of one image, loaded once for the batches that use it.
struct ImageFeatures {
  MatchableDescriptors descriptors;
  CellFiledDescriptors filed;           // Approximate matching's cells of `descriptors`.
  MatchableDescriptors largest;         // The preemptive test's largest-scale features.
  std::vector<Eigen::Vector2d> points;  // Keypoints as stored (pixel centres at +0.5).
};

// One pair's work and outcome.
struct PairJob {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  bool has_matches = false;  // Matches stored by an earlier run: verify those.
  FeatureMatches matches;    // Putative matches (read or computed).
  TwoViewGeometry geometry;
  double matching_seconds = 0;
  double verification_seconds = 0;
  int num_preemptive_matches = -1;
  bool preemptive_rejected = false;
  bool done = false;  // False when a signal stopped the batch before this pair ran.
};

// The rows of the `count` largest-scale keypoints (all when there are fewer).
MatchableDescriptors LargestFeatures(const FeatureKeypoints& keypoints,
                                     const MatchableDescriptors& descriptors, int count);

// The matching stage's work on a list of pairs, in batches of options.batch_size, each in
// three steps: load the features the batch needs (LoadFeatures), match and verify each pair
// on a thread of its own (MatchAndVerify), store the batch in one transaction (StoreJobs).
// Features are read from `database`; matches and geometries go to the store MatchPairs is
// given (a shard of a distributed run, or the database).
class PairBatchMatcher {
 public:
  // `cells`: approximate matching's partition, or nullptr for exact matching.
  PairBatchMatcher(const MatchingStageOptions& options, const Database& database,
                   const std::unordered_map<camera_t, Camera>& cameras,
                   const std::unordered_map<image_t, camera_t>& camera_of_image,
                   const DescriptorCells* cells);

  // Matches, verifies and stores every pair; returns the finished pairs' statistics and adds
  // the threads' time to the two sums. After a signal the finished pairs of the batch are
  // stored and InterruptedError says how many are.
  std::vector<PairMatchStats> MatchPairs(const std::vector<std::pair<image_t, image_t>>& pairs,
                                         Database* store, ProgressReporter* progress,
                                         double* matching_thread_seconds,
                                         double* verification_thread_seconds);

  // The features of `image_ids` in the cache (those missing read and prepared; others not
  // among them dropped when the cache would outgrow twice the pairs' block size).
  void LoadFeatures(const std::vector<image_t>& image_ids);
  const ImageFeatures& Features(image_t image_id) const { return cache_.at(image_id); }
  // The preemptive test (when on and the pair has no stored matches), the putative matches,
  // and the verified geometry; degenerate when too few matches to verify. Both images'
  // features must be loaded.
  void MatchAndVerify(PairJob* job) const;
  // The batch's finished pairs, in one transaction.
  static void StoreJobs(const std::vector<PairJob>& jobs, Database* store);

 private:
  const MatchingStageOptions& options_;
  const Database& database_;
  const std::unordered_map<camera_t, Camera>& cameras_;
  const std::unordered_map<image_t, camera_t>& camera_of_image_;
  const DescriptorCells* cells_;
  int num_cell_assignments_ = 0;
  FeatureMatchingOptions matching_options_;    // One thread each: the pairs run in parallel.
  FeatureMatchingOptions preemptive_options_;  // The preemptive test's ratio.
  std::unordered_map<image_t, ImageFeatures> cache_;
};

}  // namespace parallax
