#include "parallax/estimators/schur_bundle_adjuster.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>
#include <vector>

#include "parallax/estimators/schur_solver.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"

namespace parallax {
namespace schur_detail {

template <typename ReducedMatrix>
BundleAdjustmentSummary SchurSolver<ReducedMatrix>::Solve() {
  BundleAdjustmentSummary summary;
  summary.solver = kSparse ? "sparse Schur LM (conjugate gradients)" : "dense Schur LM";
  summary.num_residuals = problem_.observations.size();
  double cost = Evaluate(parameters_, /*linearize=*/true);
  summary.initial_cost = cost;
  summary.final_cost = cost;
  if (!std::isfinite(cost)) {
    summary.termination = "FAILURE: the initial cost is not finite";
    return summary;
  }
  summary.success = true;

  const auto gradient_max_norm = [&] {
    double norm = g_camera_.size() > 0 ? g_camera_.cwiseAbs().maxCoeff() : 0.0;
    for (size_t j = 0; j < g_point_.size(); ++j) {
      if (!problem_.points[j].constant) norm = std::max(norm, g_point_[j].cwiseAbs().maxCoeff());
    }
    return norm;
  };
  std::ostringstream termination;
  double radius = kInitialRadius;
  double decrease_factor = 2.0;
  int num_steps = 0;
  Eigen::VectorXd camera_step;
  std::vector<Eigen::Vector3d> point_step;
  Parameters candidate;
  if (gradient_max_norm() <= options_.gradient_tolerance) {
    termination << "CONVERGENCE: gradient tolerance reached";
  }
  while (termination.tellp() == 0) {
    if (num_steps >= options_.max_num_iterations) {
      termination << "NO_CONVERGENCE: maximum number of iterations reached";
      break;
    }
    ++num_steps;
    if (!ComputeStep(radius, &camera_step, &point_step)) {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) termination << "CONVERGENCE: minimum trust region radius reached";
      continue;
    }
    const double model_cost_change = ModelCostChange(camera_step, point_step);
    ApplyStep(camera_step, point_step, &candidate);
    const double candidate_cost = Evaluate(candidate, /*linearize=*/false);

    double step_norm_squared = camera_step.squaredNorm();
    for (const Eigen::Vector3d& step : point_step) step_norm_squared += step.squaredNorm();
    const double x_norm = ParameterNorm(parameters_);
    if (std::sqrt(step_norm_squared) <=
        options_.parameter_tolerance * (x_norm + options_.parameter_tolerance)) {
      termination << "CONVERGENCE: parameter tolerance reached";
      break;
    }
    const double cost_change = cost - candidate_cost;
    if (std::isfinite(candidate_cost) &&
        std::abs(cost_change) <= options_.function_tolerance * cost) {
      termination << "CONVERGENCE: function tolerance reached (|cost change|/cost "
                  << std::abs(cost_change) / cost << ")";
      break;
    }
    const double relative_decrease = cost_change / model_cost_change;
    if (std::isfinite(candidate_cost) && model_cost_change > 0 &&
        relative_decrease > kMinRelativeDecrease) {
      const double camera_move =
          options_.camera_step_tolerance > 0 ? LargestCameraMove(camera_step) : 0.0;
      // A swap, not a move: the next ApplyStep then copies into storage it already has.
      std::swap(parameters_, candidate);
      cost = Evaluate(parameters_, /*linearize=*/true);
      radius =
          std::min(kMaxRadius,
                   radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * relative_decrease - 1.0, 3)));
      decrease_factor = 2.0;
      if (gradient_max_norm() <= options_.gradient_tolerance) {
        termination << "CONVERGENCE: gradient tolerance reached";
      } else if (options_.camera_step_tolerance > 0 &&
                 camera_move <= options_.camera_step_tolerance) {
        termination << "CONVERGENCE: camera step tolerance reached (largest move " << camera_move
                    << ")";
      }
    } else {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) termination << "CONVERGENCE: minimum trust region radius reached";
    }
    if (options_.print_summary) {
      PARALLAX_LOG(Debug) << summary.solver << ": step " << num_steps << " cost " << cost
                          << " radius " << radius;
    }
  }
  CopyOut();
  summary.final_cost = cost;
  summary.num_iterations = num_steps;
  summary.termination = termination.str();
  summary.num_linear_iterations = num_linear_iterations_;
  return summary;
}

// Solve, for both reduced systems.
template class SchurSolver<DenseReducedMatrix>;
template class SchurSolver<BlockSparseReducedMatrix>;

}  // namespace schur_detail

using schur_detail::SchurSolver;

size_t NumReducedCameraVariables(const BundleAdjustmentProblem& problem) {
  size_t n = 0;
  for (const auto& pose : problem.poses) {
    if (pose.IsVariable()) n += 6;
  }
  for (const auto& block : problem.cameras) {
    if (block.IsVariable()) n += block.free_params.size();
  }
  return n;
}

namespace {

template <typename ReducedMatrix>
BundleAdjustmentSummary SolveWithSchur(const BundleAdjustmentOptions& options,
                                       const ceres::LossFunction* loss,
                                       BundleAdjustmentProblem* problem) {
  PARALLAX_CHECK(problem != nullptr);
  SchurSolver<ReducedMatrix> solver(options, loss, problem);
  return solver.Solve();
}

}  // namespace

BundleAdjustmentSummary SolveWithDenseSchur(const BundleAdjustmentOptions& options,
                                            const ceres::LossFunction* loss,
                                            BundleAdjustmentProblem* problem) {
  return SolveWithSchur<DenseReducedMatrix>(options, loss, problem);
}

BundleAdjustmentSummary SolveWithSparseSchur(const BundleAdjustmentOptions& options,
                                             const ceres::LossFunction* loss,
                                             BundleAdjustmentProblem* problem) {
  return SolveWithSchur<BlockSparseReducedMatrix>(options, loss, problem);
}

}  // namespace parallax
