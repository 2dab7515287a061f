#pragma once

#include <Eigen/Core>
#include <vector>

namespace parallax {

// Residuals of two-view models, all squared (the unit RANSAC thresholds are squared in).

// Squared Sampson error of x2^T F x1 = 0 (Hartley & Zisserman, eq. 11.9): the first-order
// approximation of the squared distance of (x1, x2) to the variety of F,
//   (x2^T F x1)^2 / ((F x1)_0^2 + (F x1)_1^2 + (F^T x2)_0^2 + (F^T x2)_1^2).
// Works for an essential matrix on normalised coordinates alike. A zero gradient (the
// point sits on an epipole of a degenerate model) gives the largest double.
double ComputeSquaredSampsonError(const Eigen::Vector2d& point1, const Eigen::Vector2d& point2,
                                  const Eigen::Matrix3d& F);
void ComputeSquaredSampsonError(const std::vector<Eigen::Vector2d>& points1,
                                const std::vector<Eigen::Vector2d>& points2,
                                const Eigen::Matrix3d& F, std::vector<double>* squared_errors);

// The Sampson error of unit rays under an essential matrix, on the sphere: the epipolar
// residual b2^T E b1 over its gradient in the planes tangent to the two rays. To first order
// the angle (radians) by which the rays miss a common epipolar plane; valid for rays in any
// direction, behind the image plane too.
double ComputeSquaredSphericalSampsonError(const Eigen::Vector3d& ray1, const Eigen::Vector3d& ray2,
                                           const Eigen::Matrix3d& E);
void ComputeSquaredSphericalSampsonError(const std::vector<Eigen::Vector3d>& rays1,
                                         const std::vector<Eigen::Vector3d>& rays2,
                                         const Eigen::Matrix3d& E,
                                         std::vector<double>* squared_errors);

// Squared transfer error ||x2 - H x1||^2 of x2 = H x1 (x1 mapped to image 2 only). A point
// mapped to infinity gives the largest double.
double ComputeSquaredHomographyError(const Eigen::Vector2d& point1, const Eigen::Vector2d& point2,
                                     const Eigen::Matrix3d& H);
void ComputeSquaredHomographyError(const std::vector<Eigen::Vector2d>& points1,
                                   const std::vector<Eigen::Vector2d>& points2,
                                   const Eigen::Matrix3d& H, std::vector<double>* squared_errors);

// Squared symmetric transfer error ||x2 - H x1||^2 + ||x1 - H^-1 x2||^2 (Hartley & Zisserman,
// eq. 4.7). A singular H gives the largest double for every correspondence.
void ComputeSquaredSymmetricTransferError(const std::vector<Eigen::Vector2d>& points1,
                                          const std::vector<Eigen::Vector2d>& points2,
                                          const Eigen::Matrix3d& H,
                                          std::vector<double>* squared_errors);

}  // namespace parallax
