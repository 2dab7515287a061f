#include "parallax/estimators/schur_bundle_adjuster.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

#include "parallax/estimators/cost_functions/reprojection_error.h"
#include "parallax/estimators/reduced_camera_matrix.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

// Ceres' trust-region constants, so that both solvers take the same steps.
constexpr double kInitialRadius = 1e4;
constexpr double kMaxRadius = 1e16;
constexpr double kMinRadius = 1e-32;
constexpr double kMinDiagonal = 1e-6;
constexpr double kMaxDiagonal = 1e32;
constexpr double kMinRelativeDecrease = 1e-3;
constexpr int kMaxCameraParams = 8;  // OPENCV's.

using Matrix26 = Eigen::Matrix<double, 2, 6>;
using Matrix23 = Eigen::Matrix<double, 2, 3>;
using Matrix2X = Eigen::Matrix<double, 2, Eigen::Dynamic>;
using Matrix63 = Eigen::Matrix<double, 6, 3>;
using MatrixC3 = Eigen::Matrix<double, Eigen::Dynamic, 3, 0, kMaxCameraParams, 3>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

using ProjectFn = void (*)(const double*, const Eigen::Vector3d&, Eigen::Vector2d*, Matrix23*,
                           double*);
using ImgFromCamFn = void (*)(const double*, double, double, double, double*, double*);

// 0.5 rho(s) of one observation's squared residual s, and in *scale (when non-null) the
// factor sqrt(rho'(s)) that Ceres' corrector applies to residual and Jacobian for losses with
// rho'' <= 0. A null loss is the squared loss.
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

// The solver's copy of the variables: the problem's blocks are written only at the end.
struct Parameters {
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<double>> camera_params;
};

// One observation's (loss-corrected) residual and Jacobians at the current parameters:
// pose columns are the rotation increment (left-multiplied rotation vector), then the
// translation. The intrinsics' Jacobian (free parameters in order) is kept apart, in
// camera_jacobian_values_, since most adjustments hold the cameras fixed.
struct ObservationJacobian {
  Eigen::Vector2d residual;
  Matrix26 pose;
  Matrix23 point;
};

template <typename ReducedMatrix>
class SchurSolver {
 public:
  static constexpr bool kSparse = std::is_same_v<ReducedMatrix, BlockSparseReducedMatrix>;

  SchurSolver(const BundleAdjustmentOptions& options, const ceres::LossFunction* loss,
              BundleAdjustmentProblem* problem)
      : options_(options), loss_(loss), problem_(*problem) {
    Layout();
    CopyIn();
  }

  BundleAdjustmentSummary Solve();

 private:
  void Layout();
  void CopyIn();
  void CopyOut() const;
  // Cost 0.5 sum rho(|r|^2) at `parameters`; with `linearize`, also the Jacobians, the
  // undamped reduced-system blocks U and g_c and the per-point V and g_p at them.
  double Evaluate(const Parameters& parameters, bool linearize);
  // Solves the damped system for `radius`; false when it is not positive definite.
  bool ComputeStep(double radius, Eigen::VectorXd* camera_step,
                   std::vector<Eigen::Vector3d>* point_step);
  double ModelCostChange(const Eigen::VectorXd& camera_step,
                         const std::vector<Eigen::Vector3d>& point_step) const;
  // J_c dc of the k-th observation (in observations_): its pose and intrinsics part of
  // the linearised residual change for the reduced-system step `camera_step`.
  Eigen::Vector2d CameraStepImage(size_t k, const Eigen::VectorXd& camera_step) const;
  void ApplyStep(const Eigen::VectorXd& camera_step, const std::vector<Eigen::Vector3d>& point_step,
                 Parameters* candidate) const;
  double ParameterNorm(const Parameters& parameters) const;
  // The largest move of a camera parameter in `camera_step`, in the units of
  // BundleAdjustmentOptions::camera_step_tolerance.
  double LargestCameraMove(const Eigen::VectorXd& camera_step) const;
  int NumChunks() const { return static_cast<int>(chunk_begin_.size()) - 1; }

  const BundleAdjustmentOptions& options_;
  const ceres::LossFunction* loss_;
  BundleAdjustmentProblem& problem_;
  int num_threads_ = 1;

  // Reduced system layout: offsets of variable poses and cameras (-1: constant).
  std::vector<int> pose_offset_;
  std::vector<int> camera_offset_;
  std::vector<int> camera_dim_;
  int num_camera_variables_ = 0;
  std::vector<ProjectFn> project_;
  std::vector<ImgFromCamFn> img_from_cam_;

  // The observations grouped by point (a copy: every pass walks them in this order, and
  // reaching them through an index into the problem's order missed the cache on most), and
  // the points split into chunks of about equal work (one partial reduced system each,
  // summed in chunk order: deterministic per thread count).
  std::vector<BundleAdjustmentProblem::Observation> observations_;
  std::vector<size_t> point_begin_;
  std::vector<int> chunk_begin_;

  Parameters parameters_;
  std::vector<ObservationJacobian> jacobians_;  // In observations_'s order.
  // The k-th observation's intrinsics Jacobian, 2 x its camera's free parameters.
  Eigen::Map<Matrix2X> CameraJacobian(size_t k, int dim) {
    return Eigen::Map<Matrix2X>(camera_jacobian_values_.data() + k * camera_jacobian_stride_, 2,
                                dim);
  }
  Eigen::Map<const Matrix2X> CameraJacobian(size_t k, int dim) const {
    return Eigen::Map<const Matrix2X>(camera_jacobian_values_.data() + k * camera_jacobian_stride_,
                                      2, dim);
  }
  // Only when some camera is free: per observation, room for the widest free camera (2 x 2
  // for SIMPLE_RADIAL's focal length and k1, where a fixed 2 x 8 took four times the memory).
  std::vector<double> camera_jacobian_values_;
  size_t camera_jacobian_stride_ = 0;
  ReducedMatrixStructure structure_;
  ReducedMatrix u_;  // Lower triangle.
  Eigen::VectorXd g_camera_;
  std::vector<Eigen::Matrix3d> v_;
  std::vector<Eigen::Vector3d> g_point_;
  std::vector<Eigen::Matrix3d> v_inverse_;  // Damped, from the last ComputeStep.
  // Per-chunk accumulators: U and g_c while linearising, then S and b while solving.
  std::vector<ReducedMatrix> partial_matrix_;
  int num_linear_iterations_ = 0;  // Conjugate-gradient iterations, over all steps.
  std::vector<Eigen::VectorXd> partial_vector_;
};

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

// block -= a b^T for 6 x 3 a and b, rows 0-3 apart from rows 4-5: Eigen sums a product of
// six rows in pairs of doubles (six is no multiple of AVX's four), so the 6 x 6 block took 72
// vector operations; four rows and two, it takes 48.
template <typename Block>
void SubtractPoseProduct(const Matrix63& a, const Matrix63& b, Block&& block) {
  block.template topRows<4>().noalias() -= a.topRows<4>() * b.transpose();
  block.template bottomRows<2>().noalias() -= a.bottomRows<2>() * b.transpose();
}

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

template <typename ReducedMatrix>
BundleAdjustmentSummary SchurSolver<ReducedMatrix>::Solve() {
  BundleAdjustmentSummary summary;
  summary.solver = kSparse ? "sparse Schur LM (conjugate gradients)" : "dense Schur LM";
  summary.num_residuals = problem_.observations.size();
  double cost = Evaluate(parameters_, /*linearize=*/true);
  summary.initial_cost = cost;
  summary.final_cost = cost;
  if (!std::isfinite(cost)) {
    summary.termination = "FAILURE: the initial cost is not finite";
    return summary;
  }
  summary.success = true;

  const auto gradient_max_norm = [&] {
    double norm = g_camera_.size() > 0 ? g_camera_.cwiseAbs().maxCoeff() : 0.0;
    for (size_t j = 0; j < g_point_.size(); ++j) {
      if (!problem_.points[j].constant) norm = std::max(norm, g_point_[j].cwiseAbs().maxCoeff());
    }
    return norm;
  };
  std::ostringstream termination;
  double radius = kInitialRadius;
  double decrease_factor = 2.0;
  int num_steps = 0;
  Eigen::VectorXd camera_step;
  std::vector<Eigen::Vector3d> point_step;
  Parameters candidate;
  if (gradient_max_norm() <= options_.gradient_tolerance) {
    termination << "CONVERGENCE: gradient tolerance reached";
  }
  while (termination.tellp() == 0) {
    if (num_steps >= options_.max_num_iterations) {
      termination << "NO_CONVERGENCE: maximum number of iterations reached";
      break;
    }
    ++num_steps;
    if (!ComputeStep(radius, &camera_step, &point_step)) {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) termination << "CONVERGENCE: minimum trust region radius reached";
      continue;
    }
    const double model_cost_change = ModelCostChange(camera_step, point_step);
    ApplyStep(camera_step, point_step, &candidate);
    const double candidate_cost = Evaluate(candidate, /*linearize=*/false);

    double step_norm_squared = camera_step.squaredNorm();
    for (const Eigen::Vector3d& step : point_step) step_norm_squared += step.squaredNorm();
    const double x_norm = ParameterNorm(parameters_);
    if (std::sqrt(step_norm_squared) <=
        options_.parameter_tolerance * (x_norm + options_.parameter_tolerance)) {
      termination << "CONVERGENCE: parameter tolerance reached";
      break;
    }
    const double cost_change = cost - candidate_cost;
    if (std::isfinite(candidate_cost) &&
        std::abs(cost_change) <= options_.function_tolerance * cost) {
      termination << "CONVERGENCE: function tolerance reached (|cost change|/cost "
                  << std::abs(cost_change) / cost << ")";
      break;
    }
    const double relative_decrease = cost_change / model_cost_change;
    if (std::isfinite(candidate_cost) && model_cost_change > 0 &&
        relative_decrease > kMinRelativeDecrease) {
      const double camera_move =
          options_.camera_step_tolerance > 0 ? LargestCameraMove(camera_step) : 0.0;
      // A swap, not a move: the next ApplyStep then copies into storage it already has.
      std::swap(parameters_, candidate);
      cost = Evaluate(parameters_, /*linearize=*/true);
      radius =
          std::min(kMaxRadius,
                   radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * relative_decrease - 1.0, 3)));
      decrease_factor = 2.0;
      if (gradient_max_norm() <= options_.gradient_tolerance) {
        termination << "CONVERGENCE: gradient tolerance reached";
      } else if (options_.camera_step_tolerance > 0 &&
                 camera_move <= options_.camera_step_tolerance) {
        termination << "CONVERGENCE: camera step tolerance reached (largest move " << camera_move
                    << ")";
      }
    } else {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < kMinRadius) termination << "CONVERGENCE: minimum trust region radius reached";
    }
    if (options_.print_summary) {
      PARALLAX_LOG(Debug) << summary.solver << ": step " << num_steps << " cost " << cost
                          << " radius " << radius;
    }
  }
  CopyOut();
  summary.final_cost = cost;
  summary.num_iterations = num_steps;
  summary.termination = termination.str();
  summary.num_linear_iterations = num_linear_iterations_;
  return summary;
}

}  // namespace

size_t NumReducedCameraVariables(const BundleAdjustmentProblem& problem) {
  size_t n = 0;
  for (const auto& pose : problem.poses) {
    if (pose.IsVariable()) n += 6;
  }
  for (const auto& block : problem.cameras) {
    if (block.IsVariable()) n += block.free_params.size();
  }
  return n;
}

namespace {

template <typename ReducedMatrix>
BundleAdjustmentSummary SolveWithSchur(const BundleAdjustmentOptions& options,
                                       const ceres::LossFunction* loss,
                                       BundleAdjustmentProblem* problem) {
  PARALLAX_CHECK(problem != nullptr);
  SchurSolver<ReducedMatrix> solver(options, loss, problem);
  return solver.Solve();
}

}  // namespace

BundleAdjustmentSummary SolveWithDenseSchur(const BundleAdjustmentOptions& options,
                                            const ceres::LossFunction* loss,
                                            BundleAdjustmentProblem* problem) {
  return SolveWithSchur<DenseReducedMatrix>(options, loss, problem);
}

BundleAdjustmentSummary SolveWithSparseSchur(const BundleAdjustmentOptions& options,
                                             const ceres::LossFunction* loss,
                                             BundleAdjustmentProblem* problem) {
  return SolveWithSchur<BlockSparseReducedMatrix>(options, loss, problem);
}

}  // namespace parallax
