#pragma once

#include <Eigen/Core>
#include <vector>

#include "parallax/estimators/solvers/p3p.h"
#include "parallax/estimators/solvers/solver_estimator.h"
#include "parallax/geometry/rigid3.h"

namespace parallax {

// Calibrated absolute pose from N >= 4 2D-3D correspondences: EPnP (V. Lepetit, F.
// Moreno-Noguer and P. Fua, "EPnP: An Accurate O(n) Solution to the PnP Problem", IJCV 2009).
//
// Every world point is a barycentric combination of four control points (three when the
// points are planar) placed on the principal axes of the point cloud; the camera-frame control
// points lie in the null space of a 2N x 12 (2N x 9) linear system. They are found as
// beta-weighted sums of the 1 to 4 smallest right singular vectors, the betas from the
// preserved control-point distances (linearised for N = 1..4 kernels, then Gauss-Newton),
// and the candidate with the lowest reprojection error wins. Its pose is then polished by
// Levenberg-Marquardt on the reprojection error, so that it serves as the least-squares step of
// LO-RANSAC. With only 4 or 5 points (a 4- or 2-dimensional null space, where the linearised
// betas can fall into a wrong basin) the P3P solutions of every triplet compete as well.
//
// `points2D` are normalised image points (z = 1). Returns one cam_from_world, or none for fewer
// than 4 points, collinear or non-finite points.
void SolveEPnP(const std::vector<Eigen::Vector2d>& points2D,
               const std::vector<Eigen::Vector3d>& points3D, std::vector<Rigid3d>* cams_from_world);

// Levenberg-Marquardt on the squared reprojection error in normalised coordinates (all points
// weighted equally, points behind the camera skipped); a step is taken only when it lowers
// the error. Returns false, leaving the pose, when fewer than 3 points lie in front.
bool RefineAbsolutePoseLeastSquares(const std::vector<Eigen::Vector2d>& points2D,
                                    const std::vector<Eigen::Vector3d>& points3D,
                                    Rigid3d* cam_from_world, int max_num_iterations = 10);

// Non-minimal RANSAC estimator (the local optimisation of absolute pose). X: normalised image
// points; Y: world points.
using EPnPEstimator = SolverEstimator<Eigen::Vector2d, Eigen::Vector3d, Rigid3d, 4, SolveEPnP,
                                      ComputeSquaredReprojectionErrors>;

}  // namespace parallax
