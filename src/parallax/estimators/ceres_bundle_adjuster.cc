#include "parallax/estimators/ceres_bundle_adjuster.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <memory>
#include <unordered_map>
#include <vector>

#include "parallax/estimators/cost_functions/reprojection_error.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

// Below this many variable images the reduced camera system is small enough for a dense
// Cholesky, which beats Ceres' block-by-block sparse Schur complement (docs/defaults.md,
// "Dense Schur up to 250 images").
constexpr size_t kMaxNumImagesForDenseSchur = 150;

// Dense Schur for few images; sparse Schur with the best sparse Cholesky Ceres was built with
// (Debian's 2.1 has SuiteSparse, CXSparse and Eigen); conjugate gradients on the implicit
// Schur complement with the Schur-Jacobi preconditioner when asked, or when Ceres has no
// sparse Cholesky.
void ChooseLinearSolver(const BundleAdjustmentOptions& options, size_t num_images,
                        ceres::Solver::Options* solver_options) {
  const bool iterative = options.solver == BundleAdjustmentSolver::kCeresIterative;
  if (!iterative && num_images < kMaxNumImagesForDenseSchur) {
    solver_options->linear_solver_type = ceres::DENSE_SCHUR;
    return;
  }
  if (!iterative) {
    for (const ceres::SparseLinearAlgebraLibraryType library :
         {ceres::SUITE_SPARSE, ceres::EIGEN_SPARSE, ceres::CX_SPARSE}) {
      if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(library)) {
        solver_options->linear_solver_type = ceres::SPARSE_SCHUR;
        solver_options->sparse_linear_algebra_library_type = library;
        return;
      }
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

}  // namespace

BundleAdjustmentSummary SolveWithCeres(const BundleAdjustmentOptions& options,
                                       ceres::LossFunction* loss,
                                       BundleAdjustmentProblem* problem) {
  BundleAdjustmentSummary summary;

  // Ceres orders the blocks of an elimination group by address, which sets the order of the
  // Schur complement's sums: blocks copied into one buffer in problem order make the solution
  // independent of where the heap put the model (bit-identical runs with one thread).
  ParameterArena arena;
  for (const auto& point : problem->points) arena.Add(point.xyz->data(), 3);
  for (const auto& pose : problem->poses) {
    arena.Add(pose.cam_from_world->rotation.coeffs().data(), 4);
    arena.Add(pose.cam_from_world->translation.data(), 3);
  }
  for (const auto& block : problem->cameras) {
    arena.Add(block.camera->params.data(), static_cast<int>(block.camera->params.size()));
  }
  arena.CopyIn();
  const auto rotation_of = [&](const BundleAdjustmentProblem::Pose& pose) {
    return arena(pose.cam_from_world->rotation.coeffs().data());
  };
  const auto translation_of = [&](const BundleAdjustmentProblem::Pose& pose) {
    return arena(pose.cam_from_world->translation.data());
  };

  // The problem borrows the loss and manifolds: one object each, shared by all blocks.
  ceres::EigenQuaternionManifold quaternion_manifold;
  std::vector<std::unique_ptr<ceres::Manifold>> subset_manifolds;
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  for (const auto& observation : problem->observations) {
    const auto& pose = problem->poses[observation.pose];
    Camera& camera = *problem->cameras[observation.camera].camera;
    ceres_problem.AddResidualBlock(
        CreateReprojectionErrorCostFunction(camera.model_id, observation.xy), loss,
        rotation_of(pose), translation_of(pose),
        arena(problem->points[observation.point].xyz->data()), arena(camera.params.data()));
  }
  summary.num_residuals = static_cast<size_t>(ceres_problem.NumResidualBlocks());

  // Points, then poses: unit quaternions on their manifold, the gauge through constant poses
  // and constant translation coordinates; then intrinsics, a subset manifold holding the
  // unrefined ones.
  for (const auto& point : problem->points) {
    if (point.constant) ceres_problem.SetParameterBlockConstant(arena(point.xyz->data()));
  }
  for (const auto& pose : problem->poses) {
    if (pose.num_observations == 0) continue;
    if (pose.constant) {
      ceres_problem.SetParameterBlockConstant(rotation_of(pose));
      ceres_problem.SetParameterBlockConstant(translation_of(pose));
      continue;
    }
    ceres_problem.SetManifold(rotation_of(pose), &quaternion_manifold);
    std::vector<int> constant_coordinates;
    for (int c = 0; c < 3; ++c) {
      if (pose.constant_translation[c]) constant_coordinates.push_back(c);
    }
    if (constant_coordinates.size() == 3) {
      ceres_problem.SetParameterBlockConstant(translation_of(pose));
    } else if (!constant_coordinates.empty()) {
      subset_manifolds.push_back(std::make_unique<ceres::SubsetManifold>(3, constant_coordinates));
      ceres_problem.SetManifold(translation_of(pose), subset_manifolds.back().get());
    }
  }
  for (const auto& block : problem->cameras) {
    if (block.num_observations == 0) continue;
    double* params = arena(block.camera->params.data());
    const int num_params = static_cast<int>(block.camera->params.size());
    if (block.free_params.empty()) {
      ceres_problem.SetParameterBlockConstant(params);
    } else if (static_cast<int>(block.free_params.size()) < num_params) {
      std::vector<int> fixed;
      for (int k = 0; k < num_params; ++k) {
        if (!std::binary_search(block.free_params.begin(), block.free_params.end(), k)) {
          fixed.push_back(k);
        }
      }
      subset_manifolds.push_back(std::make_unique<ceres::SubsetManifold>(num_params, fixed));
      ceres_problem.SetManifold(params, subset_manifolds.back().get());
    }
  }

  // Schur ordering: points are eliminated first, poses and intrinsics form the reduced
  // camera system. Cheaper and more predictable than Ceres' automatic independent set.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (const auto& point : problem->points) {
    ordering->AddElementToGroup(arena(point.xyz->data()), 0);
  }
  for (const auto& pose : problem->poses) {
    if (pose.num_observations == 0) continue;
    ordering->AddElementToGroup(rotation_of(pose), 1);
    ordering->AddElementToGroup(translation_of(pose), 1);
  }
  for (const auto& block : problem->cameras) {
    if (block.num_observations > 0)
      ordering->AddElementToGroup(arena(block.camera->params.data()), 1);
  }

  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  ChooseLinearSolver(options, problem->num_config_images, &solver_options);
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
  ceres::Solve(solver_options, &ceres_problem, &ceres_summary);
  arena.CopyBack();

  if (options.print_summary) {
    PARALLAX_LOG(Debug) << ceres_summary.FullReport();
  }
  summary.solver =
      std::string("Ceres ") + ceres::LinearSolverTypeToString(solver_options.linear_solver_type);
  summary.success = ceres_summary.IsSolutionUsable();
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.num_iterations =
      static_cast<int>(ceres_summary.num_successful_steps + ceres_summary.num_unsuccessful_steps);
  summary.termination =
      std::string(ceres::TerminationTypeToString(ceres_summary.termination_type)) + ": " +
      ceres_summary.message;
  return summary;
}

}  // namespace parallax
