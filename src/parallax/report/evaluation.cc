#include "parallax/report/evaluation.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "parallax/estimators/similarity_transform.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace {

std::string FileName(const std::string& name) {
  return std::filesystem::path(name).filename().string();
}
std::string Stem(const std::string& name) { return std::filesystem::path(name).stem().string(); }

// Finds GT views by name, by file name, or by stem; keys shared by several views are
// dropped from the looser maps so that a match is never ambiguous.
class NameMatcher {
 public:
  explicit NameMatcher(const GroundTruth& gt) {
    for (size_t i = 0; i < gt.images.size(); ++i) {
      Insert(gt.images[i].name, i, &exact_);
      Insert(FileName(gt.images[i].name), i, &file_name_);
      Insert(Stem(gt.images[i].name), i, &stem_);
    }
  }

  // GT index of a model image name, or -1.
  long Find(const std::string& name) const {
    for (const auto& [map, key] : {std::pair{&exact_, name}, std::pair{&file_name_, FileName(name)},
                                   std::pair{&stem_, Stem(name)}}) {
      const auto it = map->find(key);
      if (it != map->end() && it->second >= 0) return it->second;
    }
    return -1;
  }

 private:
  static void Insert(const std::string& key, size_t index,
                     std::unordered_map<std::string, long>* map) {
    const auto [it, inserted] = map->emplace(key, static_cast<long>(index));
    if (!inserted) it->second = -1;  // ambiguous
  }
  std::unordered_map<std::string, long> exact_, file_name_, stem_;
};

ErrorStatistics ComputeStatistics(std::vector<double> values) {
  ErrorStatistics statistics;
  statistics.count = values.size();
  if (values.empty()) return statistics;
  std::sort(values.begin(), values.end());
  const size_t mid = values.size() / 2;
  statistics.median = values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  double sum = 0;
  for (double value : values) sum += value;
  statistics.mean = sum / values.size();
  statistics.max = values.back();
  return statistics;
}

// `errors` has one entry per GT image; +inf marks a failure.
std::vector<AccuracyAtThreshold> ComputeAccuracy(const std::vector<double>& errors,
                                                 const std::vector<double>& thresholds) {
  std::vector<AccuracyAtThreshold> curve;
  for (double threshold : thresholds) {
    AccuracyAtThreshold point;
    point.threshold = threshold;
    if (!errors.empty()) {
      double num_below = 0, area = 0;
      for (double error : errors) {
        if (error <= threshold) num_below += 1;
        area += std::max(0.0, 1.0 - error / threshold);
      }
      point.fraction = num_below / errors.size();
      point.auc = area / errors.size();
    }
    curve.push_back(point);
  }
  return curve;
}

nlohmann::json StatisticsToJson(const ErrorStatistics& statistics) {
  return {{"count", statistics.count},
          {"median", statistics.median},
          {"mean", statistics.mean},
          {"max", statistics.max}};
}

nlohmann::json CurveToJson(const std::vector<AccuracyAtThreshold>& curve) {
  nlohmann::json array = nlohmann::json::array();
  for (const AccuracyAtThreshold& point : curve) {
    array.push_back(
        {{"threshold", point.threshold}, {"fraction", point.fraction}, {"auc", point.auc}});
  }
  return array;
}

}  // namespace

void EvaluationOptions::Check() const {
  PARALLAX_CHECK_GT(alignment_max_error_ratio, 0.0);
  PARALLAX_CHECK_GE(alignment_max_error, 0.0);
  alignment_ransac.Check();
  for (double threshold : rotation_thresholds_deg) PARALLAX_CHECK_GT(threshold, 0.0);
  for (double threshold : center_thresholds_ratio) PARALLAX_CHECK_GT(threshold, 0.0);
}

nlohmann::json TrackLengthHistogramToJson(const std::map<size_t, size_t>& histogram) {
  nlohmann::json bins = nlohmann::json::array();
  for (const auto& [length, count] : histogram) {
    bins.push_back({{"length", length}, {"points", count}});
  }
  return bins;
}

EvaluationMetrics EvaluateReconstruction(const Reconstruction& model, const GroundTruth& gt,
                                         const EvaluationOptions& options) {
  options.Check();
  EvaluationMetrics metrics;
  metrics.num_gt_images = gt.images.size();
  metrics.num_model_images = model.NumImages();
  metrics.num_model_registered = model.NumRegImages();
  metrics.num_points3D = model.NumPoints3D();
  metrics.num_observations = model.NumObservations();
  metrics.mean_track_length = model.ComputeMeanTrackLength();
  metrics.track_length_histogram = model.ComputeTrackLengthHistogram();

  double error_sum = 0;
  size_t error_count = 0;
  for (const auto& [point3D_id, point] : model.Points3D()) {
    for (const TrackElement& element : point.track.elements) {
      const double error = model.ReprojectionError(element.image_id, element.point2D_idx);
      if (!std::isfinite(error)) continue;
      error_sum += error;
      ++error_count;
    }
  }
  metrics.mean_reprojection_error_px = error_count > 0 ? error_sum / error_count : 0.0;

  metrics.images.resize(gt.images.size());
  for (size_t i = 0; i < gt.images.size(); ++i) metrics.images[i].name = gt.images[i].name;

  // Pair model images with GT views.
  const NameMatcher matcher(gt);
  std::vector<size_t> matched_gt_indices;
  std::vector<Eigen::Vector3d> model_centers, gt_centers;
  for (const auto& [image_id, image] : model.Images()) {
    const long gt_index = matcher.Find(image.name);
    if (gt_index < 0) continue;
    ImageEvaluation& evaluation = metrics.images[gt_index];
    if (evaluation.image_id != kInvalidImageId) {
      PARALLAX_LOG(Warning) << "images '" << model.GetImage(evaluation.image_id).name << "' and '"
                            << image.name << "' both match ground truth '" << evaluation.name
                            << "'; keeping the first";
      continue;
    }
    evaluation.image_id = image_id;
    evaluation.registered = image.registered;
    if (!image.registered) continue;
    matched_gt_indices.push_back(static_cast<size_t>(gt_index));
    model_centers.push_back(image.ProjectionCenter());
    gt_centers.push_back(parallax::ProjectionCenter(gt.images[gt_index].cam_from_world));
  }
  metrics.num_registered_in_gt = matched_gt_indices.size();

  Eigen::Vector3d gt_centroid = Eigen::Vector3d::Zero();
  for (const GroundTruthImage& view : gt.images) {
    gt_centroid += parallax::ProjectionCenter(view.cam_from_world);
  }
  if (!gt.images.empty()) gt_centroid /= static_cast<double>(gt.images.size());
  for (const GroundTruthImage& view : gt.images) {
    metrics.gt_scene_scale +=
        (parallax::ProjectionCenter(view.cam_from_world) - gt_centroid).norm();
  }
  if (!gt.images.empty()) metrics.gt_scene_scale /= static_cast<double>(gt.images.size());

  // A similarity needs three centres; with coincident GT centres there is no scale to use.
  if (matched_gt_indices.size() >= 3 && metrics.gt_scene_scale > 0) {
    RansacOptions ransac_options = options.alignment_ransac;
    ransac_options.max_error = options.alignment_max_error > 0
                                   ? options.alignment_max_error
                                   : options.alignment_max_error_ratio * metrics.gt_scene_scale;
    const Sim3dRansacReport report = EstimateSim3dRansac(model_centers, gt_centers, ransac_options);
    metrics.alignment_success = report.success;
    if (report.success) {
      metrics.gt_from_model = report.dst_from_src;
      metrics.num_alignment_inliers = report.num_inliers;
      for (size_t k = 0; k < matched_gt_indices.size(); ++k) {
        if (k < report.inlier_mask.size() && report.inlier_mask[k]) {
          metrics.images[matched_gt_indices[k]].alignment_inlier = true;
        }
      }
    }
  }
  if (!metrics.alignment_success) {
    PARALLAX_LOG(Warning) << "evaluation: no similarity aligns the model with " << gt.source << " ("
                          << matched_gt_indices.size() << " registered images in the GT)";
  }

  constexpr double kFailed = std::numeric_limits<double>::infinity();
  std::vector<double> center_errors, center_ratios, rotation_errors;
  std::vector<double> all_center_ratios(gt.images.size(), kFailed);
  std::vector<double> all_rotation_errors(gt.images.size(), kFailed);
  if (metrics.alignment_success) {
    for (size_t gt_index : matched_gt_indices) {
      ImageEvaluation& evaluation = metrics.images[gt_index];
      const Image& image = model.GetImage(evaluation.image_id);
      const GroundTruthImage& view = gt.images[gt_index];
      const Rigid3d cam_from_gt = TransformCameraPose(metrics.gt_from_model, image.cam_from_world);
      evaluation.center_error = (parallax::ProjectionCenter(cam_from_gt) -
                                 parallax::ProjectionCenter(view.cam_from_world))
                                    .norm();
      evaluation.center_error_ratio = evaluation.center_error / metrics.gt_scene_scale;
      evaluation.rotation_error_deg =
          RotationAngleDegrees(cam_from_gt.rotation, view.cam_from_world.rotation);
      center_errors.push_back(evaluation.center_error);
      center_ratios.push_back(evaluation.center_error_ratio);
      rotation_errors.push_back(evaluation.rotation_error_deg);
      all_center_ratios[gt_index] = evaluation.center_error_ratio;
      all_rotation_errors[gt_index] = evaluation.rotation_error_deg;
    }
  }
  metrics.center_error = ComputeStatistics(center_errors);
  metrics.center_error_ratio = ComputeStatistics(center_ratios);
  metrics.rotation_error_deg = ComputeStatistics(rotation_errors);
  metrics.rotation_accuracy = ComputeAccuracy(all_rotation_errors, options.rotation_thresholds_deg);
  metrics.center_accuracy = ComputeAccuracy(all_center_ratios, options.center_thresholds_ratio);
  return metrics;
}

nlohmann::json MetricsToJson(const EvaluationMetrics& metrics) {
  nlohmann::json json;
  json["images_gt"] = metrics.num_gt_images;
  json["images_model"] = metrics.num_model_images;
  json["images_registered"] = metrics.num_model_registered;
  json["images_registered_in_gt"] = metrics.num_registered_in_gt;
  json["alignment"] = {
      {"success", metrics.alignment_success},
      {"num_inliers", metrics.num_alignment_inliers},
      {"scale", metrics.gt_from_model.scale},
      {"rotation_wxyz",
       {metrics.gt_from_model.rotation.w(), metrics.gt_from_model.rotation.x(),
        metrics.gt_from_model.rotation.y(), metrics.gt_from_model.rotation.z()}},
      {"translation",
       {metrics.gt_from_model.translation.x(), metrics.gt_from_model.translation.y(),
        metrics.gt_from_model.translation.z()}}};
  json["gt_scene_scale"] = metrics.gt_scene_scale;
  json["center_error"] = StatisticsToJson(metrics.center_error);
  json["center_error_relative"] = StatisticsToJson(metrics.center_error_ratio);
  json["rotation_error_deg"] = StatisticsToJson(metrics.rotation_error_deg);
  json["rotation_accuracy"] = CurveToJson(metrics.rotation_accuracy);
  json["center_accuracy_relative"] = CurveToJson(metrics.center_accuracy);
  json["points3D"] = metrics.num_points3D;
  json["observations"] = metrics.num_observations;
  json["mean_track_length"] = metrics.mean_track_length;
  json["track_length_histogram"] = TrackLengthHistogramToJson(metrics.track_length_histogram);
  json["mean_reprojection_error_px"] = metrics.mean_reprojection_error_px;
  nlohmann::json images = nlohmann::json::array();
  for (const ImageEvaluation& image : metrics.images) {
    nlohmann::json entry = {{"name", image.name}, {"registered", image.registered}};
    if (image.registered && metrics.alignment_success) {
      entry["alignment_inlier"] = image.alignment_inlier;
      entry["center_error"] = image.center_error;
      entry["center_error_relative"] = image.center_error_ratio;
      entry["rotation_error_deg"] = image.rotation_error_deg;
    }
    images.push_back(std::move(entry));
  }
  json["images"] = std::move(images);
  return json;
}

std::string MetricsToText(const EvaluationMetrics& metrics) {
  std::ostringstream out;
  auto fixed = [](double value, int precision) {
    std::ostringstream stream;
    stream.setf(std::ios::fixed);
    stream.precision(precision);
    stream << value;
    return stream.str();
  };
  auto general = [](double value) {
    std::ostringstream stream;
    stream.precision(6);
    stream << value;
    return stream.str();
  };
  auto triple = [&](const ErrorStatistics& statistics, double factor, int precision) {
    return fixed(factor * statistics.median, precision) + " / " +
           fixed(factor * statistics.mean, precision) + " / " +
           fixed(factor * statistics.max, precision);
  };
  auto row = [&](const std::string& label, const std::string& value) {
    std::string padded = "  " + label;
    padded.resize(std::max<size_t>(padded.size() + 1, 40), ' ');
    out << padded << value << "\n";
  };
  out << "Images\n";
  row("registered / in ground truth",
      std::to_string(metrics.num_registered_in_gt) + " / " + std::to_string(metrics.num_gt_images));
  row("registered / in model", std::to_string(metrics.num_model_registered) + " / " +
                                   std::to_string(metrics.num_model_images));
  out << "Alignment (similarity of camera centres)\n";
  if (metrics.alignment_success) {
    row("inliers", std::to_string(metrics.num_alignment_inliers) + " / " +
                       std::to_string(metrics.num_registered_in_gt));
    row("scale", general(metrics.gt_from_model.scale));
  } else {
    row("status", "failed (fewer than 3 consistent cameras)");
  }
  row("GT scene scale (mean centre radius)", general(metrics.gt_scene_scale));
  out << "Pose errors (median / mean / max)\n";
  row("camera centre (GT units)", triple(metrics.center_error, 1.0, 5));
  row("camera centre (% of scene scale)", triple(metrics.center_error_ratio, 100.0, 3));
  row("rotation (deg)", triple(metrics.rotation_error_deg, 1.0, 4));
  out << "Accuracy over all GT images (fraction below threshold, AUC)\n";
  for (const AccuracyAtThreshold& point : metrics.rotation_accuracy) {
    row("rotation <= " + general(point.threshold) + " deg",
        fixed(point.fraction, 3) + ", " + fixed(point.auc, 3));
  }
  for (const AccuracyAtThreshold& point : metrics.center_accuracy) {
    row("centre <= " + general(100 * point.threshold) + " %",
        fixed(point.fraction, 3) + ", " + fixed(point.auc, 3));
  }
  out << "Model\n";
  row("3D points", std::to_string(metrics.num_points3D));
  row("observations", std::to_string(metrics.num_observations));
  row("mean track length", fixed(metrics.mean_track_length, 3));
  std::string histogram;
  for (const auto& [length, count] : metrics.track_length_histogram) {
    histogram +=
        (histogram.empty() ? "" : ", ") + std::to_string(length) + ": " + std::to_string(count);
  }
  row("points by track length", histogram.empty() ? "-" : histogram);
  row("mean reprojection error (px)", fixed(metrics.mean_reprojection_error_px, 4));
  return out.str();
}

nlohmann::json ModelStatisticsToJson(const Reconstruction& model) {
  Reconstruction copy = model;
  nlohmann::json json;
  json["cameras"] = model.NumCameras();
  json["images"] = model.NumImages();
  json["images_registered"] = model.NumRegImages();
  json["points3D"] = model.NumPoints3D();
  json["observations"] = model.NumObservations();
  json["mean_track_length"] = model.ComputeMeanTrackLength();
  json["track_length_histogram"] = TrackLengthHistogramToJson(model.ComputeTrackLengthHistogram());
  json["mean_observations_per_image"] = model.ComputeMeanObservationsPerRegImage();
  json["mean_reprojection_error_px"] = copy.UpdatePointErrors();
  return json;
}

Reconstruction AlignToReference(const Reconstruction& model, const GroundTruth& reference,
                                EvaluationMetrics* metrics, const EvaluationOptions& options) {
  const EvaluationMetrics evaluation = EvaluateReconstruction(model, reference, options);
  if (!evaluation.alignment_success) {
    throw InputError(reference.source + ": no similarity aligns the model to it (" +
                     std::to_string(evaluation.num_registered_in_gt) +
                     " registered images in common; at least 3 that agree are needed)");
  }
  Reconstruction aligned = model;
  aligned.Transform(evaluation.gt_from_model);
  if (metrics != nullptr) *metrics = evaluation;
  return aligned;
}

}  // namespace parallax
