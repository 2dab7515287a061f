#include "parallax/estimators/solvers/dlt_resection.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <limits>

#include "parallax/math/dense_decompositions.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// Below this ratio of smallest to largest principal variance the 3D points count as coplanar
// (a spread ratio of 1e-4): P is then determined only up to a 4-dimensional family.
constexpr double kMinVarianceRatio = 1e-8;
// Below this ratio of the 11th to the largest singular value the null space is not 1-D.
constexpr double kMinSingularValueRatio = 1e-10;

}  // namespace

void SolveDLTResection(const std::vector<Eigen::Vector2d>& points2D,
                       const std::vector<Eigen::Vector3d>& points3D,
                       std::vector<Matrix3x4d>* proj_matrices) {
  PARALLAX_CHECK_EQ(points2D.size(), points3D.size());
  proj_matrices->clear();
  const size_t num_points = points2D.size();
  if (num_points < 6) return;

  Eigen::Vector2d mean2D = Eigen::Vector2d::Zero();
  Eigen::Vector3d mean3D = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    if (!points2D[i].allFinite() || !points3D[i].allFinite()) return;
    mean2D += points2D[i];
    mean3D += points3D[i];
  }
  mean2D /= static_cast<double>(num_points);
  mean3D /= static_cast<double>(num_points);
  double distance2D = 0, distance3D = 0;
  Eigen::Matrix3d covariance3D = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    distance2D += (points2D[i] - mean2D).norm();
    const Eigen::Vector3d centered = points3D[i] - mean3D;
    distance3D += centered.norm();
    covariance3D.noalias() += centered * centered.transpose();
  }
  if (!(distance2D > 0) || !(distance3D > 0)) return;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance3D, Eigen::EigenvaluesOnly);
  if (!(eigen.eigenvalues()(0) > kMinVarianceRatio * eigen.eigenvalues()(2))) return;

  const double scale2D = std::sqrt(2.0) * num_points / distance2D;
  const double scale3D = std::sqrt(3.0) * num_points / distance3D;

  // Rows [X^T 0 -u X^T] and [0 X^T -v X^T] for P stacked row by row.
  Eigen::MatrixXd A(2 * num_points, 12);
  for (size_t i = 0; i < num_points; ++i) {
    const Eigen::Vector4d X = (scale3D * (points3D[i] - mean3D)).homogeneous();
    const Eigen::Vector2d x = scale2D * (points2D[i] - mean2D);
    A.row(2 * i) << X.transpose(), Eigen::RowVector4d::Zero(), -x.x() * X.transpose();
    A.row(2 * i + 1) << Eigen::RowVector4d::Zero(), X.transpose(), -x.y() * X.transpose();
  }
  Eigen::VectorXd singular_values;
  Eigen::MatrixXd V;
  RightSingularSystem(A, &singular_values, &V);
  if (!(singular_values(10) > kMinSingularValueRatio * singular_values(0))) return;
  const Eigen::Matrix<double, 12, 1> p = V.col(11);
  Matrix3x4d normalized_proj;
  normalized_proj << p.segment<4>(0).transpose(), p.segment<4>(4).transpose(),
      p.segment<4>(8).transpose();

  // Undo the normalisations: P = T2^-1 P~ T3.
  Eigen::Matrix3d inverse_transform2D = Eigen::Matrix3d::Identity();
  inverse_transform2D.topLeftCorner<2, 2>() /= scale2D;
  inverse_transform2D.topRightCorner<2, 1>() = mean2D;
  Eigen::Matrix4d transform3D = Eigen::Matrix4d::Identity();
  transform3D.topLeftCorner<3, 3>() *= scale3D;
  transform3D.topRightCorner<3, 1>() = -scale3D * mean3D;
  Matrix3x4d proj_matrix = inverse_transform2D * normalized_proj * transform3D;

  const double row_norm = proj_matrix.block<1, 3>(2, 0).norm();
  const double determinant = proj_matrix.leftCols<3>().determinant();
  if (!(row_norm > 0) || determinant == 0) return;
  proj_matrix /= std::copysign(row_norm, determinant);
  if (!proj_matrix.allFinite()) return;
  proj_matrices->push_back(proj_matrix);
}

bool DecomposeProjectionMatrix(const Matrix3x4d& proj_matrix, Eigen::Matrix3d* K,
                               Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  if (!proj_matrix.allFinite()) return false;
  const Eigen::Matrix3d H = proj_matrix.leftCols<3>();
  Eigen::Vector3d h = proj_matrix.col(3);
  Eigen::Matrix3d H_inverse;
  bool invertible = false;
  // Scale-free test: H up to scale, so compare with the cube of its norm.
  const double norm = H.norm();
  if (!(norm > 0)) return false;
  (H / norm).computeInverseWithCheck(H_inverse, invertible, 1e-12);
  if (!invertible) return false;
  H_inverse /= norm;

  // H^-1 = Q U  =>  H = U^-1 Q^T: K = U^-1 (upper-triangular), R = Q^T.
  const Eigen::HouseholderQR<Eigen::Matrix3d> qr(H_inverse);
  const Eigen::Matrix3d Q = qr.householderQ();
  const Eigen::Matrix3d U = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::Matrix3d calibration = U.inverse();
  Eigen::Matrix3d rotation = Q.transpose();

  // K D D R with D = diag(sign(K_ii)) makes the diagonal of K positive.
  for (int i = 0; i < 3; ++i) {
    if (calibration(i, i) < 0) {
      calibration.col(i) = -calibration.col(i);
      rotation.row(i) = -rotation.row(i);
    }
  }
  // det R = -1 means P was given with a negative scale: decompose -P instead.
  if (rotation.determinant() < 0) {
    rotation = -rotation;
    h = -h;
  }
  *t = calibration.triangularView<Eigen::Upper>().solve(h);
  *K = calibration / calibration(2, 2);
  *R = rotation;
  return K->allFinite() && R->allFinite() && t->allFinite();
}

void ComputeSquaredProjectionErrors(const std::vector<Eigen::Vector2d>& points2D,
                                    const std::vector<Eigen::Vector3d>& points3D,
                                    const Matrix3x4d& proj_matrix,
                                    std::vector<double>* squared_errors) {
  const Eigen::Matrix3d H = proj_matrix.leftCols<3>();
  const Eigen::Vector3d h = proj_matrix.col(3);
  squared_errors->resize(points2D.size());
  for (size_t i = 0; i < points2D.size(); ++i) {
    const Eigen::Vector3d projected = H * points3D[i] + h;
    if (projected.z() > std::numeric_limits<double>::epsilon()) {
      (*squared_errors)[i] = (projected.hnormalized() - points2D[i]).squaredNorm();
    } else {
      (*squared_errors)[i] = std::numeric_limits<double>::max();
    }
  }
}

}  // namespace parallax
