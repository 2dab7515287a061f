#include "parallax/geometry/triangulation.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "parallax/util/check.h"

namespace parallax {
namespace {

// Below this ratio of the two smallest nonzero eigenvalues of A^T A (squared singular values)
// the system has a two-dimensional null space (the rays coincide, e.g. identical cameras, or
// meet at under ~1e-7 rad): the point is undetermined. Eigenvalues carry an absolute error of
// about 1e-16 of the largest, so the bound sits above that.
constexpr double kMinRankRatio = 1e-14;
constexpr double kMinHomogeneousScale = 1e-12;

// The two independent rows of [x]_x P X = 0 for one view (the third is their combination).
inline void AddCrossProductRows(const Matrix3x4d& cam_from_world, const Eigen::Vector2d& point,
                                Eigen::Matrix<double, 2, 4>* rows) {
  rows->row(0) = point.x() * cam_from_world.row(2) - cam_from_world.row(0);
  rows->row(1) = point.y() * cam_from_world.row(2) - cam_from_world.row(1);
}

// The null vector of a 4x4 system A, dehomogenised; nullopt when degenerate. The right
// singular vectors of A are the eigenvectors of A^T A, whose symmetric 4x4 eigensolver is
// about twice as fast as a Jacobi SVD; squaring the condition number costs nothing here,
// where the smallest eigenvalue is zero for exact data and the gap above it is the squared
// sine of the triangulation angle.
std::optional<Eigen::Vector3d> SolveHomogeneous(const Eigen::Matrix4d& A) {
  if (!A.allFinite()) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> solver(A.transpose() * A);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Eigen::Vector4d& eigenvalues = solver.eigenvalues();  // Ascending.
  if (!(eigenvalues(1) > kMinRankRatio * eigenvalues(3))) return std::nullopt;
  const Eigen::Vector4d X = solver.eigenvectors().col(0);
  // A point at (or numerically at) infinity has no Euclidean position: parallel rays leave
  // X(3) at rounding level, i.e. a point ~1e12 units away.
  if (std::abs(X(3)) <= kMinHomogeneousScale * X.head<3>().norm()) {
    return std::nullopt;
  }
  const Eigen::Vector3d point3D = X.head<3>() / X(3);
  if (!point3D.allFinite()) return std::nullopt;
  return point3D;
}

}  // namespace

std::optional<Eigen::Vector3d> TriangulatePoint(const Matrix3x4d& cam1_from_world,
                                                const Matrix3x4d& cam2_from_world,
                                                const Eigen::Vector2d& point1,
                                                const Eigen::Vector2d& point2) {
  Eigen::Matrix4d A;
  Eigen::Matrix<double, 2, 4> rows;
  AddCrossProductRows(cam1_from_world, point1, &rows);
  A.topRows<2>() = rows;
  AddCrossProductRows(cam2_from_world, point2, &rows);
  A.bottomRows<2>() = rows;
  return SolveHomogeneous(A);
}

std::optional<Eigen::Vector3d> TriangulateMultiViewPoint(
    const std::vector<Matrix3x4d>& cams_from_world, const std::vector<Eigen::Vector2d>& points) {
  PARALLAX_CHECK_EQ(cams_from_world.size(), points.size());
  if (points.size() < 2) return std::nullopt;
  // The stacked 2N x 4 system is reduced view by view to its 4x4 triangular factor R
  // (Householder QR of [R; two new rows]); A and R share their right singular vectors, so
  // the SVD of R is the SVD of the whole system without a heap-allocated 2N x 4 matrix.
  Eigen::Matrix<double, 6, 4> stacked;
  Eigen::Matrix<double, 2, 4> rows;
  AddCrossProductRows(cams_from_world[0], points[0], &rows);
  stacked.topRows<2>() = rows;
  AddCrossProductRows(cams_from_world[1], points[1], &rows);
  stacked.middleRows<2>(2) = rows;
  stacked.bottomRows<2>().setZero();
  Eigen::Matrix4d R = stacked.topRows<4>();
  for (size_t i = 2; i < points.size(); ++i) {
    AddCrossProductRows(cams_from_world[i], points[i], &rows);
    stacked.topRows<4>() = R;
    stacked.bottomRows<2>() = rows;
    const Eigen::HouseholderQR<Eigen::Matrix<double, 6, 4>> qr(stacked);
    R = qr.matrixQR().topRows<4>().triangularView<Eigen::Upper>();
  }
  return SolveHomogeneous(R);
}

double CalculateTriangulationAngle(const Eigen::Vector3d& center1, const Eigen::Vector3d& center2,
                                   const Eigen::Vector3d& point3D) {
  const Eigen::Vector3d ray1 = point3D - center1;
  const Eigen::Vector3d ray2 = point3D - center2;
  // atan2 of |a x b| and a . b stays accurate for tiny and near-pi angles, unlike acos.
  return std::atan2(ray1.cross(ray2).norm(), ray1.dot(ray2));
}

bool HasPointPositiveDepth(const Matrix3x4d& cam_from_world, const Eigen::Vector3d& point3D) {
  return cam_from_world.row(2).dot(point3D.homogeneous()) > std::numeric_limits<double>::epsilon();
}

}  // namespace parallax
