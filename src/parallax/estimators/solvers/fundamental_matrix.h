#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/estimators/solvers/solver_estimator.h"
#include "parallax/geometry/epipolar.h"

namespace parallax {

// Fundamental matrix solvers on pixel correspondences x2^T F x1 = 0. Every solver overwrites
// `models` with all candidates (unit Frobenius norm, arbitrary sign) and leaves it empty on
// degenerate input: too few points, non-finite coordinates, coincident points, or a
// configuration whose epipolar system has a larger null space than the solver expects
// (all points collinear; all points on one plane, where F is a family and H must be used).

// Hartley normalisation (Hartley, "In defense of the eight-point algorithm", PAMI 1997):
// the similarity T that moves the centroid to the origin and scales the mean distance to it
// to sqrt(2). False when the points are non-finite or all coincide.
bool ComputeHartleyNormalization(const std::vector<Eigen::Vector2d>& points,
                                 Eigen::Matrix3d* normalization);

// The unit null vector, by SVD of the N x 9 system of rows kron(x2, x1), of N >= 8
// Hartley-normalised correspondences: M with x2n^T M x1n = 0, no rank constraint, plus the two
// normalisations (x_n = T x). False on degenerate input (see above).
bool SolveNormalizedEpipolarSystem(const std::vector<Eigen::Vector2d>& points1,
                                   const std::vector<Eigen::Vector2d>& points2,
                                   Eigen::Matrix3d* normalized_model,
                                   Eigen::Matrix3d* normalization1,
                                   Eigen::Matrix3d* normalization2);

// The 7-point algorithm (Hartley & Zisserman, sec. 11.1.2): the two-dimensional null space
// F1, F2 of the 7 x 9 system and the 1 or 3 real roots of det(a F1 + (1 - a) F2) = 0.
// N > 7 uses the two least-squares null vectors.
void EstimateFundamentalMatrixSevenPoint(const std::vector<Eigen::Vector2d>& points1,
                                         const std::vector<Eigen::Vector2d>& points2,
                                         std::vector<Eigen::Matrix3d>* models);

// The normalized 8-point algorithm (Hartley 1997; the paper's F estimator): Hartley
// normalisation, the SVD null vector of the N x 9 system (least squares for N > 8), rank 2
// by zeroing the smallest singular value, de-normalisation F = T2^T F_n T1. One model.
void EstimateFundamentalMatrixEightPoint(const std::vector<Eigen::Vector2d>& points1,
                                         const std::vector<Eigen::Vector2d>& points2,
                                         std::vector<Eigen::Matrix3d>* models);

// LO-RANSAC estimators (optim/ransac.h); residuals are squared Sampson errors in pixels^2.
using FundamentalMatrixSevenPointEstimator =
    SolverEstimator<Eigen::Vector2d, Eigen::Vector2d, Eigen::Matrix3d, 7,
                    EstimateFundamentalMatrixSevenPoint, ComputeSquaredSampsonError>;

// Least squares on all given points: the local (LO) estimator that refits F on the inliers.
using FundamentalMatrixEightPointEstimator =
    SolverEstimator<Eigen::Vector2d, Eigen::Vector2d, Eigen::Matrix3d, 8,
                    EstimateFundamentalMatrixEightPoint, ComputeSquaredSampsonError>;

}  // namespace parallax
