#include "parallax/estimators/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <map>
#include <memory>
#include <set>
#include <unordered_map>
#include <vector>

#include "parallax/estimators/cost_functions/reprojection_error.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

// Below this many variable images the reduced camera system is small enough for a dense
// Cholesky; above it the sparse one wins. Measured on a 100-view synthetic sequence (263k
// observations): dense Schur spent 2.3x less per iteration in the linear solver than sparse
// Schur with SuiteSparse, since Ceres' sparse Schur complement is built block by block.
constexpr size_t kMaxNumImagesForDenseSchur = 150;

// nullptr means the trivial (squared) loss, which Ceres evaluates fastest.
std::unique_ptr<ceres::LossFunction> CreateLossFunction(LossFunctionType type, double scale) {
  switch (type) {
    case LossFunctionType::kTrivial:
      return nullptr;
    case LossFunctionType::kHuber:
      return std::make_unique<ceres::HuberLoss>(scale);
    case LossFunctionType::kSoftLOne:
      return std::make_unique<ceres::SoftLOneLoss>(scale);
    case LossFunctionType::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(scale);
  }
  return nullptr;
}

// Dense Schur for few images; sparse Schur with the best sparse Cholesky Ceres was built with
// (Debian's 2.1 has SuiteSparse, CXSparse and Eigen), iterative Schur when it has none.
void ChooseLinearSolver(size_t num_images, ceres::Solver::Options* solver_options) {
  if (num_images < kMaxNumImagesForDenseSchur) {
    solver_options->linear_solver_type = ceres::DENSE_SCHUR;
    return;
  }
  for (const ceres::SparseLinearAlgebraLibraryType library :
       {ceres::SUITE_SPARSE, ceres::EIGEN_SPARSE, ceres::CX_SPARSE}) {
    if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(library)) {
      solver_options->linear_solver_type = ceres::SPARSE_SCHUR;
      solver_options->sparse_linear_algebra_library_type = library;
      return;
    }
  }
  solver_options->linear_solver_type = ceres::ITERATIVE_SCHUR;
  solver_options->preconditioner_type = ceres::SCHUR_JACOBI;
}

// Parameter blocks copied into one buffer, in the order they were added; the solver works on
// the copies and CopyBack writes them to the model.
class ParameterArena {
 public:
  void Add(double* block, int size) {
    if (!offsets_.emplace(block, values_.size()).second) return;  // Added already.
    blocks_.push_back({block, values_.size(), size});
    values_.resize(values_.size() + static_cast<size_t>(size));
  }
  // Copies the model's values in; no Add after this (the buffer must not move).
  void CopyIn() {
    for (const Block& block : blocks_) {
      std::copy(block.original, block.original + block.size, values_.data() + block.offset);
    }
  }
  double* operator()(double* original) { return values_.data() + offsets_.at(original); }
  void CopyBack() const {
    for (const Block& block : blocks_) {
      const double* copy = values_.data() + block.offset;
      std::copy(copy, copy + block.size, block.original);
    }
  }

 private:
  struct Block {
    double* original;
    size_t offset;
    int size;
  };
  std::vector<Block> blocks_;
  std::unordered_map<const double*, size_t> offsets_;
  std::vector<double> values_;
};

// Indices of the camera parameters that stay fixed under the refine flags.
std::vector<int> FixedCameraParamIdxs(const BundleAdjustmentOptions& options,
                                      CameraModelId model_id) {
  std::vector<int> fixed;
  if (!options.refine_focal_length) {
    for (int idx : CameraModelFocalIdxs(model_id)) fixed.push_back(idx);
  }
  if (!options.refine_principal_point) {
    for (int idx : CameraModelPrincipalPointIdxs(model_id)) fixed.push_back(idx);
  }
  if (!options.refine_extra_params) {
    for (int idx : CameraModelExtraIdxs(model_id)) fixed.push_back(idx);
  }
  std::sort(fixed.begin(), fixed.end());
  return fixed;
}

}  // namespace

void BundleAdjustmentOptions::Check() const {
  PARALLAX_CHECK_GT(loss_scale_px, 0.0);
  PARALLAX_CHECK_GE(max_num_iterations, 0);
  PARALLAX_CHECK_GE(function_tolerance, 0.0);
  PARALLAX_CHECK_GE(gradient_tolerance, 0.0);
  PARALLAX_CHECK_GE(parameter_tolerance, 0.0);
  PARALLAX_CHECK(num_threads == -1 || num_threads > 0);
}

BundleAdjustmentSummary BundleAdjust(const BundleAdjustmentOptions& options,
                                     const BundleAdjustmentConfig& config,
                                     Reconstruction* reconstruction) {
  options.Check();
  PARALLAX_CHECK(reconstruction != nullptr);
  const Timer timer;
  BundleAdjustmentSummary summary;
  if (config.images.empty()) {
    summary.termination = "empty configuration";
    return summary;
  }

  // 1. What takes part: the config's images, the points they observe, and those points'
  // other registered views (constant poses, as COLMAP does). Ordered sets throughout.
  std::set<camera_t> variable_camera_ids;
  std::vector<point3D_t> point3D_ids;
  for (const image_t image_id : config.images) {
    const Image& image = reconstruction->GetImage(image_id);
    variable_camera_ids.insert(image.camera_id);
    for (const Point2D& point2D : image.points2D) {
      if (point2D.HasPoint3D()) point3D_ids.push_back(point2D.point3D_id);
    }
  }
  std::sort(point3D_ids.begin(), point3D_ids.end());
  point3D_ids.erase(std::unique(point3D_ids.begin(), point3D_ids.end()), point3D_ids.end());
  std::set<image_t> outside_image_ids;
  std::set<camera_t> outside_camera_ids;
  for (const point3D_t point3D_id : point3D_ids) {
    for (const TrackElement& element : reconstruction->GetPoint3D(point3D_id).track.elements) {
      if (config.images.count(element.image_id) > 0) continue;
      const Image& image = reconstruction->GetImage(element.image_id);
      if (!image.registered) continue;
      outside_image_ids.insert(element.image_id);
      if (variable_camera_ids.count(image.camera_id) == 0) {
        outside_camera_ids.insert(image.camera_id);
      }
    }
  }

  // 2. Ceres orders the blocks of an elimination group by address, which sets the order of
  // the Schur complement's sums: blocks copied into one buffer in id order make the solution
  // independent of where the heap put the model (bit-identical runs with one thread).
  ParameterArena arena;
  for (const point3D_t point3D_id : point3D_ids) {
    arena.Add(reconstruction->GetPoint3D(point3D_id).xyz.data(), 3);
  }
  const auto add_pose = [&](image_t image_id) {
    Rigid3d& cam_from_world = reconstruction->GetImage(image_id).cam_from_world;
    arena.Add(cam_from_world.rotation.coeffs().data(), 4);
    arena.Add(cam_from_world.translation.data(), 3);
  };
  for (const image_t image_id : config.images) add_pose(image_id);
  for (const image_t image_id : outside_image_ids) add_pose(image_id);
  for (const auto* camera_ids : {&variable_camera_ids, &outside_camera_ids}) {
    for (const camera_t camera_id : *camera_ids) {
      std::vector<double>& params = reconstruction->GetCamera(camera_id).params;
      arena.Add(params.data(), static_cast<int>(params.size()));
    }
  }
  arena.CopyIn();

  // The problem borrows the loss and manifolds: one object each, shared by all blocks.
  const std::unique_ptr<ceres::LossFunction> loss_function =
      CreateLossFunction(options.loss_function, options.loss_scale_px);
  ceres::EigenQuaternionManifold quaternion_manifold;
  std::vector<std::unique_ptr<ceres::Manifold>> subset_manifolds;
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  const auto add_observation = [&](const Image& image, const Eigen::Vector2d& xy,
                                   Point3D& point3D) {
    Camera& camera = reconstruction->GetCamera(image.camera_id);
    Rigid3d& cam_from_world = reconstruction->GetImage(image.image_id).cam_from_world;
    problem.AddResidualBlock(CreateReprojectionErrorCostFunction(camera.model_id, xy),
                             loss_function.get(), arena(cam_from_world.rotation.coeffs().data()),
                             arena(cam_from_world.translation.data()), arena(point3D.xyz.data()),
                             arena(camera.params.data()));
  };

  // 3. Every observation in the config's images, then the rest of those points' tracks.
  for (const image_t image_id : config.images) {
    const Image& image = reconstruction->GetImage(image_id);
    for (const Point2D& point2D : image.points2D) {
      if (!point2D.HasPoint3D()) continue;
      add_observation(image, point2D.xy, reconstruction->GetPoint3D(point2D.point3D_id));
    }
  }
  for (const point3D_t point3D_id : point3D_ids) {
    Point3D& point3D = reconstruction->GetPoint3D(point3D_id);
    for (const TrackElement& element : point3D.track.elements) {
      if (outside_image_ids.count(element.image_id) == 0) continue;
      const Image& image = reconstruction->GetImage(element.image_id);
      add_observation(image, image.points2D[element.point2D_idx].xy, point3D);
    }
    if (config.constant_points.count(point3D_id) > 0) {
      problem.SetParameterBlockConstant(arena(point3D.xyz.data()));
    }
  }

  summary.num_residuals = static_cast<size_t>(problem.NumResidualBlocks());
  if (summary.num_residuals == 0) {
    summary.termination = "no observations in the configured images";
    return summary;
  }

  // 3. Poses: unit quaternions on their manifold; the gauge through constant poses and
  // constant translation coordinates.
  std::map<image_t, std::vector<int>> constant_coordinates;
  for (const auto& [image_id, coordinate] : config.constant_translation_coordinates) {
    PARALLAX_CHECK(coordinate >= 0 && coordinate < 3);
    constant_coordinates[image_id].push_back(coordinate);
  }
  for (const image_t image_id : config.images) {
    Image& image = reconstruction->GetImage(image_id);
    double* rotation = arena(image.cam_from_world.rotation.coeffs().data());
    double* translation = arena(image.cam_from_world.translation.data());
    if (!problem.HasParameterBlock(rotation)) continue;  // An image without observations.
    if (config.constant_poses.count(image_id) > 0) {
      problem.SetParameterBlockConstant(rotation);
      problem.SetParameterBlockConstant(translation);
      continue;
    }
    problem.SetManifold(rotation, &quaternion_manifold);
    const auto it = constant_coordinates.find(image_id);
    if (it == constant_coordinates.end()) continue;
    if (it->second.size() >= 3) {
      problem.SetParameterBlockConstant(translation);
    } else {
      subset_manifolds.push_back(std::make_unique<ceres::SubsetManifold>(3, it->second));
      problem.SetManifold(translation, subset_manifolds.back().get());
    }
  }
  for (const image_t image_id : outside_image_ids) {
    Image& image = reconstruction->GetImage(image_id);
    problem.SetParameterBlockConstant(arena(image.cam_from_world.rotation.coeffs().data()));
    problem.SetParameterBlockConstant(arena(image.cam_from_world.translation.data()));
  }

  // 4. Intrinsics: constant unless refined; a subset manifold holds the unrefined ones.
  for (const camera_t camera_id : variable_camera_ids) {
    Camera& camera = reconstruction->GetCamera(camera_id);
    double* params = arena(camera.params.data());
    if (!problem.HasParameterBlock(params)) continue;
    const std::vector<int> fixed = FixedCameraParamIdxs(options, camera.model_id);
    if (config.constant_cameras.count(camera_id) > 0 || fixed.size() == camera.params.size()) {
      problem.SetParameterBlockConstant(params);
    } else if (!fixed.empty()) {
      subset_manifolds.push_back(
          std::make_unique<ceres::SubsetManifold>(static_cast<int>(camera.params.size()), fixed));
      problem.SetManifold(params, subset_manifolds.back().get());
    }
  }
  for (const camera_t camera_id : outside_camera_ids) {
    problem.SetParameterBlockConstant(arena(reconstruction->GetCamera(camera_id).params.data()));
  }

  // 5. Schur ordering: points are eliminated first, poses and intrinsics form the reduced
  // camera system. Cheaper and more predictable than Ceres' automatic independent set.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (const point3D_t point3D_id : point3D_ids) {
    ordering->AddElementToGroup(arena(reconstruction->GetPoint3D(point3D_id).xyz.data()), 0);
  }
  auto add_image_blocks = [&](image_t image_id) {
    Image& image = reconstruction->GetImage(image_id);
    double* rotation = arena(image.cam_from_world.rotation.coeffs().data());
    if (!problem.HasParameterBlock(rotation)) return;
    ordering->AddElementToGroup(rotation, 1);
    ordering->AddElementToGroup(arena(image.cam_from_world.translation.data()), 1);
  };
  for (const image_t image_id : config.images) add_image_blocks(image_id);
  for (const image_t image_id : outside_image_ids) add_image_blocks(image_id);
  for (const auto* camera_ids : {&variable_camera_ids, &outside_camera_ids}) {
    for (const camera_t camera_id : *camera_ids) {
      double* params = arena(reconstruction->GetCamera(camera_id).params.data());
      if (problem.HasParameterBlock(params)) ordering->AddElementToGroup(params, 1);
    }
  }

  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  ChooseLinearSolver(config.images.size(), &solver_options);
  solver_options.linear_solver_ordering = ordering;
  solver_options.max_num_iterations = options.max_num_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.gradient_tolerance = options.gradient_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  // Ceres warns on stderr (through glog) when asked for more threads than cores.
  solver_options.num_threads =
      std::min(EffectiveNumThreads(options.num_threads), EffectiveNumThreads(-1));
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver_options, &problem, &ceres_summary);
  arena.CopyBack();

  // The manifold keeps quaternions on the unit sphere only up to round-off.
  for (const image_t image_id : config.images) {
    reconstruction->GetImage(image_id).cam_from_world.rotation.normalize();
  }

  if (options.print_summary) {
    PARALLAX_LOG(Debug) << ceres_summary.FullReport();
  }
  summary.success = ceres_summary.IsSolutionUsable();
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.num_iterations =
      static_cast<int>(ceres_summary.num_successful_steps + ceres_summary.num_unsuccessful_steps);
  summary.termination =
      std::string(ceres::TerminationTypeToString(ceres_summary.termination_type)) + ": " +
      ceres_summary.message;
  summary.seconds = timer.ElapsedSeconds();
  return summary;
}

}  // namespace parallax
