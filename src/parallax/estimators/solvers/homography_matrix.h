#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/estimators/solvers/solver_estimator.h"
#include "parallax/geometry/epipolar.h"

namespace parallax {

// The normalized direct linear transform for x2 ~ H x1 (Hartley & Zisserman, alg. 4.2):
// Hartley normalisation of both point sets, the SVD null vector of the 2N x 9 system
// x2 x (H x1) = 0 (least squares for N > 4), de-normalisation H = T2^-1 H_n T1. Overwrites
// `models` with the one solution (unit Frobenius norm, H(2,2) >= 0 when possible) or nothing on
// degenerate input: fewer than 4 points, non-finite coordinates, three of the four points of a
// minimal sample collinear (rank below 8), or a minimal sample whose points H would map to
// both sides of the line at infinity (no physical plane does that).
void EstimateHomographyMatrix(const std::vector<Eigen::Vector2d>& points1,
                              const std::vector<Eigen::Vector2d>& points2,
                              std::vector<Eigen::Matrix3d>* models);

// LO-RANSAC estimator (optim/ransac.h), minimal with 4 points and least squares with more (also
// the local estimator); residuals are squared transfer errors ||x2 - H x1||^2 in pixels^2.
using HomographyMatrixEstimator =
    SolverEstimator<Eigen::Vector2d, Eigen::Vector2d, Eigen::Matrix3d, 4, EstimateHomographyMatrix,
                    ComputeSquaredHomographyError>;

}  // namespace parallax
