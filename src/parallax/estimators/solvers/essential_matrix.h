#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/estimators/solvers/solver_estimator.h"
#include "parallax/geometry/epipolar.h"

namespace parallax {

// Essential matrix solvers on normalised image coordinates (z = 1, i.e. K^-1 applied),
// x2^T E x1 = 0. Every solver overwrites `models` with all candidates (unit Frobenius norm,
// arbitrary sign) and leaves it empty on degenerate input (too few points, non-finite
// coordinates, an epipolar system of too low rank).

// The 5-point algorithm (Nistér, "An efficient solution to the five-point relative pose
// problem", PAMI 2004): E = x X + y Y + z Z + W over the null space of the 5 x 9 epipolar
// system; det(E) = 0 and 2 E E^T E - tr(E E^T) E = 0 give 10 cubics in (x, y, z); Gauss-Jordan
// elimination in Nistér's monomial order leaves three equations linear in (x, y, 1) whose
// 3 x 3 polynomial determinant is of degree 10 in z. Its real roots (Sturm sequences, then
// Newton) give the (up to 10) solutions. N > 5 uses the four least-squares null vectors.
void EstimateEssentialMatrixFivePoint(const std::vector<Eigen::Vector2d>& points1,
                                      const std::vector<Eigen::Vector2d>& points2,
                                      std::vector<Eigen::Matrix3d>* models);

// The normalized 8-point algorithm on N >= 8 points, then the projection onto the essential
// manifold (singular values (1, 1, 0); Hartley & Zisserman, result 9.18). One model.
void EstimateEssentialMatrixEightPoint(const std::vector<Eigen::Vector2d>& points1,
                                       const std::vector<Eigen::Vector2d>& points2,
                                       std::vector<Eigen::Matrix3d>* models);

// The same two solvers on unit rays (Camera::CamRayFromImg), for lenses whose rays reach
// behind the image plane (fisheyes wider than 180 degrees, EQUIRECTANGULAR): b2^T E b1 = 0
// holds for rays in any direction, where normalised coordinates do not exist.
void EstimateEssentialMatrixFivePointFromRays(const std::vector<Eigen::Vector3d>& rays1,
                                              const std::vector<Eigen::Vector3d>& rays2,
                                              std::vector<Eigen::Matrix3d>* models);
void EstimateEssentialMatrixEightPointFromRays(const std::vector<Eigen::Vector3d>& rays1,
                                               const std::vector<Eigen::Vector3d>& rays2,
                                               std::vector<Eigen::Matrix3d>* models);

// LO-RANSAC estimators (optim/ransac.h); residuals are squared Sampson errors in normalised
// units (a pixel threshold divided by the focal length).
using EssentialMatrixFivePointEstimator =
    SolverEstimator<Eigen::Vector2d, Eigen::Vector2d, Eigen::Matrix3d, 5,
                    EstimateEssentialMatrixFivePoint, ComputeSquaredSampsonError>;

// Least squares on all given points: the local (LO) estimator that refits E on the inliers.
using EssentialMatrixEightPointEstimator =
    SolverEstimator<Eigen::Vector2d, Eigen::Vector2d, Eigen::Matrix3d, 8,
                    EstimateEssentialMatrixEightPoint, ComputeSquaredSampsonError>;

// On unit rays; residuals are squared Sampson errors on the sphere (radians, to first order).
using EssentialMatrixFivePointRayEstimator =
    SolverEstimator<Eigen::Vector3d, Eigen::Vector3d, Eigen::Matrix3d, 5,
                    EstimateEssentialMatrixFivePointFromRays, ComputeSquaredSphericalSampsonError>;
using EssentialMatrixEightPointRayEstimator =
    SolverEstimator<Eigen::Vector3d, Eigen::Vector3d, Eigen::Matrix3d, 8,
                    EstimateEssentialMatrixEightPointFromRays, ComputeSquaredSphericalSampsonError>;

}  // namespace parallax
