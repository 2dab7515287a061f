// The Schur LM solver's linearisation: the layout of the reduced system, the parameters'
// copies, the cost and, with the Jacobians, the reduced-system blocks U, g_c, V and g_p.

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "parallax/estimators/cost_functions/reprojection_error.h"
#include "parallax/estimators/schur_solver.h"
#include "parallax/util/check.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace schur_detail {
namespace {

double HalfRobustCost(const ceres::LossFunction* loss, double squared_norm, double* scale) {
  if (loss == nullptr) {
    if (scale != nullptr) *scale = 1.0;
    return 0.5 * squared_norm;
  }
  double rho[3];
  loss->Evaluate(squared_norm, rho);
  if (scale != nullptr) *scale = std::sqrt(std::max(rho[1], 0.0));
  return 0.5 * rho[0];
}

}  // namespace

template <typename ReducedMatrix>
void SchurSolver<ReducedMatrix>::Layout() {
  num_threads_ = std::min(EffectiveNumThreads(options_.num_threads), EffectiveNumThreads(-1));
  const size_t num_poses = problem_.poses.size();
  pose_offset_.assign(num_poses, -1);
  for (size_t i = 0; i < num_poses; ++i) {
    const auto& pose = problem_.poses[i];
    if (!pose.IsVariable()) continue;
    pose_offset_[i] = num_camera_variables_;
    num_camera_variables_ += 6;
  }
  const size_t num_cameras = problem_.cameras.size();
  camera_offset_.assign(num_cameras, -1);
  camera_dim_.assign(num_cameras, 0);
  project_.resize(num_cameras);
  img_from_cam_.resize(num_cameras);
  for (size_t c = 0; c < num_cameras; ++c) {
    const auto& block = problem_.cameras[c];
    const CameraModelId model_id = block.camera->model_id;
    project_[c] = VisitCameraModel(
        model_id, []<typename Model>() -> ProjectFn { return &ProjectWithJacobians<Model>; });
    img_from_cam_[c] = VisitCameraModel(model_id, []<typename Model>() -> ImgFromCamFn {
      return &Model::template ImgFromCam<double>;
    });
    PARALLAX_CHECK_LE(block.camera->params.size(), static_cast<size_t>(kMaxCameraParams));
    if (!block.IsVariable()) continue;
    camera_offset_[c] = num_camera_variables_;
    camera_dim_[c] = static_cast<int>(block.free_params.size());
    num_camera_variables_ += camera_dim_[c];
  }

  // Counting sort of the observations by point (stable: problem order within a point).
  const size_t num_points = problem_.points.size();
  point_begin_.assign(num_points + 1, 0);
  for (const auto& observation : problem_.observations) ++point_begin_[observation.point + 1];
  for (size_t j = 0; j < num_points; ++j) point_begin_[j + 1] += point_begin_[j];
  observations_.resize(problem_.observations.size());
  std::vector<size_t> next(point_begin_.begin(), point_begin_.end() - 1);
  for (const auto& observation : problem_.observations) {
    observations_[next[observation.point]++] = observation;
  }

  // Chunks by observation count; their number is the thread count, so that a given thread
  // count always sums the same partial systems in the same order.
  const int num_chunks = std::max(1, std::min<int>(num_threads_, static_cast<int>(num_points)));
  chunk_begin_.assign(1, 0);
  const size_t num_observations = problem_.observations.size();
  for (int chunk = 1; chunk < num_chunks; ++chunk) {
    const size_t target = num_observations * chunk / num_chunks;
    const auto it = std::lower_bound(point_begin_.begin(), point_begin_.end(), target);
    chunk_begin_.push_back(
        std::max(chunk_begin_.back(), static_cast<int>(it - point_begin_.begin())));
  }
  chunk_begin_.push_back(static_cast<int>(num_points));

  jacobians_.resize(num_observations);
  const bool any_free_camera = std::any_of(camera_offset_.begin(), camera_offset_.end(),
                                           [](int offset) { return offset >= 0; });
  if (any_free_camera) {
    camera_jacobian_stride_ =
        2 * static_cast<size_t>(*std::max_element(camera_dim_.begin(), camera_dim_.end()));
    camera_jacobian_values_.resize(num_observations * camera_jacobian_stride_);
  }
  v_.resize(num_points);
  g_point_.resize(num_points);
  v_inverse_.resize(num_points);
  for (size_t i = 0; i < num_poses; ++i) {
    if (pose_offset_[i] >= 0) structure_.AddVariableBlock(pose_offset_[i], 6);
  }
  for (size_t c = 0; c < num_cameras; ++c) {
    if (camera_offset_[c] >= 0) structure_.AddVariableBlock(camera_offset_[c], camera_dim_[c]);
  }
  if constexpr (kSparse) {
    // The blocks a point couples: its views' poses and intrinsics, pairwise.
    std::vector<int> offsets;
    for (size_t j = 0; j < num_points; ++j) {
      offsets.clear();
      for (size_t k = point_begin_[j]; k < point_begin_[j + 1]; ++k) {
        const auto& observation = observations_[k];
        if (pose_offset_[observation.pose] >= 0) offsets.push_back(pose_offset_[observation.pose]);
        if (camera_offset_[observation.camera] >= 0)
          offsets.push_back(camera_offset_[observation.camera]);
      }
      structure_.Couple(offsets);
    }
  }
  structure_.Finalize();
  u_ = ReducedMatrix(structure_);
  partial_matrix_.assign(NumChunks(), ReducedMatrix(structure_));
  partial_vector_.assign(NumChunks(), Eigen::VectorXd());
}

template <typename ReducedMatrix>
void SchurSolver<ReducedMatrix>::CopyIn() {
  for (const auto& pose : problem_.poses) {
    parameters_.rotations.push_back(pose.cam_from_world->rotation.normalized());
    parameters_.translations.push_back(pose.cam_from_world->translation);
  }
  for (const auto& point : problem_.points) parameters_.points.push_back(*point.xyz);
  for (const auto& block : problem_.cameras)
    parameters_.camera_params.push_back(block.camera->params);
}

template <typename ReducedMatrix>
void SchurSolver<ReducedMatrix>::CopyOut() const {
  for (size_t i = 0; i < problem_.poses.size(); ++i) {
    if (pose_offset_[i] < 0) continue;
    problem_.poses[i].cam_from_world->rotation = parameters_.rotations[i];
    problem_.poses[i].cam_from_world->translation = parameters_.translations[i];
  }
  for (size_t j = 0; j < problem_.points.size(); ++j) {
    if (!problem_.points[j].constant) *problem_.points[j].xyz = parameters_.points[j];
  }
  for (size_t c = 0; c < problem_.cameras.size(); ++c) {
    if (camera_offset_[c] >= 0) problem_.cameras[c].camera->params = parameters_.camera_params[c];
  }
}

template <typename ReducedMatrix>
double SchurSolver<ReducedMatrix>::Evaluate(const Parameters& parameters, bool linearize) {
  std::vector<Eigen::Matrix3d> rotations(parameters.rotations.size());
  for (size_t i = 0; i < rotations.size(); ++i) {
    rotations[i] = parameters.rotations[i].toRotationMatrix();
  }
  const int n = num_camera_variables_;
  std::vector<double> chunk_cost(NumChunks(), 0.0);
  ParallelFor(0, static_cast<size_t>(NumChunks()), num_threads_, [&](size_t chunk) {
    ReducedMatrix* u = nullptr;
    Eigen::VectorXd* g = nullptr;
    if (linearize) {
      u = &partial_matrix_[chunk];
      g = &partial_vector_[chunk];
      u->SetZero();
      g->setZero(n);
    }
    double cost = 0;
    for (int j = chunk_begin_[chunk]; j < chunk_begin_[chunk + 1]; ++j) {
      const Eigen::Vector3d& point = parameters.points[j];
      Eigen::Matrix3d v = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g_point = Eigen::Vector3d::Zero();
      for (size_t k = point_begin_[j]; k < point_begin_[j + 1]; ++k) {
        const auto& observation = observations_[k];
        const int p = observation.pose;
        const int c = observation.camera;
        const double* params = parameters.camera_params[c].data();
        const Eigen::Vector3d rotated = rotations[p] * point;
        const Eigen::Vector3d point_in_cam = rotated + parameters.translations[p];
        if (!linearize) {
          double x, y;
          img_from_cam_[c](params, point_in_cam.x(), point_in_cam.y(), point_in_cam.z(), &x, &y);
          cost += HalfRobustCost(loss_, (Eigen::Vector2d(x, y) - observation.xy).squaredNorm(),
                                 nullptr);
          continue;
        }
        ObservationJacobian& jacobian = jacobians_[k];
        Eigen::Vector2d img;
        Matrix23 d_img_d_cam;
        double d_img_d_params[2 * kMaxCameraParams];
        const int camera_offset = camera_offset_[c];
        project_[c](params, point_in_cam, &img, &d_img_d_cam,
                    camera_offset >= 0 ? d_img_d_params : nullptr);
        jacobian.residual = img - observation.xy;
        // Only variable poses need theirs (and are the only ones read): in a local adjustment
        // most observations are in the constant images around it.
        const int pose_offset = pose_offset_[p];
        if (pose_offset >= 0) {
          // d(R X)/d(rotation vector) for R <- exp([w]x) R is -[R X]x.
          Eigen::Matrix3d minus_skew;
          minus_skew << 0, rotated.z(), -rotated.y(), -rotated.z(), 0, rotated.x(), rotated.y(),
              -rotated.x(), 0;
          jacobian.pose.leftCols<3>() = d_img_d_cam * minus_skew;
          jacobian.pose.rightCols<3>() = d_img_d_cam;
          const auto& pose = problem_.poses[p];
          for (int axis = 0; axis < 3; ++axis) {
            if (pose.constant_translation[axis]) jacobian.pose.col(3 + axis).setZero();
          }
        }
        jacobian.point = d_img_d_cam * rotations[p];
        const int dim = camera_dim_[c];
        if (camera_offset >= 0) {
          auto camera_jacobian = CameraJacobian(k, dim);
          const int num_params = static_cast<int>(parameters.camera_params[c].size());
          const std::vector<int>& free = problem_.cameras[c].free_params;
          for (int f = 0; f < dim; ++f) {
            camera_jacobian.col(f) << d_img_d_params[free[f]], d_img_d_params[num_params + free[f]];
          }
        }
        double scale = 1.0;
        cost += HalfRobustCost(loss_, jacobian.residual.squaredNorm(), &scale);
        if (loss_ != nullptr) {
          jacobian.residual *= scale;
          if (pose_offset >= 0) jacobian.pose *= scale;
          jacobian.point *= scale;
          if (camera_offset >= 0) CameraJacobian(k, dim) *= scale;
        }
        if (pose_offset >= 0) {
          u->template Block<6, 6>(pose_offset, pose_offset).noalias() +=
              jacobian.pose.transpose() * jacobian.pose;
          g->segment<6>(pose_offset).noalias() += jacobian.pose.transpose() * jacobian.residual;
        }
        if (camera_offset >= 0) {
          const auto camera_block = CameraJacobian(k, dim);
          u->Block(camera_offset, camera_offset, dim, dim).noalias() +=
              camera_block.transpose() * camera_block;
          g->segment(camera_offset, dim).noalias() += camera_block.transpose() * jacobian.residual;
          if (pose_offset >= 0) {
            // Lower triangle: the later block's rows.
            if (camera_offset > pose_offset) {
              u->Block(camera_offset, pose_offset, dim, 6).noalias() +=
                  camera_block.transpose() * jacobian.pose;
            } else {
              u->Block(pose_offset, camera_offset, 6, dim).noalias() +=
                  jacobian.pose.transpose() * camera_block;
            }
          }
        }
        v.noalias() += jacobian.point.transpose() * jacobian.point;
        g_point.noalias() += jacobian.point.transpose() * jacobian.residual;
      }
      if (linearize) {
        v_[j] = v;
        g_point_[j] = g_point;
      }
    }
    chunk_cost[chunk] = cost;
  });
  if (linearize) {
    u_ = partial_matrix_[0];
    g_camera_ = partial_vector_[0];
    for (int chunk = 1; chunk < NumChunks(); ++chunk) {
      u_ += partial_matrix_[chunk];
      g_camera_ += partial_vector_[chunk];
    }
  }
  double cost = 0;
  for (const double value : chunk_cost) cost += value;
  return cost;
}

// The members defined here, for both reduced systems.
template class SchurSolver<DenseReducedMatrix>;
template class SchurSolver<BlockSparseReducedMatrix>;

}  // namespace schur_detail
}  // namespace parallax
