#pragma once

#include <array>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "parallax/estimators/absolute_pose.h"
#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/scene/reconstruction.h"
#include "parallax/sfm/mapper_input.h"
#include "parallax/sfm/observation_filter.h"
#include "parallax/sfm/track_triangulation.h"
#include "parallax/util/progress.h"

namespace parallax {

struct IncrementalMapperOptions {
  // Initial pair.
  int init_min_num_inliers = 100;  // Triangulated points the initial pair must give.
  double init_min_triangulation_angle_deg =
      16.0;                   // Median triangulation angle of the initial pair.
  int init_max_trials = 200;  // Candidate pairs examined per angle threshold.
  // Registration of the next image.
  AbsolutePoseEstimationOptions absolute_pose;
  AbsolutePoseRefinementOptions absolute_pose_refinement;
  int absolute_pose_min_num_inliers = 30;  // PnP inliers an image needs to be registered.
  double absolute_pose_min_inlier_ratio = 0.25;
  int max_registration_trials = 2;  // Failed attempts before an image is given up.
  // Triangulation and filtering.
  TrackTriangulationOptions triangulation;
  ObservationFilterOptions filter;
  // Bundle adjustment: one options struct per use, each used as it is. The mapper chooses
  // only the images and what stays constant: every camera in local adjustments, cameras with
  // a prior focal length (and all until three images are registered) in global ones. Squared
  // loss while the model grows and a robust finish is faster and more accurate than either
  // loss throughout (docs/defaults.md, "Squared loss while growing, a robust finish").
  BundleAdjustmentOptions local_ba = [] {  // Around each new image; intrinsics fixed.
    BundleAdjustmentOptions options;
    options.loss_function = LossFunctionType::kTrivial;
    options.max_num_iterations = 25;
    // A step that lowers the cost by less than 3e-5 of it ends the adjustment: the last one
    // or two steps of 1e-6 changed no model's errors, and the final adjustment settles the
    // points anyway (docs/defaults.md, "Local adjustments stop sooner").
    options.function_tolerance = 3e-5;
    return options;
  }();
  BundleAdjustmentOptions global_ba = [] {  // Whenever the model has grown enough.
    BundleAdjustmentOptions options;
    options.loss_function = LossFunctionType::kTrivial;
    options.max_num_iterations = 50;
    options.refine_focal_length = true;
    options.refine_extra_params = true;
    return options;
  }();
  BundleAdjustmentOptions final_ba = [] {  // The last one; iterations per refinement round.
    BundleAdjustmentOptions options;
    options.loss_function = LossFunctionType::kCauchy;
    options.max_num_iterations = 10;
    // Each round stops once no camera moves by more than 3e-5 (radians, or of the centres'
    // spread): the points' creep under Cauchy left the cameras where they were (docs/defaults.md,
    // "A robust finish that stops when the cameras do").
    options.camera_step_tolerance = 3e-5;
    options.refine_focal_length = true;
    options.refine_extra_params = true;
    return options;
  }();
  // The three, for settings that apply to every adjustment (threads, solver).
  std::array<BundleAdjustmentOptions*, 3> BundleAdjustments() {
    return {&local_ba, &global_ba, &final_ba};
  }
  int local_ba_num_images = 6;  // Images optimised around each new image.
  // Global BA when the model grew by this factor in images or in points: each doubling. The
  // local adjustments keep new images in place meanwhile, and the final adjustment sets the
  // errors: 1.25 and COLMAP's 1.1 give the same errors on templeRing and the 300- and
  // 1,000-view surveys for more global adjustments (docs/defaults.md, "Global bundle adjustment").
  double global_ba_images_ratio = 2.0;
  double global_ba_points_ratio = 2.0;
  int global_ba_max_refinements = 3;  // BA + filter + complete rounds of the final BA.
  // The final adjustment also frees the principal point of cameras without a prior when each
  // is seen by at least this many images (0: never), and keeps it only if it stays near the
  // image centre: a centred guess that is off is otherwise absorbed by focal length and
  // distortion (docs/defaults.md, "Principal point freed at the end").
  int final_principal_point_min_images = 10;
  // Models.
  int min_model_size = 3;       // Smaller models are discarded.
  bool multiple_models = true;  // Start a new model when the current one is stuck.
  int max_num_models = 20;
  void Check() const;
};

// What happened to each image, for summary.json and the log.
struct MapperImageReport {
  int model_index = -1;  // Index into the returned models; -1 when not registered.
  std::string reason;    // Why it ended unregistered (empty when registered).
  int num_registration_trials = 0;
  size_t num_visible_points = 0;  // 2D-3D correspondences at the last attempt.
  size_t num_pnp_inliers = 0;
  // Mean reprojection error right after registration and triangulation (before any bundle
  // adjustment that includes the image) and in the final model.
  double error_before_ba_px = std::numeric_limits<double>::quiet_NaN();
  double error_after_ba_px = std::numeric_limits<double>::quiet_NaN();
};

// Wall time of the mapper's phases, each summed over the run. The rest of `seconds` is
// starting models, bookkeeping and the final reports.
struct MapperPhaseSeconds {
  double next_view = 0;        // Ranking the unregistered images by visibility.
  double registration = 0;     // 2D-3D correspondences, PnP RANSAC and pose refinement.
  double triangulation = 0;    // New points in each registered image.
  double local_ba = 0;         // Local bundle adjustments (the solver).
  double global_ba = 0;        // Global bundle adjustments (the solver).
  double filtering = 0;        // Observations and points that stopped fitting.
  double completion = 0;       // Tracks completed and points merged.
  double retriangulation = 0;  // Under-reconstructed pairs, before each global adjustment.

  // Each phase with its name (summary.json's key, and the log's), in the order above.
  std::vector<std::pair<const char*, double>> Named() const;
  double Total() const;
};

struct MapperSummary {
  std::map<image_t, MapperImageReport> images;
  size_t num_local_ba = 0;
  size_t num_global_ba = 0;
  MapperPhaseSeconds phase_seconds;
  // The bundle-adjustment solver's time, local and global.
  double BaSeconds() const { return phase_seconds.local_ba + phase_seconds.global_ba; }
  double seconds = 0;
  std::string failure;  // Set when no model could be started.
};

// The paper's Algorithm 1 (and COLMAP's incremental mapper): initialise from the best pair,
// then repeatedly register the image that sees the most (and best spread) triangulated
// points by PnP, triangulate the tracks it completes, adjust locally, and globally when the
// model has grown; filter and re-triangulate. When no image can be added, a new model is
// started from the remaining images. Models come back largest first.
class IncrementalMapper {
 public:
  IncrementalMapper(const IncrementalMapperOptions& options, const MapperInput& input);
  // Maps from scratch.
  std::vector<Reconstruction> Reconstruct(MapperSummary* summary);
  // Maps starting from the registered images of `seed` (ids of this input; poses and
  // intrinsics as given, points triangulated anew from the tracks), as the last stage of
  // partitioned mapping does with its merged clusters: the first model grows from the seed,
  // further models start from what is left as usual.
  std::vector<Reconstruction> Extend(const Reconstruction& seed, MapperSummary* summary);
  // Counts registrations on `progress` (shared by mappers running side by side) instead of
  // a "mapping" line of the mapper's own.
  void SetProgress(ProgressReporter* progress) { progress_ = progress; }

 private:
  class ModelBuilder;
  std::vector<Reconstruction> Run(const Reconstruction* seed, MapperSummary* summary);
  const IncrementalMapperOptions options_;
  const MapperInput& input_;
  ProgressReporter* progress_ = nullptr;
};

// A copy holding only the registered images, the cameras they use, and the points.
Reconstruction ExtractRegisteredModel(const Reconstruction& reconstruction);

}  // namespace parallax
