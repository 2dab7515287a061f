#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "parallax/estimators/solvers/solver_estimator.h"
#include "parallax/geometry/rigid3.h"

namespace parallax {

// Minimal absolute pose from three 2D-3D correspondences with a calibrated camera:
// Lambda Twist (M. Persson and K. Nordberg, "Lambda Twist: An Accurate Fast Robust
// Perspective Three Point (P3P) Solver", ECCV 2018).
//
// The depths lambda_i along the rays y_i satisfy |lambda_i y_i - lambda_j y_j|^2 = |X_i - X_j|^2,
// three quadrics in lambda. Two homogeneous combinations of them span a pencil of conics whose
// degenerate member (a root of a cubic) is a pair of lines; intersecting each line with the
// pencil gives at most four depth triples, which are polished by Gauss-Newton and aligned with
// the world triangle.
//
// `rays_in_cam` need not be unit length (a normalised image point (u, v, 1) is fine). Returns
// every cam_from_world with all three points in front of the camera (0 to 4 candidates); none
// for collinear world points, parallel rays or non-finite input.
void SolveP3P(const std::array<Eigen::Vector3d, 3>& rays_in_cam,
              const std::array<Eigen::Vector3d, 3>& points_in_world,
              std::vector<Rigid3d>* cams_from_world);

// Squared reprojection error, in normalised image coordinates (z = 1), of each 3D point under
// cam_from_world; points at or behind the camera get std::numeric_limits<double>::max().
void ComputeSquaredReprojectionErrors(const std::vector<Eigen::Vector2d>& points2D,
                                      const std::vector<Eigen::Vector3d>& points3D,
                                      const Rigid3d& cam_from_world,
                                      std::vector<double>* squared_errors);

// P3P on the first three correspondences: normalised image points (u, v) with z = 1, and
// world points.
void SolveP3PFromFirstThree(const std::vector<Eigen::Vector2d>& points2D,
                            const std::vector<Eigen::Vector3d>& points3D,
                            std::vector<Rigid3d>* cams_from_world);

// RANSAC estimator (optim/ransac.h) for calibrated absolute pose from minimal samples.
using P3PEstimator = SolverEstimator<Eigen::Vector2d, Eigen::Vector3d, Rigid3d, 3,
                                     SolveP3PFromFirstThree, ComputeSquaredReprojectionErrors>;

}  // namespace parallax
