#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "parallax/estimators/similarity_transform.h"
#include "parallax/geometry/sim3.h"
#include "parallax/report/ground_truth.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

struct EvaluationOptions {
  // Inlier distance of the similarity alignment of camera centres, as a fraction of the GT
  // scene scale (mean distance of the GT centres from their centroid).
  double alignment_max_error_ratio = 0.05;
  // When positive, the inlier distance in the reference's units instead (metres for GPS:
  // the ratio would reject honest GPS noise on a survey whose spread is small beside it).
  double alignment_max_error = 0;
  // The alignment's RANSAC (its max_error is set from the two above).
  RansacOptions alignment_ransac = Sim3dRansacOptions(1.0);
  // Thresholds (degrees) of the rotation accuracy curve.
  std::vector<double> rotation_thresholds_deg = {1.0, 2.0, 5.0};
  // Thresholds (fractions of the GT scene scale) of the relative centre accuracy curve.
  std::vector<double> center_thresholds_ratio = {0.01, 0.02, 0.05};
  void Check() const;
};

// One ground-truth view and how the model did on it.
struct ImageEvaluation {
  std::string name;
  // Id in the model, kInvalidImageId when the model has no image of that name.
  image_t image_id = kInvalidImageId;
  bool registered = false;
  // True when the view counted as an inlier of the alignment.
  bool alignment_inlier = false;
  // Errors after alignment (only meaningful when registered and the alignment succeeded).
  double center_error = 0;        // GT units
  double center_error_ratio = 0;  // center_error / gt_scene_scale
  double rotation_error_deg = 0;
};

// One point of an accuracy curve: the fraction of GT images whose error is at most the
// threshold (unregistered images count as failures), and the normalised area under the
// cumulative error curve from 0 to the threshold, i.e. the mean over GT images of
// max(0, 1 - error / threshold) (1 means every image is exact).
struct AccuracyAtThreshold {
  double threshold = 0;
  double fraction = 0;
  double auc = 0;
};

// Basic statistics of a list of errors (all zero when empty).
struct ErrorStatistics {
  size_t count = 0;
  double median = 0;
  double mean = 0;
  double max = 0;
};

struct EvaluationMetrics {
  // Image counts: in the GT; in the model; registered in the model and present in the GT.
  size_t num_gt_images = 0;
  size_t num_model_images = 0;
  size_t num_model_registered = 0;
  size_t num_registered_in_gt = 0;

  // Similarity gt_from_model fitted robustly to the camera centres.
  bool alignment_success = false;
  Sim3d gt_from_model;
  size_t num_alignment_inliers = 0;
  // Mean distance of the GT camera centres from their centroid (the unit of relative errors).
  double gt_scene_scale = 0;

  // Over registered images present in the GT, after alignment.
  ErrorStatistics center_error;        // GT units
  ErrorStatistics center_error_ratio;  // fraction of gt_scene_scale
  ErrorStatistics rotation_error_deg;

  // Over all GT images (unregistered ones fail every threshold).
  std::vector<AccuracyAtThreshold> rotation_accuracy;
  std::vector<AccuracyAtThreshold> center_accuracy;

  // Model statistics independent of the GT.
  size_t num_points3D = 0;
  size_t num_observations = 0;
  double mean_track_length = 0;
  std::map<size_t, size_t> track_length_histogram;  // Points by images per point.
  double mean_reprojection_error_px = 0;

  // One entry per GT image, in GT order.
  std::vector<ImageEvaluation> images;
};

// Compares a reconstruction with ground-truth poses. Images are matched by name: exactly,
// else by file name without folder, else by name without folder and extension.
// [{"length": 2, "points": N}, ...]: points by track length, shortest first.
nlohmann::json TrackLengthHistogramToJson(const std::map<size_t, size_t>& histogram);

EvaluationMetrics EvaluateReconstruction(const Reconstruction& model, const GroundTruth& gt,
                                         const EvaluationOptions& options = {});

nlohmann::json MetricsToJson(const EvaluationMetrics& metrics);

// The ground-truth-free numbers of any model (`parallax model analyze`, Python's summary()):
// cameras, images, registered images, points, observations, mean track length and its
// histogram, mean observations per registered image, mean reprojection error (recomputed).
nlohmann::json ModelStatisticsToJson(const Reconstruction& model);

// `model` moved into the frame of `reference` (a ground truth, or another model read as one;
// images matched by name) by the similarity EvaluateReconstruction fits to the camera
// centres (`parallax model align`). Throws InputError naming the reference when none could be
// fitted. `metrics`, when not null, gets that evaluation.
Reconstruction AlignToReference(const Reconstruction& model, const GroundTruth& reference,
                                EvaluationMetrics* metrics = nullptr,
                                const EvaluationOptions& options = {});
// A readable multi-line table for the terminal.
std::string MetricsToText(const EvaluationMetrics& metrics);

}  // namespace parallax
