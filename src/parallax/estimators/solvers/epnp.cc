#include "parallax/estimators/solvers/epnp.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <type_traits>

#include "parallax/estimators/solvers/pose_levenberg_marquardt.h"
#include "parallax/math/dense_decompositions.h"
#include "parallax/math/eigen_types.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kMinDepth = std::numeric_limits<double>::epsilon();

// Sum of squared reprojection errors (normalised coordinates) of the points in front of the
// camera, and how many there are.
double ReprojectionCost(const std::vector<Vector2d>& points2D,
                        const std::vector<Vector3d>& points3D, const Matrix3d& rotation,
                        const Vector3d& translation, size_t* num_in_front) {
  double cost = 0;
  *num_in_front = 0;
  for (size_t i = 0; i < points2D.size(); ++i) {
    const Vector3d point_in_cam = rotation * points3D[i] + translation;
    if (!(point_in_cam.z() > kMinDepth)) continue;
    cost += (point_in_cam.hnormalized() - points2D[i]).squaredNorm();
    ++*num_in_front;
  }
  return cost;
}

// Least-squares rigid alignment cam = R world + t (Kabsch; Umeyama without scale).
bool AlignRigid(const std::vector<Vector3d>& points_in_world,
                const std::vector<Vector3d>& points_in_cam, Matrix3d* rotation,
                Vector3d* translation) {
  const size_t num_points = points_in_world.size();
  Vector3d world_mean = Vector3d::Zero(), cam_mean = Vector3d::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    world_mean += points_in_world[i];
    cam_mean += points_in_cam[i];
  }
  world_mean /= static_cast<double>(num_points);
  cam_mean /= static_cast<double>(num_points);
  Matrix3d cross_covariance = Matrix3d::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    cross_covariance.noalias() +=
        (points_in_cam[i] - cam_mean) * (points_in_world[i] - world_mean).transpose();
  }
  const Eigen::JacobiSVD<Matrix3d> svd(cross_covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Vector3d signs = Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) signs(2) = -1;
  *rotation = svd.matrixU() * signs.asDiagonal() * svd.matrixV().transpose();
  *translation = cam_mean - *rotation * world_mean;
  return rotation->allFinite() && translation->allFinite();
}

// Column of the beta product beta_a beta_b (a <= b) in the distance system, in the paper's
// order [b11 b12 b22 b13 b23 b33 b14 b24 b34 b44].
constexpr int ProductIndex(int a, int b) { return b * (b + 1) / 2 + a; }

// EPnP with `kNumControlPoints` control points: 4 in general, 3 for planar scenes (whose
// barycentric coordinates then ignore the out-of-plane offset). `axes` are the principal axes
// of the centred world points (columns, by decreasing spread) and `sigmas` their spreads.
template <int kNumControlPoints>
bool SolveWithControlPoints(const std::vector<Vector2d>& points2D,
                            const std::vector<Vector3d>& points3D, const Vector3d& centroid,
                            const Matrix3d& axes, const Vector3d& sigmas, Matrix3d* best_rotation,
                            Vector3d* best_translation) {
  constexpr int K = kNumControlPoints;
  constexpr int kDim = 3 * K;
  constexpr int kNumPairs = K * (K - 1) / 2;
  constexpr int kNumBetas = K == 4 ? 4 : 3;
  constexpr int kNumProducts = kNumBetas * (kNumBetas + 1) / 2;
  using Alphas = Eigen::Matrix<double, K, 1>;
  using Betas = Eigen::Matrix<double, kNumBetas, 1>;
  using RowVector = Eigen::Matrix<double, kDim, 1>;
  const size_t num_points = points2D.size();

  std::array<Vector3d, K> control_in_world;
  control_in_world[0] = centroid;
  for (int k = 1; k < K; ++k) control_in_world[k] = centroid + sigmas(k - 1) * axes.col(k - 1);

  // Barycentric coordinates: X = sum_k alpha_k c_k with sum_k alpha_k = 1.
  std::vector<Alphas> alphas(num_points);
  Eigen::Matrix<double, kDim, kDim> MtM = Eigen::Matrix<double, kDim, kDim>::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    const Vector3d offset = points3D[i] - centroid;
    Alphas& alpha = alphas[i];
    for (int k = 1; k < K; ++k) alpha(k) = axes.col(k - 1).dot(offset) / sigmas(k - 1);
    alpha(0) = 1 - alpha.template tail<K - 1>().sum();
    // Two rows of M per point: sum_k alpha_k (c_k.x - u c_k.z) = 0 and likewise for v.
    RowVector row_u, row_v;
    for (int k = 0; k < K; ++k) {
      row_u.template segment<3>(3 * k) << alpha(k), 0, -alpha(k) * points2D[i].x();
      row_v.template segment<3>(3 * k) << 0, alpha(k), -alpha(k) * points2D[i].y();
    }
    MtM.noalias() += row_u * row_u.transpose() + row_v * row_v.transpose();
  }

  // The small systems here go through dynamic-size decompositions (dense_decompositions.h) on
  // purpose: a fixed-size QR per shape and an eigensolver per control-point count made this
  // file slow to compile, for no measurable gain in a solver that runs once per LO-RANSAC
  // refinement (docs/building.md, "Compile time").
  Eigen::VectorXd eigenvalues;
  Eigen::MatrixXd eigenvectors;
  if (!SymmetricEigenSystem(MtM, &eigenvalues, &eigenvectors)) return false;
  // Null-space basis: the eigenvectors of the smallest eigenvalues (ascending order).
  const Eigen::Matrix<double, kDim, kNumBetas> kernel = eigenvectors.template leftCols<kNumBetas>();

  // Distance constraints |c^cam_p - c^cam_q|^2 = |c^world_p - c^world_q|^2 as L b = rho, b the
  // vector of beta products.
  Eigen::Matrix<double, kNumPairs, kNumProducts> L;
  Eigen::Matrix<double, kNumPairs, 1> rho;
  {
    int row = 0;
    for (int p = 0; p < K; ++p) {
      for (int q = p + 1; q < K; ++q, ++row) {
        std::array<Vector3d, kNumBetas> dv;
        for (int a = 0; a < kNumBetas; ++a) {
          dv[a] =
              kernel.col(a).template segment<3>(3 * p) - kernel.col(a).template segment<3>(3 * q);
        }
        for (int b = 0; b < kNumBetas; ++b) {
          for (int a = 0; a <= b; ++a) {
            L(row, ProductIndex(a, b)) = (a == b ? 1.0 : 2.0) * dv[a].dot(dv[b]);
          }
        }
        rho(row) = (control_in_world[p] - control_in_world[q]).squaredNorm();
      }
    }
  }

  // Linearised initial betas for 1 to 4 kernel vectors.
  std::array<Betas, 4> initial_betas;
  int num_initial = 0;
  auto signed_sqrt = [](double value) { return std::sqrt(std::abs(value)); };
  auto solve_columns = [&](const auto& columns) {
    constexpr int kNumColumns = std::tuple_size_v<std::decay_t<decltype(columns)>>;
    Eigen::Matrix<double, kNumPairs, kNumColumns> L_sub;
    for (int c = 0; c < kNumColumns; ++c) L_sub.col(c) = L.col(columns[c]);
    return Eigen::Matrix<double, kNumColumns, 1>(SolveLeastSquares(L_sub, rho));
  };
  {
    // N = 1: |beta| |dv| = |dc| in the least-squares sense.
    const Eigen::Matrix<double, kNumPairs, 1> lengths = L.col(0).cwiseSqrt();
    Betas betas = Betas::Zero();
    betas(0) = lengths.dot(rho.cwiseSqrt()) / lengths.squaredNorm();
    initial_betas[num_initial++] = betas;
  }
  {
    // N = 2: [b11 b12 b22].
    const auto x = solve_columns(std::array<int, 3>{0, 1, 2});
    Betas betas = Betas::Zero();
    betas(0) = signed_sqrt(x(0));
    betas(1) = std::copysign(signed_sqrt(x(2)), x(1));
    initial_betas[num_initial++] = betas;
  }
  if constexpr (K == 4) {
    // N = 3: [b11 b12 b22 b13 b23 b33], six equations for six products.
    const auto x = solve_columns(std::array<int, 6>{0, 1, 2, 3, 4, 5});
    Betas betas = Betas::Zero();
    betas(0) = signed_sqrt(x(0));
    betas(1) = std::copysign(signed_sqrt(x(2)), x(1));
    betas(2) = std::copysign(signed_sqrt(x(5)), x(3));
    initial_betas[num_initial++] = betas;
  }
  {
    // N = kNumBetas (4, or 3 when planar): only the products with beta_1.
    Betas betas = Betas::Zero();
    if constexpr (K == 4) {
      const auto x = solve_columns(std::array<int, 4>{0, 1, 3, 6});
      betas(0) = signed_sqrt(x(0));
      if (betas(0) > 0) betas.template tail<3>() = x.template tail<3>() / betas(0);
    } else {
      const auto x = solve_columns(std::array<int, 3>{0, 1, 3});
      betas(0) = signed_sqrt(x(0));
      if (betas(0) > 0) betas.template tail<2>() = x.template tail<2>() / betas(0);
    }
    initial_betas[num_initial++] = betas;
  }

  auto distance_residuals = [&](const Betas& betas) {
    Eigen::Matrix<double, kNumProducts, 1> products;
    for (int b = 0; b < kNumBetas; ++b) {
      for (int a = 0; a <= b; ++a) products(ProductIndex(a, b)) = betas(a) * betas(b);
    }
    return Eigen::Matrix<double, kNumPairs, 1>(L * products - rho);
  };

  std::vector<Vector3d> points_in_cam(num_points);
  double best_cost = std::numeric_limits<double>::max();
  for (int candidate = 0; candidate < num_initial; ++candidate) {
    Betas betas = initial_betas[candidate];
    if (!betas.allFinite()) continue;
    // Gauss-Newton on the distance constraints over all kernel vectors.
    Eigen::Matrix<double, kNumPairs, 1> residuals = distance_residuals(betas);
    for (int iteration = 0; iteration < 5; ++iteration) {
      Eigen::Matrix<double, kNumPairs, kNumBetas> jacobian =
          Eigen::Matrix<double, kNumPairs, kNumBetas>::Zero();
      for (int b = 0; b < kNumBetas; ++b) {
        for (int a = 0; a <= b; ++a) {
          jacobian.col(a) += L.col(ProductIndex(a, b)) * betas(b);
          jacobian.col(b) += L.col(ProductIndex(a, b)) * betas(a);
        }
      }
      const Betas step = SolveLeastSquares(jacobian, -residuals);
      if (!step.allFinite()) break;
      const Betas updated = betas + step;
      const Eigen::Matrix<double, kNumPairs, 1> updated_residuals = distance_residuals(updated);
      if (!(updated_residuals.squaredNorm() < residuals.squaredNorm())) break;
      betas = updated;
      residuals = updated_residuals;
    }

    // Camera-frame control points, then points; the sign of the null vector is free.
    RowVector control_in_cam = kernel * betas;
    double depth_sum = 0;
    for (size_t i = 0; i < num_points; ++i) {
      Vector3d point = Vector3d::Zero();
      for (int k = 0; k < K; ++k) point += alphas[i](k) * control_in_cam.template segment<3>(3 * k);
      points_in_cam[i] = point;
      depth_sum += point.z();
    }
    if (depth_sum < 0) {
      for (Vector3d& point : points_in_cam) point = -point;
    }

    // For planar control points the cloud's out-of-plane offsets are not represented; align
    // with the points as the barycentric coordinates see them.
    Matrix3d rotation;
    Vector3d translation;
    if constexpr (K == 3) {
      std::vector<Vector3d> projected_world(num_points);
      for (size_t i = 0; i < num_points; ++i) {
        projected_world[i] = alphas[i](0) * control_in_world[0] +
                             alphas[i](1) * control_in_world[1] +
                             alphas[i](2) * control_in_world[2];
      }
      if (!AlignRigid(projected_world, points_in_cam, &rotation, &translation)) continue;
    } else {
      if (!AlignRigid(points3D, points_in_cam, &rotation, &translation)) continue;
    }
    size_t num_in_front = 0;
    const double cost = ReprojectionCost(points2D, points3D, rotation, translation, &num_in_front);
    // Prefer poses that see more points in front, then lower error.
    const double penalised_cost = cost + static_cast<double>(num_points - num_in_front) * 1e6;
    if (std::isfinite(penalised_cost) && penalised_cost < best_cost) {
      best_cost = penalised_cost;
      *best_rotation = rotation;
      *best_translation = translation;
    }
  }
  return best_cost < std::numeric_limits<double>::max();
}

}  // namespace

bool RefineAbsolutePoseLeastSquares(const std::vector<Eigen::Vector2d>& points2D,
                                    const std::vector<Eigen::Vector3d>& points3D,
                                    Rigid3d* cam_from_world, int max_num_iterations) {
  PARALLAX_CHECK_EQ(points2D.size(), points3D.size());
  Matrix3d rotation = cam_from_world->rotation.normalized().toRotationMatrix();
  Vector3d translation = cam_from_world->translation;
  // Residuals pi(R X + t) - x on the normalised plane; the cost as ReprojectionCost sums it.
  const auto observe = [&](size_t i, const Vector3d& point_in_cam, Vector2d* residual,
                           Eigen::Matrix<double, 2, 3>* jacobian) {
    if (!(point_in_cam.z() > kMinDepth)) return false;
    if (jacobian == nullptr) {
      *residual = point_in_cam.hnormalized() - points2D[i];
      return true;
    }
    const double inverse_depth = 1 / point_in_cam.z();
    const double u = point_in_cam.x() * inverse_depth, v = point_in_cam.y() * inverse_depth;
    *residual = Vector2d(u - points2D[i].x(), v - points2D[i].y());
    *jacobian << inverse_depth, 0, -u * inverse_depth, 0, inverse_depth, -v * inverse_depth;
    return true;
  };
  struct SquaredLoss {
    double Cost(double squared_norm) const { return squared_norm; }
    double Weight(double) const { return 1; }
  };
  PoseLevenbergMarquardtOptions options;
  options.max_num_iterations = max_num_iterations;
  if (!MinimizeOverPose(points3D, observe, SquaredLoss(), options, &rotation, &translation)) {
    return false;
  }
  cam_from_world->rotation = Eigen::Quaterniond(rotation).normalized();
  cam_from_world->translation = translation;
  return true;
}

void SolveEPnP(const std::vector<Eigen::Vector2d>& points2D,
               const std::vector<Eigen::Vector3d>& points3D,
               std::vector<Rigid3d>* cams_from_world) {
  PARALLAX_CHECK_EQ(points2D.size(), points3D.size());
  cams_from_world->clear();
  const size_t num_points = points2D.size();
  if (num_points < 4) return;

  Vector3d centroid = Vector3d::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    if (!points2D[i].allFinite() || !points3D[i].allFinite()) return;
    centroid += points3D[i];
  }
  centroid /= static_cast<double>(num_points);
  Matrix3d covariance = Matrix3d::Zero();
  for (const Vector3d& point : points3D) {
    covariance.noalias() += (point - centroid) * (point - centroid).transpose();
  }
  covariance /= static_cast<double>(num_points);
  const Eigen::SelfAdjointEigenSolver<Matrix3d> eigen(covariance);
  // Principal axes by decreasing variance.
  Matrix3d axes;
  Vector3d variances;
  for (int k = 0; k < 3; ++k) {
    axes.col(k) = eigen.eigenvectors().col(2 - k);
    variances(k) = eigen.eigenvalues()(2 - k);
  }
  if (!(variances(0) > 0) || !(variances(1) > 1e-12 * variances(0))) return;  // Collinear.
  const Vector3d sigmas = variances.cwiseMax(0).cwiseSqrt();

  // Thin clouds are solved both ways (general and planar), the better one kept.
  const double flatness = variances(2) / variances(0);
  Rigid3d best_pose;
  double best_cost = std::numeric_limits<double>::max();
  auto consider = [&](const Matrix3d& rotation, const Vector3d& translation) {
    Rigid3d pose(Eigen::Quaterniond(rotation).normalized(), translation);
    if (!RefineAbsolutePoseLeastSquares(points2D, points3D, &pose)) return;
    size_t num_in_front = 0;
    const double cost = ReprojectionCost(points2D, points3D, pose.rotation.toRotationMatrix(),
                                         pose.translation, &num_in_front) +
                        static_cast<double>(num_points - num_in_front) * 1e6;
    if (std::isfinite(cost) && cost < best_cost) {
      best_cost = cost;
      best_pose = pose;
    }
  };
  Matrix3d rotation;
  Vector3d translation;
  if (flatness > 1e-10 && SolveWithControlPoints<4>(points2D, points3D, centroid, axes, sigmas,
                                                    &rotation, &translation)) {
    consider(rotation, translation);
  }
  if (flatness < 1e-4 && SolveWithControlPoints<3>(points2D, points3D, centroid, axes, sigmas,
                                                   &rotation, &translation)) {
    consider(rotation, translation);
  }
  // With 4 or 5 points the null space has 4 or 2 dimensions and the linearised betas can
  // land in a wrong basin; minimal solutions on the triplets settle it at negligible cost.
  if (num_points <= 5) {
    std::vector<Rigid3d> minimal_poses;
    for (size_t i = 0; i < num_points; ++i) {
      for (size_t j = i + 1; j < num_points; ++j) {
        for (size_t k = j + 1; k < num_points; ++k) {
          SolveP3P(
              {points2D[i].homogeneous(), points2D[j].homogeneous(), points2D[k].homogeneous()},
              {points3D[i], points3D[j], points3D[k]}, &minimal_poses);
          for (const Rigid3d& pose : minimal_poses) {
            consider(pose.rotation.toRotationMatrix(), pose.translation);
          }
        }
      }
    }
  }
  if (best_cost < std::numeric_limits<double>::max()) cams_from_world->push_back(best_pose);
}

}  // namespace parallax
