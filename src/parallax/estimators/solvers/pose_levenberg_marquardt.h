#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "parallax/math/eigen_types.h"

namespace parallax {

// Levenberg-Marquardt over the six degrees of freedom of a pose, R <- exp([w]x) R and
// t <- t + dt, for residuals that depend on each 3D point only through its position in the
// camera. Two callers: the local optimisation of PnP (normalised coordinates, squared loss)
// and the refinement of a registered image's pose (pixels through the camera model, Cauchy
// loss), which a general solver did at several times the cost for the same minimum.
struct PoseLevenbergMarquardtOptions {
  int max_num_iterations = 100;
  // Stops after an accepted step that lowered the cost by at most this fraction of it.
  double min_relative_decrease = 1e-12;
};

// `observe(i, point_in_cam, &residual, jacobian)` gives point i's 2-vector residual and, when
// `jacobian` is not null, its 2x3 derivative with respect to point_in_cam; it returns false
// for a point it cannot observe there (behind the camera), which then takes no part.
// `loss.Cost(s)` is the cost of a squared residual norm s and `loss.Weight(s)` its derivative
// (iteratively reweighted normal equations). A step is taken only when it lowers the cost
// and keeps at least as many points observable as at the start. Returns false, leaving the
// pose, when fewer than three points are observable at the start or the cost is not finite.
template <typename Observe, typename Loss>
bool MinimizeOverPose(const std::vector<Eigen::Vector3d>& points3D, const Observe& observe,
                      const Loss& loss, const PoseLevenbergMarquardtOptions& options,
                      Eigen::Matrix3d* rotation, Eigen::Vector3d* translation) {
  using Matrix23 = Eigen::Matrix<double, 2, 3>;
  const auto cost_of = [&](const Eigen::Matrix3d& r, const Eigen::Vector3d& t,
                           size_t* num_observed) {
    double cost = 0;
    *num_observed = 0;
    Eigen::Vector2d residual;
    for (size_t i = 0; i < points3D.size(); ++i) {
      if (!observe(i, r * points3D[i] + t, &residual, static_cast<Matrix23*>(nullptr))) continue;
      cost += loss.Cost(residual.squaredNorm());
      ++*num_observed;
    }
    return cost;
  };
  size_t num_observed = 0;
  double cost = cost_of(*rotation, *translation, &num_observed);
  if (num_observed < 3 || !std::isfinite(cost)) return false;

  double damping = 1e-4;
  for (int iteration = 0; iteration < options.max_num_iterations; ++iteration) {
    Matrix6d hessian = Matrix6d::Zero();
    Vector6d gradient = Vector6d::Zero();
    for (size_t i = 0; i < points3D.size(); ++i) {
      const Eigen::Vector3d rotated = *rotation * points3D[i];
      Eigen::Vector2d residual;
      Matrix23 d_residual;
      if (!observe(i, rotated + *translation, &residual, &d_residual)) continue;
      Eigen::Matrix3d skew_rotated;
      skew_rotated << 0, -rotated.z(), rotated.y(), rotated.z(), 0, -rotated.x(), -rotated.y(),
          rotated.x(), 0;
      Eigen::Matrix<double, 2, 6> jacobian;
      jacobian.leftCols<3>() = -d_residual * skew_rotated;
      jacobian.rightCols<3>() = d_residual;
      const double weight = loss.Weight(residual.squaredNorm());
      hessian.noalias() += weight * jacobian.transpose() * jacobian;
      gradient.noalias() += weight * jacobian.transpose() * residual;
    }

    bool accepted = false;
    double new_cost = cost;
    while (damping < 1e10) {
      Matrix6d damped = hessian;
      damped.diagonal() += damping * hessian.diagonal().cwiseMax(1e-12);
      const Vector6d step = -damped.ldlt().solve(gradient);
      if (!step.allFinite()) {
        damping *= 10;
        continue;
      }
      const double angle = step.head<3>().norm();
      const Eigen::Matrix3d step_rotation =
          angle > 0 ? Eigen::AngleAxisd(angle, step.head<3>() / angle).toRotationMatrix()
                    : Eigen::Matrix3d::Identity();
      const Eigen::Matrix3d new_rotation = step_rotation * *rotation;
      const Eigen::Vector3d new_translation = *translation + step.tail<3>();
      size_t new_num_observed = 0;
      new_cost = cost_of(new_rotation, new_translation, &new_num_observed);
      if (new_num_observed >= num_observed && new_cost < cost) {
        *rotation = new_rotation;
        *translation = new_translation;
        damping = std::max(damping / 10, 1e-12);
        accepted = true;
        break;
      }
      damping *= 10;
    }
    if (!accepted) break;
    const double decrease = cost - new_cost;
    cost = new_cost;
    if (decrease <= options.min_relative_decrease * cost) break;
  }
  return true;
}

}  // namespace parallax
