#pragma once

#include <array>
#include <cstdint>

#include "parallax/estimators/absolute_pose.h"
#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/sfm/model_joiner.h"
#include "parallax/sfm/observation_filter.h"
#include "parallax/sfm/track_triangulation.h"

namespace parallax {

struct IncrementalMapperOptions {
  // The mapper's one seed: registration's PnP RANSAC draws from a seed derived from it per
  // image and attempt, so the same seed registers the same way whatever came before.
  uint64_t seed = 0;
  // Initial pair. When no pair meets the two thresholds they are halved in turns, down to
  // their floors (InitThresholdSchedule): a walk facing forwards has small angles everywhere.
  int init_min_num_inliers = 100;  // Triangulated points the initial pair must give.
  double init_min_triangulation_angle_deg =
      16.0;                             // Median triangulation angle of the initial pair.
  int init_min_num_inliers_floor = 25;  // The relaxation goes no lower.
  double init_min_triangulation_angle_floor_deg = 2.0;
  int init_max_trials = 200;  // Pairs adjusted per step of the relaxation (that met it).
  // Registration of the next image.
  AbsolutePoseEstimationOptions absolute_pose;
  AbsolutePoseRefinementOptions absolute_pose_refinement;
  int absolute_pose_min_num_inliers = 30;  // PnP inliers an image needs to be registered.
  double absolute_pose_min_inlier_ratio = 0.25;
  int max_registration_trials = 2;  // Failed attempts before an image is given up.
  // The last pass, when nothing more registers: every image left is tried again with these
  // lower bars (each attempt counted in its report), then the model is finished.
  int relaxed_absolute_pose_min_num_inliers = 15;
  double relaxed_absolute_pose_min_inlier_ratio = 0.15;
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
  // Join the models by the tracks they share, then register what is left against the whole
  // and adjust it (JoinModels): fewer, larger models.
  bool join_models = true;
  ModelJoinerOptions join;
  void Check() const;
};

}  // namespace parallax
