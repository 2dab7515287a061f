#include "parallax/pipeline/matching_stage.h"

#include <algorithm>
#include <optional>
#include <unordered_map>

#include "parallax/pipeline/pair_batch_matcher.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/progress.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

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

// The images with features, sorted by name, and the cameras they use.
struct MatchableImages {
  std::vector<image_t> image_ids;
  std::unordered_map<image_t, camera_t> camera_of_image;
  std::unordered_map<camera_t, Camera> cameras;
};

MatchableImages ReadMatchableImages(const Database& database) {
  std::vector<Image> images = database.ReadAllImages();
  std::sort(images.begin(), images.end(),
            [](const Image& a, const Image& b) { return a.name < b.name; });
  MatchableImages matchable;
  for (const Image& image : images) {
    if (!database.ExistsKeypoints(image.image_id) || !database.ExistsDescriptors(image.image_id)) {
      PARALLAX_LOG(Warning) << database.Path().string() << ": image " << image.name
                            << " has no features; not matched";
      continue;
    }
    matchable.image_ids.push_back(image.image_id);
    matchable.camera_of_image[image.image_id] = image.camera_id;
  }
  for (Camera& camera : database.ReadAllCameras()) {
    matchable.cameras[camera.camera_id] = std::move(camera);
  }
  for (const auto& [image_id, camera_id] : matchable.camera_of_image) {
    if (matchable.cameras.count(camera_id) == 0) {
      throw InputError(database.Path().string() + ": image " + std::to_string(image_id) +
                       " refers to missing camera " + std::to_string(camera_id));
    }
  }
  return matchable;
}

// The verified pairs' loop-closing neighbours that no earlier round tried (retrieval's
// second chance for images that verified pairs tie together).
std::vector<std::pair<image_t, image_t>> LoopPairsToMatch(const MatchingStageOptions& options,
                                                          const std::vector<image_t>& image_ids,
                                                          const Database& database) {
  std::vector<std::pair<image_pair_t, int>> verified;
  for (const auto& [pair_id, num_inliers] : database.ReadTwoViewGeometryNumInliers()) {
    if (num_inliers >= options.geometry.min_num_inliers)
      verified.emplace_back(pair_id, num_inliers);
  }
  // Pairs tried and rejected before are not candidates again (nor counted as skipped).
  size_t num_rejected_before = 0;
  return PairsNotStored(
      LoopClosingPairs(verified, image_ids, options.pairs.retrieval.num_loop_neighbors), database,
      &num_rejected_before);
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

  const MatchableImages matchable = ReadMatchableImages(*database);
  const std::vector<image_t>& image_ids = matchable.image_ids;

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
  if (cells) {
    PARALLAX_LOG(Info) << "Matching: approximate nearest neighbours, in " << cells->NumCells()
                       << " cells (each descriptor searched under its "
                       << std::min(options.approximate.cells.num_assignments, cells->NumCells())
                       << " nearest; trained in " << cells_timer.ElapsedSeconds() << " s)";
  }

  PairBatchMatcher matcher(options, *database, matchable.cameras, matchable.camera_of_image,
                           cells ? &*cells : nullptr);
  // This rank's share of `all_pairs` matched, verified and stored, then every rank's counted.
  const auto match_pairs = [&](const std::vector<std::pair<image_t, image_t>>& all_pairs,
                               const char* label) {
    const std::vector<std::pair<image_t, image_t>> pairs =
        sharing != nullptr ? sharing->ShareOf(all_pairs) : all_pairs;
    Database* const store = sharing != nullptr ? sharing->Store() : database;
    ProgressReporter progress(label, pairs.size());
    std::vector<PairMatchStats> processed =
        matcher.MatchPairs(pairs, store, &progress, &stats.matching_thread_seconds,
                           &stats.verification_thread_seconds);
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
      loop_pairs = LoopPairsToMatch(options, image_ids, *database);
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
