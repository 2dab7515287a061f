#include "parallax/pipeline/matching_stage.h"

#include <algorithm>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/interrupt.h"
#include "parallax/util/logging.h"
#include "parallax/util/progress.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

// What matching and verification need of one image, loaded once per batch that uses it.
struct ImageFeatures {
  MatchableDescriptors descriptors;
  CellFiledDescriptors filed;           // Approximate matching's cells of `descriptors`.
  MatchableDescriptors largest;         // The preemptive test's largest-scale features.
  std::vector<Eigen::Vector2d> points;  // Keypoints as stored (pixel centres at +0.5).
};

struct PairJob {
  image_t image_id1;
  image_t image_id2;
  bool has_matches;        // Matches stored by an earlier run: verify those.
  FeatureMatches matches;  // Putative matches (read or computed).
  TwoViewGeometry geometry;
  double matching_seconds = 0;
  double verification_seconds = 0;
  int num_preemptive_matches = -1;
  bool preemptive_rejected = false;
  bool done = false;  // False when a signal stopped the batch before this pair ran.
};

bool IsVerified(const PairMatchStats& pair) {
  return pair.config != TwoViewGeometry::kUndefined &&
         pair.config != TwoViewGeometry::kDegenerate && pair.num_inliers > 0;
}

// The pairs without a two-view geometry in `database`; counts the others in `*num_stored`.
std::vector<std::pair<image_t, image_t>> PairsNotStored(
    const std::vector<std::pair<image_t, image_t>>& pairs, const Database& database,
    size_t* num_stored) {
  std::vector<std::pair<image_t, image_t>> remaining;
  for (const auto& pair : pairs) {
    if (database.ExistsTwoViewGeometry(pair.first, pair.second)) {
      ++*num_stored;
    } else {
      remaining.push_back(pair);
    }
  }
  return remaining;
}

// The rows of the `count` largest-scale keypoints (all when there are fewer).
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

// Whether approximate matching applies. `auto` turns it on where the pairs come from
// retrieval or GPS, and where the images have kMinMeanDescriptorsForCells descriptors or more
// on average: COLMAP 4 matches on the CPU through an inverted file (FAISS's IVF, 4 of
// 4 sqrt(n) lists probed) wherever the searched image has 512 or more, exhaustive matching
// included. Every rank of a distributed run reads the same counts, so all decide alike.
constexpr double kMinMeanDescriptorsForCells = 512;

bool UseApproximateMatching(const MatchingStageOptions& options,
                            const std::vector<image_t>& image_ids, const Database& database) {
  switch (options.approximate.mode) {
    case ApproximateMatchingOptions::Mode::kOn:
      return true;
    case ApproximateMatchingOptions::Mode::kOff:
      return false;
    case ApproximateMatchingOptions::Mode::kAuto:
      break;
  }
  const PairMode mode = ResolvedPairMode(options.pairs, image_ids.size());
  if (mode == PairMode::kRetrieval || mode == PairMode::kSpatial) return true;
  if (image_ids.empty()) return false;
  double num_descriptors = 0;
  for (const image_t image_id : image_ids) num_descriptors += database.NumKeypoints(image_id);
  return num_descriptors >= kMinMeanDescriptorsForCells * static_cast<double>(image_ids.size());
}

// The cells, trained on an even share of the rows of up to max_training_images images spread
// over `image_ids`: the same database gives the same cells on every rank. None without
// descriptors.
std::optional<DescriptorCells> TrainDescriptorCells(const ApproximateMatchingOptions& options,
                                                    const std::vector<image_t>& image_ids,
                                                    const Database& database) {
  const size_t num_images =
      std::min(image_ids.size(), static_cast<size_t>(options.max_training_images));
  const size_t rows_per_image =
      std::max<size_t>(1, options.cells.max_training_descriptors / std::max<size_t>(1, num_images));
  std::vector<FeatureDescriptors> parts;
  Eigen::Index num_rows = 0;
  for (size_t k = 0; k < num_images; ++k) {
    FeatureDescriptors descriptors =
        database.ReadDescriptors(image_ids[k * image_ids.size() / num_images]);
    const size_t stride =
        std::max<size_t>(1, static_cast<size_t>(descriptors.rows()) / rows_per_image);
    if (stride == 1) {
      num_rows += descriptors.rows();
      parts.push_back(std::move(descriptors));
      continue;
    }
    std::vector<int> rows;
    for (Eigen::Index row = 0; row < descriptors.rows(); row += static_cast<Eigen::Index>(stride))
      rows.push_back(static_cast<int>(row));
    GatherDescriptorRows(descriptors, rows, &parts.emplace_back());
    num_rows += parts.back().rows();
  }
  if (num_rows == 0) return std::nullopt;
  FeatureDescriptors sample(num_rows, parts.front().cols());
  uint8_t* out = sample.data();
  for (const FeatureDescriptors& part : parts) {
    out = std::copy_n(part.data(), part.size(), out);
  }
  return DescriptorCells::Train(std::move(sample), options.cells);
}

}  // namespace

std::optional<ApproximateMatchingOptions::Mode> ApproximateMatchingModeFromName(
    const std::string& name) {
  if (name == "auto") return ApproximateMatchingOptions::Mode::kAuto;
  if (name == "on") return ApproximateMatchingOptions::Mode::kOn;
  if (name == "off") return ApproximateMatchingOptions::Mode::kOff;
  return std::nullopt;
}

void ApproximateMatchingOptions::Check() const {
  cells.Check();
  PARALLAX_CHECK_GT(max_training_images, 0);
}

void PreemptiveMatchingOptions::Check() const {
  PARALLAX_CHECK_GT(num_features, 0);
  PARALLAX_CHECK_GE(min_matches, 0);
  PARALLAX_CHECK_GE(max_ratio, 0.0);
  PARALLAX_CHECK_LE(max_ratio, 1.0);
}

void MatchingStageOptions::Check() const {
  matching.Check();
  geometry.Check();
  pairs.Check();
  preemptive.Check();
  approximate.Check();
  PARALLAX_CHECK_GT(batch_size, 0);
}

MatchingStageResult RunMatchingStage(const MatchingStageOptions& options, Database* database,
                                     PairSharing* sharing) {
  options.Check();
  PARALLAX_CHECK(database != nullptr);
  const Timer timer;
  MatchingStageResult stats;
  const bool coordinator = sharing == nullptr || sharing->IsCoordinator();

  std::vector<Image> images = database->ReadAllImages();
  std::sort(images.begin(), images.end(),
            [](const Image& a, const Image& b) { return a.name < b.name; });
  std::vector<image_t> image_ids;
  std::unordered_map<image_t, camera_t> camera_of_image;
  for (const Image& image : images) {
    if (!database->ExistsKeypoints(image.image_id) ||
        !database->ExistsDescriptors(image.image_id)) {
      PARALLAX_LOG(Warning) << database->Path().string() << ": image " << image.name
                            << " has no features; not matched";
      continue;
    }
    image_ids.push_back(image.image_id);
    camera_of_image[image.image_id] = image.camera_id;
  }
  std::unordered_map<camera_t, Camera> cameras;
  for (Camera& camera : database->ReadAllCameras()) cameras[camera.camera_id] = std::move(camera);
  for (const auto& [image_id, camera_id] : camera_of_image) {
    if (cameras.count(camera_id) == 0) {
      throw InputError(database->Path().string() + ": image " + std::to_string(image_id) +
                       " refers to missing camera " + std::to_string(camera_id));
    }
  }

  // What the ranks of an interrupted distributed run stored goes into the database first, so
  // that no pair is matched again.
  if (sharing != nullptr) sharing->Merge(database);
  stats.preemptive = options.preemptive.enabled;
  std::vector<std::pair<image_t, image_t>> pairs;
  // The coordinator's time alone, as each loop round below measures it: the choice and the
  // look-up of the pairs already stored.
  const Timer first_round_timer;
  if (coordinator) {
    PairSelection selection = SelectPairs(options.pairs, image_ids, *database, options.seed);
    const std::vector<std::pair<image_t, image_t>> all_pairs = std::move(selection.pairs);
    selection.pairs.clear();
    stats.selection = selection;
    stats.num_pairs = all_pairs.size();
    pairs = PairsNotStored(all_pairs, *database, &stats.num_skipped);
    std::string mode_names;
    for (const PairMode mode : selection.modes)
      mode_names += (mode_names.empty() ? "" : " + ") + PairModeName(mode);
    PARALLAX_LOG(Info) << "Matching: " << image_ids.size() << " images, " << all_pairs.size() << " "
                       << mode_names << " pairs (" << selection.reason << "; chosen in "
                       << selection.seconds << " s), " << stats.num_skipped << " already verified, "
                       << pairs.size() << " to match"
                       << (stats.preemptive ? ", preemptive test on" : "");
  }
  if (sharing != nullptr)
    sharing->Share(&pairs, coordinator ? first_round_timer.ElapsedSeconds() : 0.0);

  // Trained even when every first-round pair is stored (a resumed run), so that the loop
  // pairs are matched as an uninterrupted run matches them.
  const Timer cells_timer;
  std::optional<DescriptorCells> cells;
  if (UseApproximateMatching(options, image_ids, *database)) {
    ApproximateMatchingOptions approximate = options.approximate;
    approximate.cells.num_threads = options.num_threads;  // Nothing else runs while it trains.
    cells = TrainDescriptorCells(approximate, image_ids, *database);
  }
  stats.approximate = cells.has_value();
  int num_cell_assignments = 0;
  if (cells) {
    num_cell_assignments = std::min(options.approximate.cells.num_assignments, cells->NumCells());
    PARALLAX_LOG(Info) << "Matching: approximate nearest neighbours, in " << cells->NumCells()
                       << " cells (each descriptor searched under its " << num_cell_assignments
                       << " nearest; trained in " << cells_timer.ElapsedSeconds() << " s)";
  }

  // Each pair runs on one thread; the parallelism is over pairs.
  FeatureMatchingOptions matching_options = options.matching;
  matching_options.num_threads = 1;
  FeatureMatchingOptions preemptive_matching_options = matching_options;
  if (options.preemptive.max_ratio > 0)
    preemptive_matching_options.max_ratio = options.preemptive.max_ratio;
  const size_t cache_capacity = 2 * static_cast<size_t>(options.pairs.block_size);
  std::unordered_map<image_t, ImageFeatures> cache;
  // Matches, verifies and stores `all_pairs` (this rank's share of them) in batches, one
  // transaction each.
  const auto match_pairs = [&](const std::vector<std::pair<image_t, image_t>>& all_pairs,
                               const char* label) {
    const std::vector<std::pair<image_t, image_t>> pairs =
        sharing != nullptr ? sharing->ShareOf(all_pairs) : all_pairs;
    Database* const store = sharing != nullptr ? sharing->Store() : database;
    std::vector<PairMatchStats> processed;
    ProgressReporter progress(label, pairs.size());

    for (size_t batch_start = 0; batch_start < pairs.size(); batch_start += options.batch_size) {
      const size_t batch_end = std::min(pairs.size(), batch_start + options.batch_size);

      // Load the images this batch needs (database reads are sequential; preparing the
      // descriptors is parallel).
      std::vector<image_t> needed;
      std::unordered_set<image_t> needed_set;
      for (size_t k = batch_start; k < batch_end; ++k) {
        for (image_t image_id : {pairs[k].first, pairs[k].second}) {
          if (needed_set.insert(image_id).second) needed.push_back(image_id);
        }
      }
      std::vector<image_t> missing;
      for (image_t image_id : needed) {
        if (cache.count(image_id) == 0) missing.push_back(image_id);
      }
      if (cache.size() + missing.size() > cache_capacity) {
        for (auto it = cache.begin(); it != cache.end();) {
          it = needed_set.count(it->first) > 0 ? std::next(it) : cache.erase(it);
        }
      }
      std::vector<FeatureDescriptors> raw_descriptors(missing.size());
      std::vector<FeatureKeypoints> keypoints(missing.size());
      for (size_t m = 0; m < missing.size(); ++m) {
        ImageFeatures& features = cache[missing[m]];
        keypoints[m] = database->ReadKeypoints(missing[m]);
        features.points.reserve(keypoints[m].size());
        for (const FeatureKeypoint& keypoint : keypoints[m]) {
          features.points.emplace_back(keypoint.x, keypoint.y);
        }
        raw_descriptors[m] = database->ReadDescriptors(missing[m]);
        if (static_cast<size_t>(raw_descriptors[m].rows()) != keypoints[m].size()) {
          throw InputError(database->Path().string() + ": image " + std::to_string(missing[m]) +
                           " has " + std::to_string(keypoints[m].size()) + " keypoints but " +
                           std::to_string(raw_descriptors[m].rows()) + " descriptors");
        }
      }
      ParallelFor(0, missing.size(), options.num_threads, [&](size_t m) {
        ImageFeatures& features = cache.at(missing[m]);
        features.descriptors = PrepareDescriptors(std::move(raw_descriptors[m]));
        // Exact matching reads an image's rows as image 1 of each of its pairs: packed once.
        if (!cells) PackRows(&features.descriptors);
        if (stats.preemptive) {
          features.largest =
              LargestFeatures(keypoints[m], features.descriptors, options.preemptive.num_features);
        }
        if (cells) {
          features.filed =
              FileDescriptorsByCell(features.descriptors, *cells, num_cell_assignments);
        }
      });
      raw_descriptors.clear();

      std::vector<PairJob> jobs(batch_end - batch_start);
      for (size_t k = 0; k < jobs.size(); ++k) {
        PairJob& job = jobs[k];
        job.image_id1 = pairs[batch_start + k].first;
        job.image_id2 = pairs[batch_start + k].second;
        job.has_matches = store->ExistsMatches(job.image_id1, job.image_id2);
        if (job.has_matches) job.matches = store->ReadMatches(job.image_id1, job.image_id2);
      }

      ParallelFor(0, jobs.size(), options.num_threads, [&](size_t k) {
        // After a signal no new pair starts; the finished ones are stored below.
        if (PendingInterruptSignal() != 0) return;
        PairJob& job = jobs[k];
        const ImageFeatures& features1 = cache.at(job.image_id1);
        const ImageFeatures& features2 = cache.at(job.image_id2);
        Timer pair_timer;
        if (!job.has_matches && stats.preemptive) {
          job.num_preemptive_matches = static_cast<int>(
              MatchDescriptors(features1.largest, features2.largest, preemptive_matching_options)
                  .size());
          job.preemptive_rejected = job.num_preemptive_matches < options.preemptive.min_matches;
        }
        if (!job.has_matches && !job.preemptive_rejected) {
          job.matches = cells ? MatchDescriptorsInCells(features1.filed, features2.filed,
                                                        features2.descriptors, matching_options)
                              : MatchDescriptors(features1.descriptors, features2.descriptors,
                                                 matching_options);
        }
        job.matching_seconds = pair_timer.ElapsedSeconds();
        pair_timer.Restart();
        if (static_cast<int>(job.matches.size()) < options.geometry.min_num_inliers) {
          // Too few to verify: recorded as degenerate so a resumed run does not retry it.
          job.geometry.config = TwoViewGeometry::kDegenerate;
        } else {
          // The pair's seed comes from the run's and the pair's ids: the result does not
          // depend on which thread verifies the pair, nor in what order.
          TwoViewGeometryOptions pair_options = options.geometry;
          pair_options.ransac.random_seed =
              DeriveSeed(options.seed, ImagePairToPairId(job.image_id1, job.image_id2));
          job.geometry = EstimateTwoViewGeometry(cameras.at(camera_of_image.at(job.image_id1)),
                                                 features1.points,
                                                 cameras.at(camera_of_image.at(job.image_id2)),
                                                 features2.points, job.matches, pair_options);
        }
        job.verification_seconds = pair_timer.ElapsedSeconds();
        job.done = true;
        progress.Increment();
      });

      DatabaseTransaction transaction(store);
      for (const PairJob& job : jobs) {
        if (!job.done) continue;
        if (!job.has_matches) store->WriteMatches(job.image_id1, job.image_id2, job.matches);
        store->WriteTwoViewGeometry(job.image_id1, job.image_id2, job.geometry);
      }
      transaction.Commit();

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
        stats.matching_thread_seconds += job.matching_seconds;
        stats.verification_thread_seconds += job.verification_seconds;
      }
      ThrowIfInterrupted(std::to_string(processed.size()) + " of " + std::to_string(pairs.size()) +
                         " pairs are matched and verified in " + store->Path().string());
    }
    progress.Finish();
    if (sharing != nullptr) processed = sharing->Merge(database);
    for (const PairMatchStats& pair_stats : processed) {
      ++stats.num_matched;
      if (pair_stats.preemptive_rejected) ++stats.num_preemptive_rejected;
      if (IsVerified(pair_stats)) ++stats.num_verified;
      stats.pairs.push_back(pair_stats);
    }
  };
  match_pairs(pairs, "matching");

  // Pairs that close loops: images that verified pairs tie together but retrieval missed.
  // The coordinator chooses them; the other ranks learn from an empty list that it is over.
  const bool retrieval = std::find(stats.selection.modes.begin(), stats.selection.modes.end(),
                                   PairMode::kRetrieval) != stats.selection.modes.end();
  for (int round = 0; options.pairs.retrieval.num_loop_neighbors > 0 &&
                      round < options.pairs.retrieval.num_loop_rounds;
       ++round) {
    std::vector<std::pair<image_t, image_t>> loop_pairs;
    const Timer choosing_timer;
    if (coordinator && retrieval) {
      std::vector<std::pair<image_pair_t, int>> verified;
      for (const auto& [pair_id, num_inliers] : database->ReadTwoViewGeometryNumInliers()) {
        if (num_inliers >= options.geometry.min_num_inliers)
          verified.emplace_back(pair_id, num_inliers);
      }
      // Pairs tried and rejected before are not candidates again (nor counted as skipped).
      size_t num_rejected_before = 0;
      loop_pairs = PairsNotStored(
          LoopClosingPairs(verified, image_ids, options.pairs.retrieval.num_loop_neighbors),
          *database, &num_rejected_before);
      if (!loop_pairs.empty()) {
        stats.num_pairs += loop_pairs.size();
        stats.selection.num_loop_pairs += loop_pairs.size();
        PARALLAX_LOG(Info) << "Matching: " << loop_pairs.size() << " pairs that close loops (round "
                           << round + 1 << ": neighbours of verified neighbours) to match";
        loop_pairs = OrderPairsForLocality(std::move(loop_pairs), image_ids);
      }
    }
    if (sharing != nullptr)
      sharing->Share(&loop_pairs, coordinator ? choosing_timer.ElapsedSeconds() : 0.0);
    if (loop_pairs.empty()) break;
    match_pairs(loop_pairs, "matching loops");
  }

  stats.seconds = timer.ElapsedSeconds();
  PARALLAX_LOG(Info) << "Matching: " << stats.num_matched << " pairs matched ("
                     << stats.num_preemptive_rejected << " stopped by the preemptive test), "
                     << stats.num_verified << " verified, " << stats.num_skipped << " skipped, "
                     << stats.seconds << " s (thread time: matching "
                     << stats.matching_thread_seconds << " s, verification "
                     << stats.verification_thread_seconds << " s)";
  return stats;
}

}  // namespace parallax
