#include "parallax/pipeline/pair_batch_matcher.h"

#include <algorithm>
#include <string>
#include <unordered_set>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/interrupt.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {

MatchableDescriptors LargestFeatures(const FeatureKeypoints& keypoints,
                                     const MatchableDescriptors& descriptors, int count) {
  std::vector<int> order(keypoints.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  const size_t keep = std::min(order.size(), static_cast<size_t>(count));
  std::partial_sort(order.begin(), order.begin() + keep, order.end(), [&keypoints](int a, int b) {
    const float scale_a = keypoints[a].ComputeScale(), scale_b = keypoints[b].ComputeScale();
    return scale_a != scale_b ? scale_a > scale_b : a < b;
  });
  order.resize(keep);
  MatchableDescriptors largest;
  SelectRows(descriptors, order, &largest);
  return largest;
}

PairBatchMatcher::PairBatchMatcher(const MatchingStageOptions& options, const Database& database,
                                   const std::unordered_map<camera_t, Camera>& cameras,
                                   const std::unordered_map<image_t, camera_t>& camera_of_image,
                                   const DescriptorCells* cells)
    : options_(options),
      database_(database),
      cameras_(cameras),
      camera_of_image_(camera_of_image),
      cells_(cells) {
  if (cells_ != nullptr) {
    num_cell_assignments_ = std::min(options.approximate.cells.num_assignments, cells_->NumCells());
  }
  matching_options_ = options.matching;
  matching_options_.num_threads = 1;
  preemptive_options_ = matching_options_;
  if (options.preemptive.max_ratio > 0)
    preemptive_options_.max_ratio = options.preemptive.max_ratio;
}

void PairBatchMatcher::LoadFeatures(const std::vector<image_t>& image_ids) {
  const std::unordered_set<image_t> needed(image_ids.begin(), image_ids.end());
  std::vector<image_t> missing;
  for (image_t image_id : image_ids) {
    if (cache_.count(image_id) == 0) missing.push_back(image_id);
  }
  const size_t capacity = 2 * static_cast<size_t>(options_.pairs.block_size);
  if (cache_.size() + missing.size() > capacity) {
    for (auto it = cache_.begin(); it != cache_.end();) {
      it = needed.count(it->first) > 0 ? std::next(it) : cache_.erase(it);
    }
  }
  // Database reads are sequential; preparing the descriptors is parallel.
  std::vector<FeatureDescriptors> raw_descriptors(missing.size());
  std::vector<FeatureKeypoints> keypoints(missing.size());
  for (size_t m = 0; m < missing.size(); ++m) {
    ImageFeatures& features = cache_[missing[m]];
    keypoints[m] = database_.ReadKeypoints(missing[m]);
    features.points.reserve(keypoints[m].size());
    for (const FeatureKeypoint& keypoint : keypoints[m]) {
      features.points.emplace_back(keypoint.x, keypoint.y);
    }
    raw_descriptors[m] = database_.ReadDescriptors(missing[m]);
    if (static_cast<size_t>(raw_descriptors[m].rows()) != keypoints[m].size()) {
      throw InputError(database_.Path().string() + ": image " + std::to_string(missing[m]) +
                       " has " + std::to_string(keypoints[m].size()) + " keypoints but " +
                       std::to_string(raw_descriptors[m].rows()) + " descriptors");
    }
  }
  ParallelFor(0, missing.size(), options_.num_threads, [&](size_t m) {
    ImageFeatures& features = cache_.at(missing[m]);
    features.descriptors = PrepareDescriptors(std::move(raw_descriptors[m]));
    // Exact matching reads an image's rows as image 1 of each of its pairs: packed once.
    if (cells_ == nullptr) PackRows(&features.descriptors);
    if (options_.preemptive.enabled) {
      features.largest =
          LargestFeatures(keypoints[m], features.descriptors, options_.preemptive.num_features);
    }
    if (cells_ != nullptr) {
      features.filed = FileDescriptorsByCell(features.descriptors, *cells_, num_cell_assignments_);
    }
  });
}

void PairBatchMatcher::MatchAndVerify(PairJob* job) const {
  const ImageFeatures& features1 = cache_.at(job->image_id1);
  const ImageFeatures& features2 = cache_.at(job->image_id2);
  Timer pair_timer;
  if (!job->has_matches && options_.preemptive.enabled) {
    job->num_preemptive_matches = static_cast<int>(
        MatchDescriptors(features1.largest, features2.largest, preemptive_options_).size());
    job->preemptive_rejected = job->num_preemptive_matches < options_.preemptive.min_matches;
  }
  if (!job->has_matches && !job->preemptive_rejected) {
    job->matches =
        cells_ != nullptr
            ? MatchDescriptorsInCells(features1.filed, features2.filed, features2.descriptors,
                                      matching_options_)
            : MatchDescriptors(features1.descriptors, features2.descriptors, matching_options_);
  }
  job->matching_seconds = pair_timer.ElapsedSeconds();
  pair_timer.Restart();
  if (static_cast<int>(job->matches.size()) < options_.geometry.min_num_inliers) {
    // Too few to verify: recorded as degenerate so a resumed run does not retry it.
    job->geometry.config = TwoViewGeometry::kDegenerate;
  } else {
    // The pair's seed comes from the run's and the pair's ids: the result does not depend on
    // which thread verifies the pair, nor in what order.
    TwoViewGeometryOptions pair_options = options_.geometry;
    pair_options.ransac.random_seed =
        DeriveSeed(options_.seed, ImagePairToPairId(job->image_id1, job->image_id2));
    job->geometry =
        EstimateTwoViewGeometry(cameras_.at(camera_of_image_.at(job->image_id1)), features1.points,
                                cameras_.at(camera_of_image_.at(job->image_id2)), features2.points,
                                job->matches, pair_options);
  }
  job->verification_seconds = pair_timer.ElapsedSeconds();
  job->done = true;
}

void PairBatchMatcher::StoreJobs(const std::vector<PairJob>& jobs, Database* store) {
  DatabaseTransaction transaction(store);
  for (const PairJob& job : jobs) {
    if (!job.done) continue;
    if (!job.has_matches) store->WriteMatches(job.image_id1, job.image_id2, job.matches);
    store->WriteTwoViewGeometry(job.image_id1, job.image_id2, job.geometry);
  }
  transaction.Commit();
}

std::vector<PairMatchStats> PairBatchMatcher::MatchPairs(
    const std::vector<std::pair<image_t, image_t>>& pairs, Database* store,
    ProgressReporter* progress, double* matching_thread_seconds,
    double* verification_thread_seconds) {
  PARALLAX_CHECK(store != nullptr && progress != nullptr);
  std::vector<PairMatchStats> processed;
  for (size_t batch_start = 0; batch_start < pairs.size(); batch_start += options_.batch_size) {
    const size_t batch_end = std::min(pairs.size(), batch_start + options_.batch_size);
    std::vector<image_t> needed;
    std::unordered_set<image_t> needed_set;
    for (size_t k = batch_start; k < batch_end; ++k) {
      for (image_t image_id : {pairs[k].first, pairs[k].second}) {
        if (needed_set.insert(image_id).second) needed.push_back(image_id);
      }
    }
    LoadFeatures(needed);

    std::vector<PairJob> jobs(batch_end - batch_start);
    for (size_t k = 0; k < jobs.size(); ++k) {
      PairJob& job = jobs[k];
      job.image_id1 = pairs[batch_start + k].first;
      job.image_id2 = pairs[batch_start + k].second;
      job.has_matches = store->ExistsMatches(job.image_id1, job.image_id2);
      if (job.has_matches) job.matches = store->ReadMatches(job.image_id1, job.image_id2);
    }
    ParallelFor(0, jobs.size(), options_.num_threads, [&](size_t k) {
      // After a signal no new pair starts; the finished ones are stored below.
      if (PendingInterruptSignal() != 0) return;
      MatchAndVerify(&jobs[k]);
      progress->Increment();
    });
    StoreJobs(jobs, store);

    for (const PairJob& job : jobs) {
      if (!job.done) continue;
      PairMatchStats pair_stats;
      pair_stats.image_id1 = job.image_id1;
      pair_stats.image_id2 = job.image_id2;
      pair_stats.num_putative = static_cast<int>(job.matches.size());
      pair_stats.num_inliers = static_cast<int>(job.geometry.inlier_matches.size());
      pair_stats.config = job.geometry.config;
      pair_stats.num_preemptive_matches = job.num_preemptive_matches;
      pair_stats.preemptive_rejected = job.preemptive_rejected;
      processed.push_back(pair_stats);
      *matching_thread_seconds += job.matching_seconds;
      *verification_thread_seconds += job.verification_seconds;
    }
    ThrowIfInterrupted(std::to_string(processed.size()) + " of " + std::to_string(pairs.size()) +
                       " pairs are matched and verified in " + store->Path().string());
  }
  return processed;
}

}  // namespace parallax
