#include "parallax/estimators/solvers/homography_matrix.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/estimators/solvers/null_space.h"
#include "parallax/math/dense_decompositions.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr double kMinRankRatio = 1e-10;
// Least squares on at least this many points solves the normal equations (see
// NullSpaceFromNormalMatrix), with its rank test on eigenvalues.
constexpr size_t kMinNumPointsForNormalEquations = 16;
constexpr double kMinEigenvalueRatio = 1e-14;

using RowMajorMatrix3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

inline Eigen::Vector2d ApplyNormalization(const Eigen::Matrix3d& T, const Eigen::Vector2d& point) {
  return Eigen::Vector2d(T(0, 0) * point.x() + T(0, 2), T(1, 1) * point.y() + T(1, 2));
}

// The two independent rows of x2 x (H x1) = 0 in the row-major entries of H.
template <typename Rows>
inline void AddHomographyRows(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, Rows&& rows) {
  const Eigen::Vector3d x = x1.homogeneous();
  rows.row(0) << Eigen::RowVector3d::Zero(), -x.transpose(), x2.y() * x.transpose();
  rows.row(1) << x.transpose(), Eigen::RowVector3d::Zero(), -x2.x() * x.transpose();
}

// Inverse of a normalisation [s 0 -s cx; 0 s -s cy; 0 0 1].
inline Eigen::Matrix3d InverseNormalization(const Eigen::Matrix3d& T) {
  Eigen::Matrix3d inverse;
  inverse << 1.0 / T(0, 0), 0, -T(0, 2) / T(0, 0), 0, 1.0 / T(1, 1), -T(1, 2) / T(1, 1), 0, 0, 1;
  return inverse;
}

}  // namespace

void EstimateHomographyMatrix(const std::vector<Eigen::Vector2d>& points1,
                              const std::vector<Eigen::Vector2d>& points2,
                              std::vector<Eigen::Matrix3d>* models) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  models->clear();
  const size_t num_points = points1.size();
  if (num_points < 4) return;
  Eigen::Matrix3d T1, T2;
  if (!ComputeHartleyNormalization(points1, &T1) || !ComputeHartleyNormalization(points2, &T2)) {
    return;
  }

  Vector9d h;
  if (num_points == 4) {
    // Minimal case: elimination exposes a rank below 8 in its last pivot.
    Eigen::Matrix<double, 8, 9> A;
    for (int i = 0; i < 4; ++i) {
      AddHomographyRows(ApplyNormalization(T1, points1[i]), ApplyNormalization(T2, points2[i]),
                        A.middleRows<2>(2 * i));
    }
    Eigen::Matrix<double, 9, 1> null_vector;
    if (!NullSpaceByElimination(A, &null_vector, kMinRankRatio)) return;
    h = null_vector;
  } else {
    Eigen::Matrix<double, Eigen::Dynamic, 9> A(static_cast<Eigen::Index>(2 * num_points), 9);
    for (size_t i = 0; i < num_points; ++i) {
      AddHomographyRows(ApplyNormalization(T1, points1[i]), ApplyNormalization(T2, points2[i]),
                        A.middleRows<2>(static_cast<Eigen::Index>(2 * i)));
    }
    if (num_points >= kMinNumPointsForNormalEquations) {
      if (!NullSpaceFromNormalMatrix<1>(NormalMatrix(A), &h, kMinEigenvalueRatio)) return;
    } else {
      Eigen::VectorXd singular_values;
      Eigen::MatrixXd V;
      RightSingularSystem(A, &singular_values, &V);
      if (!(singular_values(7) > kMinRankRatio * singular_values(0))) return;
      h = V.col(8);
    }
  }

  const Eigen::Matrix3d normalized_H = Eigen::Map<const RowMajorMatrix3d>(h.data());
  if (num_points == 4) {
    // A homography induced by a plane keeps every visible point in front: the third
    // coordinates of H x1 share one sign (oriented constraint; a sign flip means a bad sample).
    int num_positive = 0;
    for (int i = 0; i < 4; ++i) {
      num_positive +=
          (normalized_H.row(2).dot(ApplyNormalization(T1, points1[i]).homogeneous()) > 0);
    }
    if (num_positive != 0 && num_positive != 4) return;
  }
  Eigen::Matrix3d H = InverseNormalization(T2) * normalized_H * T1;
  const double norm = H.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return;
  H /= norm;
  if (H(2, 2) < 0) H = -H;
  models->push_back(H);
}

}  // namespace parallax
