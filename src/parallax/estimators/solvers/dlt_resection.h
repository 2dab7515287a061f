#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/estimators/solvers/solver_estimator.h"
#include "parallax/math/eigen_types.h"

namespace parallax {

// Uncalibrated camera resection by the Direct Linear Transform (Hartley and Zisserman,
// "Multiple View Geometry", 2nd ed., algorithm 7.1): both point sets are normalised (centroid
// at the origin, mean distance sqrt(2) resp. sqrt(3)), the 2N x 12 system x_i ~ P X_i is solved
// by SVD, and P is denormalised.
//
// `points2D` in pixels. Returns one P = K [R | t] scaled so that the third row of its left 3x3
// block has unit norm and det of that block is positive, or none for fewer than 6 points,
// (near-)coplanar or collinear 3D points, a rank-deficient system or non-finite input.
void SolveDLTResection(const std::vector<Eigen::Vector2d>& points2D,
                       const std::vector<Eigen::Vector3d>& points3D,
                       std::vector<Matrix3x4d>* proj_matrices);

// Splits P = [H | h] = s K [R | t] (any scale s, sign included) into K upper-triangular with
// positive diagonal and K(2, 2) = 1, R a rotation (det +1) and t. Through the QR factorisation
// H^-1 = Q U: H = U^-1 Q^T, so K ~ U^-1 and R = Q^T, with the diagonal signs moved from K to R
// and the overall sign of P chosen so that det R = +1. False for a singular or non-finite H.
bool DecomposeProjectionMatrix(const Matrix3x4d& proj_matrix, Eigen::Matrix3d* K,
                               Eigen::Matrix3d* R, Eigen::Vector3d* t);

// Squared reprojection error in pixels of each point under P; points at or behind the camera
// (P normalised as SolveDLTResection returns it) get std::numeric_limits<double>::max().
void ComputeSquaredProjectionErrors(const std::vector<Eigen::Vector2d>& points2D,
                                    const std::vector<Eigen::Vector3d>& points3D,
                                    const Matrix3x4d& proj_matrix,
                                    std::vector<double>* squared_errors);

// RANSAC estimator (optim/ransac.h) for the projection matrix of an uncalibrated camera.
// X: pixels; Y: world points.
using DLTResectionEstimator = SolverEstimator<Eigen::Vector2d, Eigen::Vector3d, Matrix3x4d, 6,
                                              SolveDLTResection, ComputeSquaredProjectionErrors>;

}  // namespace parallax
