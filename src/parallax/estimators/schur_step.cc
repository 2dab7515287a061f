// The Schur LM solver's step: the damped reduced camera system solved (dense Cholesky or
// preconditioned conjugate gradients), the points back-substituted, the model cost change,
// and the step applied.

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

#include "parallax/estimators/schur_solver.h"
#include "parallax/util/check.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace schur_detail {
namespace {

// block -= a b^T for 6 x 3 a and b, rows 0-3 apart from rows 4-5: Eigen sums a product of
// six rows in pairs of doubles (six is no multiple of AVX's four), so the 6 x 6 block took 72
// vector operations; four rows and two, it takes 48.
template <typename Block>
void SubtractPoseProduct(const Matrix63& a, const Matrix63& b, Block&& block) {
  block.template topRows<4>().noalias() -= a.topRows<4>() * b.transpose();
  block.template bottomRows<2>().noalias() -= a.bottomRows<2>() * b.transpose();
}

}  // namespace

template <typename ReducedMatrix>
bool SchurSolver<ReducedMatrix>::ComputeStep(double radius, Eigen::VectorXd* camera_step,
                                             std::vector<Eigen::Vector3d>* point_step) {
  const int n = num_camera_variables_;
  const auto damping = [radius](double diagonal) {
    return std::clamp(diagonal, kMinDiagonal, kMaxDiagonal) / radius;
  };
  // Per chunk: S_chunk = -sum_j W_j V_j^-1 W_j^T and b_chunk = sum_j W_j V_j^-1 g_j over its
  // points, lower triangle only; W_j's rows are the pose and camera blocks of j's views.
  ParallelFor(0, static_cast<size_t>(NumChunks()), num_threads_, [&](size_t chunk) {
    ReducedMatrix& s = partial_matrix_[chunk];
    Eigen::VectorXd& b = partial_vector_[chunk];
    s.SetZero();
    b.setZero(n);
    // The point's views with a variable pose or camera, in observation order: the pairs of
    // the others add nothing, and in a local adjustment most views are of constant images
    // (walking all pairs, their bookkeeping took more time than the products).
    struct VariableView {
      int pose = -1;  // Offsets in the reduced system (-1: constant), and the camera's size.
      int camera = -1;
      int dim = 0;
    };
    std::vector<VariableView> views;
    std::vector<Matrix63> w_pose, y_pose;
    std::vector<MatrixC3> w_camera, y_camera;
    for (int j = chunk_begin_[chunk]; j < chunk_begin_[chunk + 1]; ++j) {
      if (problem_.points[j].constant) continue;
      Eigen::Matrix3d v = v_[j];
      for (int d = 0; d < 3; ++d) v(d, d) += damping(v(d, d));
      const Eigen::LLT<Eigen::Matrix3d> llt(v);
      if (llt.info() != Eigen::Success) {
        v_inverse_[j].setZero();  // A point no view constrains stays where it is.
        continue;
      }
      v_inverse_[j] = llt.solve(Eigen::Matrix3d::Identity());
      const size_t begin = point_begin_[j];
      const size_t m = point_begin_[j + 1] - begin;
      if (w_pose.size() < m) {
        w_pose.resize(m);
        y_pose.resize(m);
        w_camera.resize(m);
        y_camera.resize(m);
      }
      views.clear();
      for (size_t a = 0; a < m; ++a) {
        const size_t k = begin + a;
        const auto& observation = observations_[k];
        const int c = observation.camera;
        const VariableView view{pose_offset_[observation.pose], camera_offset_[c], camera_dim_[c]};
        if (view.pose < 0 && view.camera < 0) continue;
        const size_t i = views.size();
        views.push_back(view);
        const ObservationJacobian& jacobian = jacobians_[k];
        if (view.pose >= 0) {
          w_pose[i].noalias() = jacobian.pose.transpose() * jacobian.point;
          y_pose[i].noalias() = w_pose[i] * v_inverse_[j];
          b.segment<6>(view.pose).noalias() += y_pose[i] * g_point_[j];
        }
        if (view.camera >= 0) {
          w_camera[i].noalias() = CameraJacobian(k, view.dim).transpose() * jacobian.point;
          y_camera[i].noalias() = w_camera[i] * v_inverse_[j];
          b.segment(view.camera, view.dim).noalias() += y_camera[i] * g_point_[j];
        }
      }
      // One variable camera in every view of the point (a collection from one camera): its
      // block of the sum is W_c V^-1 W_c^T with W_c the sum of the views' camera parts, and
      // pose a's cross block Y_a W_c^T: m products where pairs of views take m^2.
      int shared_camera = observations_[begin].camera;
      if (camera_offset_[shared_camera] < 0) shared_camera = -1;
      for (size_t a = 1; a < m && shared_camera >= 0; ++a) {
        if (observations_[begin + a].camera != shared_camera) shared_camera = -1;
      }
      const auto cross = [&](int pose_offset, const Matrix63& y_or_w_pose, int camera_offset,
                             int dim, const MatrixC3& w_or_y_camera) {
        if (pose_offset < 0 || camera_offset < 0) return;
        if (camera_offset > pose_offset) {
          s.Block(camera_offset, pose_offset, dim, 6).noalias() -=
              w_or_y_camera * y_or_w_pose.transpose();
        } else {
          s.Block(pose_offset, camera_offset, 6, dim).noalias() -=
              y_or_w_pose * w_or_y_camera.transpose();
        }
      };
      // Block (a, b) of the sum is Y_a W_b^T; only blocks on or below the diagonal are
      // written, each once: pairs b <= a, and for b == a the two segments in one order.
      for (size_t a = 0; a < views.size(); ++a) {
        const auto [pose_a, camera_a, dim_a] = views[a];
        for (size_t bi = 0; bi <= a; ++bi) {
          const auto [pose_b, camera_b, dim_b] = views[bi];
          if (pose_a >= 0 && pose_b >= 0) {
            if (pose_a > pose_b) {
              SubtractPoseProduct(y_pose[a], w_pose[bi], s.template Block<6, 6>(pose_a, pose_b));
            } else if (pose_a < pose_b) {
              SubtractPoseProduct(w_pose[bi], y_pose[a], s.template Block<6, 6>(pose_b, pose_a));
            } else {
              // The diagonal block; (a, b) and (b, a) both land here only if one image
              // observed the point twice.
              SubtractPoseProduct(y_pose[a], w_pose[bi], s.template Block<6, 6>(pose_a, pose_a));
              if (bi != a) {
                SubtractPoseProduct(w_pose[bi], y_pose[a], s.template Block<6, 6>(pose_a, pose_a));
              }
            }
          }
          if (camera_a >= 0 && camera_b >= 0 && shared_camera < 0) {
            auto block =
                s.Block(std::max(camera_a, camera_b), std::min(camera_a, camera_b),
                        camera_a >= camera_b ? dim_a : dim_b, camera_a >= camera_b ? dim_b : dim_a);
            if (camera_a > camera_b) {
              block.noalias() -= y_camera[a] * w_camera[bi].transpose();
            } else if (camera_a < camera_b) {
              block.noalias() -= w_camera[bi] * y_camera[a].transpose();
            } else {
              // Shared intrinsics: (a, b) and (b, a) land on the same diagonal block.
              block.noalias() -= y_camera[a] * w_camera[bi].transpose();
              if (bi != a) block.noalias() -= w_camera[bi] * y_camera[a].transpose();
            }
          }
          if (shared_camera >= 0) continue;  // Its blocks follow the loop.
          // Cross blocks pose(a)-camera(b), and pose(b)-camera(a) when b != a.
          if (pose_a >= 0 && camera_b >= 0) cross(pose_a, y_pose[a], camera_b, dim_b, w_camera[bi]);
          if (bi != a && pose_b >= 0 && camera_a >= 0) {
            cross(pose_b, w_pose[bi], camera_a, dim_a, y_camera[a]);
          }
        }
      }
      if (shared_camera >= 0) {
        // Every view is variable here (its camera is), so views[a] is observation a.
        const int offset = camera_offset_[shared_camera];
        const int dim = camera_dim_[shared_camera];
        MatrixC3 w_sum = w_camera[0];
        for (size_t a = 1; a < m; ++a) w_sum += w_camera[a];
        const MatrixC3 y_sum = w_sum * v_inverse_[j];
        s.Block(offset, offset, dim, dim).noalias() -= y_sum * w_sum.transpose();
        for (size_t a = 0; a < m; ++a) cross(views[a].pose, y_pose[a], offset, dim, w_sum);
      }
    }
  });

  ReducedMatrix s = u_;
  Eigen::VectorXd b = -g_camera_;
  for (int chunk = 0; chunk < NumChunks(); ++chunk) {
    s += partial_matrix_[chunk];
    b += partial_vector_[chunk];
  }
  for (int d = 0; d < n; ++d) s.AddToDiagonal(d, damping(u_.Diagonal(d)));
  camera_step->setZero(n);
  if (n > 0) {
    int num_iterations = 0;
    const bool solved = s.Solve(b, options_.conjugate_gradient, camera_step, &num_iterations);
    num_linear_iterations_ += num_iterations;
    if (!solved || !camera_step->allFinite()) return false;
  }

  // Back-substitution: dX_j = -V_j^-1 (g_j + W_j^T dc).
  point_step->assign(problem_.points.size(), Eigen::Vector3d::Zero());
  ParallelFor(0, static_cast<size_t>(NumChunks()), num_threads_, [&](size_t chunk) {
    for (int j = chunk_begin_[chunk]; j < chunk_begin_[chunk + 1]; ++j) {
      if (problem_.points[j].constant) continue;
      Eigen::Vector3d rhs = g_point_[j];
      for (size_t k = point_begin_[j]; k < point_begin_[j + 1]; ++k) {
        rhs.noalias() += jacobians_[k].point.transpose() * CameraStepImage(k, *camera_step);
      }
      (*point_step)[j] = -v_inverse_[j] * rhs;
    }
  });
  return true;
}

template <typename ReducedMatrix>
Eigen::Vector2d SchurSolver<ReducedMatrix>::CameraStepImage(
    size_t k, const Eigen::VectorXd& camera_step) const {
  const auto& observation = observations_[k];
  Eigen::Vector2d image = Eigen::Vector2d::Zero();
  const int pose_offset = pose_offset_[observation.pose];
  if (pose_offset >= 0) image += jacobians_[k].pose * camera_step.segment<6>(pose_offset);
  const int c = observation.camera;
  if (camera_offset_[c] >= 0) {
    image +=
        CameraJacobian(k, camera_dim_[c]) * camera_step.segment(camera_offset_[c], camera_dim_[c]);
  }
  return image;
}

// Ceres' model cost change of the linearised, loss-corrected residuals: -(J d)^T (r + J d / 2).
// By the linearisation's chunks, each on a thread as there: a serial pass would pull every
// chunk's Jacobians into one core's cache, from which the other core must fetch its own back
// when it next writes them, which made the linearisation slower on two threads than on one
// (docs/performance.md, "Schur LM: the model cost change by chunks").
template <typename ReducedMatrix>
double SchurSolver<ReducedMatrix>::ModelCostChange(
    const Eigen::VectorXd& camera_step, const std::vector<Eigen::Vector3d>& point_step) const {
  std::vector<double> chunk_change(NumChunks(), 0.0);
  ParallelFor(0, static_cast<size_t>(NumChunks()), num_threads_, [&](size_t chunk) {
    double change = 0;
    for (size_t k = point_begin_[chunk_begin_[chunk]]; k < point_begin_[chunk_begin_[chunk + 1]];
         ++k) {
      const auto& observation = observations_[k];
      const ObservationJacobian& jacobian = jacobians_[k];
      const Eigen::Vector2d j_step =
          jacobian.point * point_step[observation.point] + CameraStepImage(k, camera_step);
      change -= j_step.dot(jacobian.residual + 0.5 * j_step);
    }
    chunk_change[chunk] = change;
  });
  double change = 0;
  for (const double value : chunk_change) change += value;
  return change;
}

template <typename ReducedMatrix>
void SchurSolver<ReducedMatrix>::ApplyStep(const Eigen::VectorXd& camera_step,
                                           const std::vector<Eigen::Vector3d>& point_step,
                                           Parameters* candidate) const {
  *candidate = parameters_;
  for (size_t i = 0; i < problem_.poses.size(); ++i) {
    const int offset = pose_offset_[i];
    if (offset < 0) continue;
    const Eigen::Vector3d rotation_step = camera_step.segment<3>(offset);
    const double angle = rotation_step.norm();
    if (angle > 0) {
      candidate->rotations[i] =
          (Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation_step / angle)) *
           parameters_.rotations[i])
              .normalized();
    }
    candidate->translations[i] += camera_step.segment<3>(offset + 3);
  }
  for (size_t j = 0; j < problem_.points.size(); ++j) candidate->points[j] += point_step[j];
  for (size_t c = 0; c < problem_.cameras.size(); ++c) {
    const int offset = camera_offset_[c];
    if (offset < 0) continue;
    const std::vector<int>& free = problem_.cameras[c].free_params;
    for (size_t f = 0; f < free.size(); ++f) {
      candidate->camera_params[c][free[f]] += camera_step[offset + static_cast<int>(f)];
    }
  }
}

// |x| over the variable blocks, as Ceres' parameter tolerance uses it.
template <typename ReducedMatrix>
double SchurSolver<ReducedMatrix>::ParameterNorm(const Parameters& parameters) const {
  double squared = 0;
  for (size_t i = 0; i < problem_.poses.size(); ++i) {
    if (pose_offset_[i] < 0) continue;
    squared +=
        parameters.rotations[i].coeffs().squaredNorm() + parameters.translations[i].squaredNorm();
  }
  for (size_t j = 0; j < problem_.points.size(); ++j) {
    if (!problem_.points[j].constant) squared += parameters.points[j].squaredNorm();
  }
  for (size_t c = 0; c < problem_.cameras.size(); ++c) {
    if (camera_offset_[c] < 0) continue;
    for (const double value : parameters.camera_params[c]) squared += value * value;
  }
  return std::sqrt(squared);
}

template <typename ReducedMatrix>
double SchurSolver<ReducedMatrix>::LargestCameraMove(const Eigen::VectorXd& camera_step) const {
  // The scene's scale: the RMS distance of the camera centres (constant poses included) from
  // their mean; 1 where they coincide.
  std::vector<Eigen::Vector3d> centres(problem_.poses.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < centres.size(); ++i) {
    centres[i] = -(parameters_.rotations[i].conjugate() * parameters_.translations[i]);
    mean += centres[i] / static_cast<double>(centres.size());
  }
  double spread_squared = 0;
  for (const Eigen::Vector3d& centre : centres) {
    spread_squared += (centre - mean).squaredNorm() / static_cast<double>(centres.size());
  }
  const double spread = spread_squared > 0 ? std::sqrt(spread_squared) : 1.0;
  double largest = 0;
  for (size_t i = 0; i < problem_.poses.size(); ++i) {
    const int offset = pose_offset_[i];
    if (offset < 0) continue;
    largest = std::max({largest, camera_step.segment<3>(offset).norm(),
                        camera_step.segment<3>(offset + 3).norm() / spread});
  }
  for (size_t c = 0; c < problem_.cameras.size(); ++c) {
    const int offset = camera_offset_[c];
    if (offset < 0) continue;
    const std::vector<int>& free = problem_.cameras[c].free_params;
    for (size_t f = 0; f < free.size(); ++f) {
      largest =
          std::max(largest, std::abs(camera_step[offset + static_cast<int>(f)]) /
                                std::max(1.0, std::abs(parameters_.camera_params[c][free[f]])));
    }
  }
  return largest;
}

// The members defined here, for both reduced systems.
template class SchurSolver<DenseReducedMatrix>;
template class SchurSolver<BlockSparseReducedMatrix>;

}  // namespace schur_detail
}  // namespace parallax
