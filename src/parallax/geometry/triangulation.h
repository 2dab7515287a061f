#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "parallax/math/eigen_types.h"

namespace parallax {

// Linear triangulation (Hartley & Zisserman, sec. 12.2): the null vector, by SVD, of the
// stacked cross-product system [x]_x P X = 0 of both views. Points are normalised image
// coordinates (z = 1) and the matrices cam_from_world = [R | t]. Returns nullopt when the
// system is degenerate (point at infinity, NaN input).
std::optional<Eigen::Vector3d> TriangulatePoint(const Matrix3x4d& cam1_from_world,
                                                const Matrix3x4d& cam2_from_world,
                                                const Eigen::Vector2d& point1,
                                                const Eigen::Vector2d& point2);

// The same system stacked over N >= 2 views.
std::optional<Eigen::Vector3d> TriangulateMultiViewPoint(
    const std::vector<Matrix3x4d>& cams_from_world, const std::vector<Eigen::Vector2d>& points);

// Angle in radians between the rays from the two centres to the point.
double CalculateTriangulationAngle(const Eigen::Vector3d& center1, const Eigen::Vector3d& center2,
                                   const Eigen::Vector3d& point3D);

// True when the point lies in front of the camera (positive depth).
bool HasPointPositiveDepth(const Matrix3x4d& cam_from_world, const Eigen::Vector3d& point3D);

}  // namespace parallax
