#pragma once

#include <ceres/loss_function.h>

#include <cstddef>

#include "parallax/estimators/bundle_adjustment.h"
#include "parallax/estimators/bundle_adjustment_problem.h"

namespace parallax {

// Levenberg-Marquardt on the reduced camera system, written for bundle adjustment: points
// are eliminated point by point (Schur complement), the poses and intrinsics are solved
// (SolveWithDenseSchur: all of S and a dense Cholesky; SolveWithSparseSchur: only the blocks
// of images that share points, and block-Jacobi preconditioned conjugate gradients), and
// the points are recovered by back-substitution. The steps are
// Ceres' (same damping, radius updates and termination tests), but the reduced system is
// built straight from 2x6 and 2x3 Jacobian blocks, without Ceres' generic per-residual
// machinery, which took most of the time on problems of a few hundred images or less.
// Deterministic for a given number of threads. Robust losses are applied as Ceres' corrector
// does for losses with rho'' <= 0 (all of LossFunctionType): residual and Jacobian scaled
// by sqrt(rho'). `loss` may be nullptr (squared loss).
BundleAdjustmentSummary SolveWithDenseSchur(const BundleAdjustmentOptions& options,
                                            const ceres::LossFunction* loss,
                                            BundleAdjustmentProblem* problem);

// The same steps for problems whose dense S would not fit or factor in time: memory and cost
// per iteration grow with the observations and the pairs of co-visible images, not with
// the square or cube of the number of images.
BundleAdjustmentSummary SolveWithSparseSchur(const BundleAdjustmentOptions& options,
                                             const ceres::LossFunction* loss,
                                             BundleAdjustmentProblem* problem);

// Size of the reduced camera system: 6 per variable pose, plus the free intrinsics.
size_t NumReducedCameraVariables(const BundleAdjustmentProblem& problem);

}  // namespace parallax
