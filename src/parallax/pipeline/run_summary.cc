#include "parallax/pipeline/run_summary.h"

#include <cmath>

#include "parallax/report/evaluation.h"
#include "parallax/util/file.h"

namespace parallax {

namespace {
nlohmann::json NumberOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

// How a model started: from a given model, or from a pair and the thresholds it met (step 0:
// as given; k: relaxed k times).
nlohmann::json ModelStartToJson(const ModelStartReport& start,
                                const std::map<image_t, std::string>& image_names) {
  if (start.from_input_model) return {{"from", "input model"}};
  const auto name = [&image_names](image_t image_id) {
    const auto it = image_names.find(image_id);
    return it == image_names.end() ? std::to_string(image_id) : it->second;
  };
  return {{"from", "pair"},
          {"images", {name(start.image_id1), name(start.image_id2)}},
          {"min_inliers", start.thresholds.min_num_inliers},
          {"min_tri_angle_deg", start.thresholds.min_angle_deg},
          {"relaxation_step", start.thresholds.step},
          {"triangulated", start.num_triangulated},
          {"median_tri_angle_deg", start.median_angle_deg},
          {"pairs_tried_before", start.num_pairs_tried}};
}

}  // namespace

nlohmann::json BuildRunSummary(const MappingStageResult& result, const StageTimings& timings) {
  nlohmann::json summary;
  const Reconstruction* model = result.models.empty() ? nullptr : &result.models.front();
  size_t num_registered = 0;
  for (const auto& [image_id, report] : result.summary.images) {
    if (report.model_index >= 0) ++num_registered;
  }
  summary["images_total"] = result.image_names.size();
  summary["images_registered"] = num_registered;
  summary["images_registered_largest_model"] = model ? model->NumRegImages() : 0;
  summary["points3D"] = model ? model->NumPoints3D() : 0;
  summary["observations"] = model ? model->NumObservations() : 0;
  summary["mean_track_length"] = model ? model->ComputeMeanTrackLength() : 0.0;
  summary["track_length_histogram"] = TrackLengthHistogramToJson(
      model ? model->ComputeTrackLengthHistogram() : std::map<size_t, size_t>());
  double mean_error = 0;
  if (model) {
    Reconstruction copy = *model;
    mean_error = copy.UpdatePointErrors();
  }
  summary["mean_reprojection_error_px"] = mean_error;
  if (!result.summary.failure.empty()) summary["failure"] = result.summary.failure;

  nlohmann::json stage_times = nlohmann::json::object();
  double total = 0;
  for (const auto& [stage, seconds] : timings) {
    stage_times[stage] = seconds;
    total += seconds;
  }
  stage_times["total"] = total;
  summary["timings_s"] = stage_times;
  nlohmann::json phase_times = nlohmann::json::object();
  for (const auto& [name, seconds] : result.summary.phase_seconds.Named()) {
    phase_times[name] = seconds;
  }
  summary["mapper"] = {{"type", result.hierarchical ? "hierarchical" : "incremental"},
                       {"local_bundle_adjustments", result.summary.num_local_ba},
                       {"global_bundle_adjustments", result.summary.num_global_ba},
                       {"bundle_adjustment_s", result.summary.BaSeconds()},
                       {"phase_s", phase_times},
                       {"load_s", result.load_seconds},
                       {"write_s", result.write_seconds}};
  if (!result.mapper_type_reason.empty()) {
    summary["mapper"]["type_reason"] = result.mapper_type_reason;
  }
  if (result.num_input_model_images > 0 || !result.input_model_images_missing.empty()) {
    // An extended model: the images that kept their poses, and those that are gone.
    summary["mapper"]["input_model"] = {{"images_kept", result.num_input_model_images},
                                        {"images_missing", result.input_model_images_missing}};
  }
  if (result.hierarchical) {
    const HierarchicalMapperSummary& hierarchical = *result.hierarchical;
    nlohmann::json clusters = nlohmann::json::array();
    for (const ClusterReport& cluster : hierarchical.clusters) {
      nlohmann::json merges = nlohmann::json::array();
      for (const ModelMergeReport& merge : cluster.merges) {
        merges.push_back({{"merged", merge.success},
                          {"shared_images", merge.num_shared_images},
                          {"shared_points", merge.num_correspondences},
                          {"agreeing_points", merge.num_inliers}});
      }
      clusters.push_back({{"images", cluster.num_images},
                          {"pairs", cluster.num_pairs},
                          {"model_sizes", cluster.model_sizes},
                          {"merges", merges},
                          {"seconds", cluster.seconds}});
    }
    summary["mapper"]["hierarchical"] = {{"clusters", clusters},
                                         {"clusters_s", hierarchical.cluster_seconds},
                                         {"merge_s", hierarchical.merge_seconds},
                                         {"refine_s", hierarchical.refine_seconds}};
  }

  nlohmann::json images = nlohmann::json::array();
  for (const auto& [image_id, name] : result.image_names) {
    nlohmann::json entry;
    entry["image_id"] = image_id;
    entry["name"] = name;
    const auto keypoints = result.num_keypoints.find(image_id);
    entry["num_keypoints"] = keypoints == result.num_keypoints.end() ? 0 : keypoints->second;
    const auto it = result.summary.images.find(image_id);
    const MapperImageReport report =
        it == result.summary.images.end() ? MapperImageReport() : it->second;
    entry["registered"] = report.model_index >= 0;
    entry["model"] = report.model_index;
    size_t num_observations = 0;
    if (report.model_index >= 0) {
      num_observations = result.models[report.model_index].GetImage(image_id).num_points3D;
    }
    entry["num_observations"] = num_observations;
    if (report.registered_relaxed) entry["registered_at_relaxed_pnp_thresholds"] = true;
    entry["reprojection_error_before_ba_px"] = NumberOrNull(report.error_before_ba_px);
    entry["reprojection_error_after_ba_px"] = NumberOrNull(report.error_after_ba_px);
    if (report.model_index < 0) {
      entry["reason"] = report.reason;
      entry["registration_attempts"] = report.num_registration_trials;
      entry["relaxed_registration_attempts"] = report.num_relaxed_registration_trials;
      entry["visible_points_at_last_attempt"] = report.num_visible_points;
      entry["pnp_inliers_at_last_attempt"] = report.num_pnp_inliers;
    }
    images.push_back(entry);
  }
  summary["images"] = images;

  nlohmann::json models = nlohmann::json::array();
  for (size_t index = 0; index < result.models.size(); ++index) {
    nlohmann::json entry = {{"path", "sparse/" + std::to_string(index)},
                            {"images_registered", result.models[index].NumRegImages()},
                            {"points3D", result.models[index].NumPoints3D()}};
    if (index < result.summary.models.size()) {
      const MapperModelReport& report = result.summary.models[index];
      entry["start"] = ModelStartToJson(report.start, result.image_names);
      entry["joined_models"] = report.num_joined_models;
      nlohmann::json links = nlohmann::json::array();
      for (const ModelLink& link : report.links) {
        links.push_back({{"model", link.model_index},
                         {"image_pairs", link.num_image_pairs},
                         {"matches", link.num_matches}});
      }
      entry["links"] = links;
    }
    models.push_back(entry);
  }
  summary["mapper"]["discarded_models"] = result.summary.num_discarded_models;
  summary["models"] = models;
  return summary;
}

nlohmann::json MatchingSummary(const MatchingStageResult& stats) {
  nlohmann::json modes = nlohmann::json::array();
  for (const PairMode mode : stats.selection.modes) modes.push_back(PairModeName(mode));
  nlohmann::json summary = {{"pair_modes", modes},
                            {"pair_choice", stats.selection.reason},
                            {"pairs_considered", stats.num_pairs},
                            {"pairs_skipped_already_stored", stats.num_skipped},
                            {"pairs_matched", stats.num_matched},
                            {"preemptive", stats.preemptive},
                            {"pairs_stopped_by_preemptive_test", stats.num_preemptive_rejected},
                            {"approximate_matching", stats.approximate},
                            {"pairs_verified", stats.num_verified},
                            {"pair_selection_seconds", stats.selection.seconds},
                            {"seconds", stats.seconds},
                            {"matching_thread_seconds", stats.matching_thread_seconds},
                            {"verification_thread_seconds", stats.verification_thread_seconds}};
  if (stats.selection.num_retrieval_pairs > 0)
    summary["retrieval_pairs"] = stats.selection.num_retrieval_pairs;
  if (stats.selection.num_spatial_pairs > 0)
    summary["spatial_pairs"] = stats.selection.num_spatial_pairs;
  if (stats.selection.num_loop_pairs > 0) summary["loop_pairs"] = stats.selection.num_loop_pairs;
  if (!stats.selection.vocab_tree_path.empty()) {
    summary["vocab_tree"] = stats.selection.vocab_tree_path.string();
    summary["vocab_tree_trained"] = stats.selection.trained_vocab_tree;
  }
  return summary;
}

void WriteRunSummary(const nlohmann::json& summary, const std::filesystem::path& path) {
  WriteTextFileAtomically(path, summary.dump(2) + "\n");
}

std::vector<std::string> UnregisteredImageLines(const MappingStageResult& result) {
  std::vector<std::string> lines;
  for (const auto& [image_id, report] : result.summary.images) {
    if (report.model_index >= 0) continue;
    const auto name = result.image_names.find(image_id);
    lines.push_back((name == result.image_names.end() ? std::to_string(image_id) : name->second) +
                    ": not registered: " + report.reason);
  }
  return lines;
}

}  // namespace parallax
