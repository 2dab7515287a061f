#include "parallax/estimators/solvers/fundamental_matrix.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "parallax/estimators/solvers/null_space.h"
#include "parallax/math/dense_decompositions.h"
#include "parallax/math/polynomial.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// A singular value (or pivot) below this fraction of the largest one is zero: the system has
// a larger null space than the solver expects (degenerate configuration). Noise puts real
// samples many orders of magnitude above it.
constexpr double kMinRankRatio = 1e-10;

// Least squares on at least this many points solves the normal equations (see
// NullSpaceFromNormalMatrix); its rank test is on eigenvalues, the squares of singular values,
// above the ~1e-16 rounding floor.
constexpr Eigen::Index kMinNumPointsForNormalEquations = 16;
constexpr double kMinEigenvalueRatio = 1e-14;

using RowMajorMatrix3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

inline Eigen::Vector2d ApplyNormalization(const Eigen::Matrix3d& T, const Eigen::Vector2d& point) {
  return Eigen::Vector2d(T(0, 0) * point.x() + T(0, 2), T(1, 1) * point.y() + T(1, 2));
}

// Coefficients of x2^T M x1 = 0 in the row-major entries of M.
inline Vector9d EpipolarRow(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2) {
  Vector9d row;
  row << x2.x() * x1.x(), x2.x() * x1.y(), x2.x(), x2.y() * x1.x(), x2.y() * x1.y(), x2.y(), x1.x(),
      x1.y(), 1.0;
  return row;
}

inline Eigen::Matrix3d MatrixFromRowMajor(const Vector9d& entries) {
  return Eigen::Map<const RowMajorMatrix3d>(entries.data());
}

Eigen::Matrix3d Adjugate(const Eigen::Matrix3d& M) {
  Eigen::Matrix3d adjugate;
  adjugate.row(0) = M.col(1).cross(M.col(2)).transpose();
  adjugate.row(1) = M.col(2).cross(M.col(0)).transpose();
  adjugate.row(2) = M.col(0).cross(M.col(1)).transpose();
  return adjugate;
}

// Least-squares null space (the last `num_null` right singular vectors) of the N x 9 system;
// false when its rank is below 9 - num_null. Zero rows pad N < 9 so that V is always 9 x 9.
template <int kNumNull>
bool LeastSquaresNullSpace(const std::vector<Eigen::Vector2d>& points1,
                           const std::vector<Eigen::Vector2d>& points2, const Eigen::Matrix3d& T1,
                           const Eigen::Matrix3d& T2,
                           Eigen::Matrix<double, 9, kNumNull>* null_space) {
  const Eigen::Index num_points = static_cast<Eigen::Index>(points1.size());
  if (num_points >= kMinNumPointsForNormalEquations) {
    Eigen::Matrix<double, Eigen::Dynamic, 9> A(num_points, 9);
    for (Eigen::Index i = 0; i < num_points; ++i) {
      A.row(i) = EpipolarRow(ApplyNormalization(T1, points1[i]), ApplyNormalization(T2, points2[i]))
                     .transpose();
    }
    return NullSpaceFromNormalMatrix<kNumNull>(NormalMatrix(A), null_space, kMinEigenvalueRatio);
  }
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(std::max<Eigen::Index>(num_points, 9), 9);
  for (Eigen::Index i = 0; i < num_points; ++i) {
    A.row(i) = EpipolarRow(ApplyNormalization(T1, points1[i]), ApplyNormalization(T2, points2[i]))
                   .transpose();
  }
  Eigen::VectorXd singular_values;
  Eigen::MatrixXd V;
  RightSingularSystem(A, &singular_values, &V);
  constexpr int kRank = 9 - kNumNull;
  if (!(singular_values(kRank - 1) > kMinRankRatio * singular_values(0))) return false;
  *null_space = V.template rightCols<kNumNull>();
  return true;
}

}  // namespace

bool ComputeHartleyNormalization(const std::vector<Eigen::Vector2d>& points,
                                 Eigen::Matrix3d* normalization) {
  if (points.empty()) return false;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& point : points) centroid += point;
  centroid /= static_cast<double>(points.size());
  double mean_distance = 0.0;
  for (const Eigen::Vector2d& point : points) mean_distance += (point - centroid).norm();
  mean_distance /= static_cast<double>(points.size());
  // Also false for NaN/Inf input, which propagates into both sums.
  if (!centroid.allFinite() || !std::isfinite(mean_distance) ||
      !(mean_distance > 1e-12 * std::max(1.0, centroid.lpNorm<Eigen::Infinity>()))) {
    return false;
  }
  const double scale = std::sqrt(2.0) / mean_distance;
  *normalization << scale, 0, -scale * centroid.x(), 0, scale, -scale * centroid.y(), 0, 0, 1;
  return true;
}

bool SolveNormalizedEpipolarSystem(const std::vector<Eigen::Vector2d>& points1,
                                   const std::vector<Eigen::Vector2d>& points2,
                                   Eigen::Matrix3d* normalized_model,
                                   Eigen::Matrix3d* normalization1,
                                   Eigen::Matrix3d* normalization2) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  if (points1.size() < 8) return false;
  if (!ComputeHartleyNormalization(points1, normalization1) ||
      !ComputeHartleyNormalization(points2, normalization2)) {
    return false;
  }
  Eigen::Matrix<double, 9, 1> null_vector = Eigen::Matrix<double, 9, 1>::Zero();
  if (!LeastSquaresNullSpace<1>(points1, points2, *normalization1, *normalization2, &null_vector)) {
    return false;
  }
  *normalized_model = MatrixFromRowMajor(null_vector);
  return normalized_model->allFinite();
}

void EstimateFundamentalMatrixSevenPoint(const std::vector<Eigen::Vector2d>& points1,
                                         const std::vector<Eigen::Vector2d>& points2,
                                         std::vector<Eigen::Matrix3d>* models) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  models->clear();
  const size_t num_points = points1.size();
  if (num_points < 7) return;
  Eigen::Matrix3d T1, T2;
  if (!ComputeHartleyNormalization(points1, &T1) || !ComputeHartleyNormalization(points2, &T2)) {
    return;
  }

  Eigen::Matrix<double, 9, 2> null_space;
  if (num_points == 7) {
    // Minimal case: elimination exposes a rank below 7 in its last pivot.
    Eigen::Matrix<double, 7, 9> A;
    for (int i = 0; i < 7; ++i) {
      A.row(i) = EpipolarRow(ApplyNormalization(T1, points1[i]), ApplyNormalization(T2, points2[i]))
                     .transpose();
    }
    if (!NullSpaceByElimination(A, &null_space, kMinRankRatio)) return;
  } else if (!LeastSquaresNullSpace<2>(points1, points2, T1, T2, &null_space)) {
    return;
  }

  // det(a F1 + (1 - a) F2) = det(A + a B) with A = F2, B = F1 - F2, expanded as
  // det(A) + a tr(adj(A) B) + a^2 tr(A adj(B)) + a^3 det(B).
  const Eigen::Matrix3d F1 = MatrixFromRowMajor(null_space.col(0));
  const Eigen::Matrix3d F2 = MatrixFromRowMajor(null_space.col(1));
  const Eigen::Matrix3d A = F2;
  const Eigen::Matrix3d B = F1 - F2;
  const double c3 = B.determinant();
  const double c2 = (A * Adjugate(B)).trace();
  const double c1 = (Adjugate(A) * B).trace();
  const double c0 = A.determinant();
  const double max_coeff = std::max({std::abs(c3), std::abs(c2), std::abs(c1), std::abs(c0)});
  if (!(max_coeff > 0.0) || !std::isfinite(max_coeff)) return;

  double roots[3];
  int num_roots = 0;
  Eigen::Matrix3d normalized_models[4];
  int num_models = 0;
  if (std::abs(c3) > 1e-12 * max_coeff) {
    num_roots = SolveCubicReal(c3, c2, c1, c0, roots);
  } else {
    // det(B) = 0: B itself (a -> infinity) is a solution and the rest is a quadratic.
    normalized_models[num_models++] = B;
    num_roots = SolveQuadraticReal(c2, c1, c0, roots);
  }
  for (int i = 0; i < num_roots; ++i) normalized_models[num_models++] = A + roots[i] * B;

  for (int i = 0; i < num_models; ++i) {
    Eigen::Matrix3d F = T2.transpose() * normalized_models[i] * T1;
    const double norm = F.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) continue;
    F /= norm;
    models->push_back(F);
  }
}

void EstimateFundamentalMatrixEightPoint(const std::vector<Eigen::Vector2d>& points1,
                                         const std::vector<Eigen::Vector2d>& points2,
                                         std::vector<Eigen::Matrix3d>* models) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  models->clear();
  Eigen::Matrix3d normalized_F, T1, T2;
  if (!SolveNormalizedEpipolarSystem(points1, points2, &normalized_F, &T1, &T2)) return;
  // Closest rank-2 matrix in the Frobenius norm, enforced where the entries are balanced.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(normalized_F,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d singular_values = svd.singularValues();
  singular_values(2) = 0.0;
  normalized_F = svd.matrixU() * singular_values.asDiagonal() * svd.matrixV().transpose();
  Eigen::Matrix3d F = T2.transpose() * normalized_F * T1;
  const double norm = F.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return;
  models->push_back(F / norm);
}

}  // namespace parallax
