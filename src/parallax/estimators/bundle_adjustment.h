#pragma once

#include <optional>
#include <set>
#include <string>
#include <unordered_set>

#include "parallax/estimators/reduced_camera_matrix.h"
#include "parallax/scene/reconstruction.h"
#include "parallax/util/types.h"

namespace parallax {

enum class LossFunctionType { kTrivial, kHuber, kSoftLOne, kCauchy };

// Which solver minimises: Parallax's Schur LM with a dense or a block-sparse reduced camera
// system (schur_bundle_adjuster.h), or Ceres (kCeres: dense or sparse Schur by size;
// kCeresIterative: its conjugate gradients on the implicit Schur complement). All take LM
// steps; kAuto picks the dense Schur LM while the reduced system fits
// `max_dense_schur_variables`, the sparse one above.
enum class BundleAdjustmentSolver { kAuto, kDenseSchur, kSparseSchur, kCeres, kCeresIterative };

// "auto", "dense-schur", "sparse-schur", "ceres", "ceres-iterative"; nullopt for anything else.
std::optional<BundleAdjustmentSolver> BundleAdjustmentSolverFromName(const std::string& name);
// "squared", "huber", "soft-l1" or "cauchy" (the command line's names), both ways.
std::optional<LossFunctionType> LossFunctionTypeFromName(const std::string& name);
const char* LossFunctionName(LossFunctionType type);

struct BundleAdjustmentOptions {
  BundleAdjustmentSolver solver = BundleAdjustmentSolver::kAuto;
  // 6 per variable pose plus the free intrinsics: 1500 is 250 images, where the dense reduced
  // matrix (n^2 doubles) stops paying (docs/defaults.md, "Dense Schur up to 250 images").
  int max_dense_schur_variables = 1500;
  // The sparse Schur LM's linear solve.
  ConjugateGradientOptions conjugate_gradient;
  LossFunctionType loss_function = LossFunctionType::kCauchy;
  double loss_scale_px = 1.0;  // Robust loss scale on reprojection error, pixels.
  bool refine_focal_length = false;
  bool refine_principal_point = false;
  bool refine_extra_params = false;
  int max_num_iterations = 100;
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  // Parallax's Schur LM (Ceres ignores it) also stops once an accepted step moves no camera
  // by more than this (0: never): rotations in radians, translations over the spread of the
  // camera centres, free intrinsics relative to their value (or to 1 when smaller). Under a
  // robust loss the points keep creeping long after the cameras have settled (docs/defaults.md,
  // "A robust finish that stops when the cameras do").
  double camera_step_tolerance = 0;
  int num_threads = -1;        // -1: all cores.
  bool print_summary = false;  // Ceres' report to the log at debug level.
  void Check() const;
};

// Which images and points take part and what is held constant. Points observed by the
// images are included automatically; their observations in registered images outside the
// config are added with those poses constant (COLMAP's behaviour), so they fix the gauge.
struct BundleAdjustmentConfig {
  std::set<image_t> images;
  std::set<image_t> constant_poses;
  // Images whose translation is fixed in one coordinate (gauge): image id and index 0..2.
  std::set<std::pair<image_t, int>> constant_translation_coordinates;
  std::set<point3D_t> constant_points;
  std::set<camera_t> constant_cameras;

  void AddImage(image_t image_id) { images.insert(image_id); }
  void SetConstantPose(image_t image_id) { constant_poses.insert(image_id); }
};

// Every registered image of `reconstruction`, the gauge fixed as COLMAP's bundle_adjuster
// fixes it: the first image's pose and the largest coordinate of the second's translation
// (the scale).
// With `fix_poses`, every pose is constant: only points (and free intrinsics) move.
BundleAdjustmentConfig WholeModelConfig(const Reconstruction& reconstruction, bool fix_poses);

struct BundleAdjustmentSummary {
  bool success = false;
  double initial_cost = 0;  // Ceres cost (0.5 sum of squared robustified residuals).
  double final_cost = 0;
  int num_iterations = 0;
  size_t num_residuals = 0;
  double seconds = 0;
  std::string termination;  // Termination type and message (Ceres' wording).
  std::string solver;       // Which solver ran, e.g. "dense Schur LM" or "Ceres SPARSE_SCHUR".
  int num_linear_iterations = 0;  // Conjugate-gradient iterations of the sparse Schur LM.
};

// Minimises reprojection error over poses, points and (optionally) intrinsics:
// Levenberg-Marquardt trust region on the Schur complement (points eliminated), robust loss,
// multi-threaded. See BundleAdjustmentSolver for which solver runs.
BundleAdjustmentSummary BundleAdjust(const BundleAdjustmentOptions& options,
                                     const BundleAdjustmentConfig& config,
                                     Reconstruction* reconstruction);

}  // namespace parallax
