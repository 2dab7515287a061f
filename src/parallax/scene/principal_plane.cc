#include "parallax/scene/principal_plane.h"

#include <Eigen/Eigenvalues>

namespace parallax {

Sim3d PrincipalPlaneAlignment(const Reconstruction& model) {
  if (model.NumPoints3D() < 3) return Sim3d();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& [point3D_id, point] : model.Points3D()) centroid += point.xyz;
  centroid /= static_cast<double>(model.NumPoints3D());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& [point3D_id, point] : model.Points3D()) {
    const Eigen::Vector3d offset = point.xyz - centroid;
    covariance += offset * offset.transpose();
  }
  // Eigenvalues ascending: the last vector spreads most, the first is the plane's normal.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d x_axis = solver.eigenvectors().col(2);
  Eigen::Vector3d z_axis = solver.eigenvectors().col(0);
  Eigen::Vector3d mean_center = Eigen::Vector3d::Zero();
  for (const image_t image_id : model.RegImageIds()) {
    mean_center += model.GetImage(image_id).ProjectionCenter();
  }
  if (model.NumRegImages() > 0 && z_axis.dot(mean_center / model.NumRegImages() - centroid) < 0) {
    z_axis = -z_axis;
  }
  Eigen::Matrix3d rotation;
  rotation.row(0) = x_axis.transpose();
  rotation.row(1) = z_axis.cross(x_axis).transpose();
  rotation.row(2) = z_axis.transpose();
  return Sim3d(1.0, Eigen::Quaterniond(rotation), -(rotation * centroid));
}

}  // namespace parallax
