#include "parallax/estimators/solvers/essential_matrix.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>

#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr double kMinRankRatio = 1e-10;
// Eigenvalues of the action matrix with a larger relative imaginary part are complex roots.
constexpr double kMaxImaginaryRatio = 1e-8;

using RowMajorMatrix3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

// Polynomials in (x, y, z) of degree <= 3 as 20 coefficients. The 10 cubic monomials come
// first (they are eliminated), then the quotient basis {x^2, xy, xz, y^2, yz, z^2, x, y, z, 1}.
constexpr int kNumMonomials = 20;
constexpr int kNumCubic = 10;
constexpr int kFirstQuadratic = 10;
constexpr int kFirstLinear = 16;
constexpr int kMonomialX = 16;
using Polynomial = Eigen::Matrix<double, kNumMonomials, 1>;

constexpr int kExponents[kNumMonomials][3] = {
    {3, 0, 0}, {2, 1, 0}, {2, 0, 1}, {1, 2, 0}, {1, 1, 1}, {1, 0, 2}, {0, 3, 0},
    {0, 2, 1}, {0, 1, 2}, {0, 0, 3}, {2, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 2, 0},
    {0, 1, 1}, {0, 0, 2}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}};

struct ProductTable {
  // Index of the product of monomials i and j, -1 when its degree exceeds 3.
  int index[kNumMonomials][kNumMonomials];
};

constexpr ProductTable MakeProductTable() {
  ProductTable table{};
  for (int i = 0; i < kNumMonomials; ++i) {
    for (int j = 0; j < kNumMonomials; ++j) {
      table.index[i][j] = -1;
      for (int k = 0; k < kNumMonomials; ++k) {
        if (kExponents[k][0] == kExponents[i][0] + kExponents[j][0] &&
            kExponents[k][1] == kExponents[i][1] + kExponents[j][1] &&
            kExponents[k][2] == kExponents[i][2] + kExponents[j][2]) {
          table.index[i][j] = k;
        }
      }
    }
  }
  return table;
}
constexpr ProductTable kProduct = MakeProductTable();

// a * b where a has no monomials before `first_a` and b none before `first_b` (their degrees
// must add up to at most 3).
inline Polynomial Multiply(const Polynomial& a, int first_a, const Polynomial& b, int first_b) {
  Polynomial product = Polynomial::Zero();
  for (int i = first_a; i < kNumMonomials; ++i) {
    for (int j = first_b; j < kNumMonomials; ++j) {
      product(kProduct.index[i][j]) += a(i) * b(j);
    }
  }
  return product;
}

inline Vector9d EpipolarRow(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2) {
  Vector9d row;
  row << x2.x() * x1.x(), x2.x() * x1.y(), x2.x(), x2.y() * x1.x(), x2.y() * x1.y(), x2.y(), x1.x(),
      x1.y(), 1.0;
  return row;
}

// Four vectors spanning the null space of the epipolar system (row-major E entries).
bool EssentialNullSpace(const std::vector<Eigen::Vector2d>& points1,
                        const std::vector<Eigen::Vector2d>& points2,
                        Eigen::Matrix<double, 9, 4>* null_space) {
  const size_t num_points = points1.size();
  if (num_points == 5) {
    // Minimal case without the heap: the last four columns of Q in A^T = QR.
    Eigen::Matrix<double, 9, 5> A_transpose;
    for (int i = 0; i < 5; ++i) A_transpose.col(i) = EpipolarRow(points1[i], points2[i]);
    if (!A_transpose.allFinite()) return false;
    const Eigen::ColPivHouseholderQR<Eigen::Matrix<double, 9, 5>> qr(A_transpose);
    const auto& R = qr.matrixR();
    if (!(std::abs(R(4, 4)) > kMinRankRatio * std::abs(R(0, 0)))) return false;
    const Eigen::Matrix<double, 9, 9> Q = qr.householderQ();
    *null_space = Q.rightCols<4>();
    return true;
  }
  Eigen::Matrix<double, Eigen::Dynamic, 9> A = Eigen::Matrix<double, Eigen::Dynamic, 9>::Zero(
      std::max<Eigen::Index>(static_cast<Eigen::Index>(num_points), 9), 9);
  for (size_t i = 0; i < num_points; ++i) {
    A.row(static_cast<Eigen::Index>(i)) = EpipolarRow(points1[i], points2[i]).transpose();
  }
  if (!A.allFinite()) return false;
  const Eigen::JacobiSVD<Eigen::Matrix<double, Eigen::Dynamic, 9>> svd(A, Eigen::ComputeFullV);
  const auto& singular_values = svd.singularValues();
  if (!(singular_values(4) > kMinRankRatio * singular_values(0))) return false;
  *null_space = svd.matrixV().rightCols<4>();
  return true;
}

// The 10 x 20 coefficients of det(E) = 0 and 2 E E^T E - tr(E E^T) E = 0 for
// E = x X + y Y + z Z + W (the four null-space columns, in that order).
Eigen::Matrix<double, 10, kNumMonomials> BuildConstraints(
    const Eigen::Matrix<double, 9, 4>& null_space) {
  Polynomial E[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      E[i][j].setZero();
      for (int k = 0; k < 4; ++k) E[i][j](kFirstLinear + k) = null_space(3 * i + j, k);
    }
  }
  Polynomial E_Et[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      E_Et[i][j] = Multiply(E[i][0], kFirstLinear, E[j][0], kFirstLinear) +
                   Multiply(E[i][1], kFirstLinear, E[j][1], kFirstLinear) +
                   Multiply(E[i][2], kFirstLinear, E[j][2], kFirstLinear);
      E_Et[j][i] = E_Et[i][j];
    }
  }
  const Polynomial trace = E_Et[0][0] + E_Et[1][1] + E_Et[2][2];

  Eigen::Matrix<double, 10, kNumMonomials> constraints;
  // det(E) = row0 . (row1 x row2).
  const Polynomial cross0 = Multiply(E[1][1], kFirstLinear, E[2][2], kFirstLinear) -
                            Multiply(E[1][2], kFirstLinear, E[2][1], kFirstLinear);
  const Polynomial cross1 = Multiply(E[1][2], kFirstLinear, E[2][0], kFirstLinear) -
                            Multiply(E[1][0], kFirstLinear, E[2][2], kFirstLinear);
  const Polynomial cross2 = Multiply(E[1][0], kFirstLinear, E[2][1], kFirstLinear) -
                            Multiply(E[1][1], kFirstLinear, E[2][0], kFirstLinear);
  constraints.row(0) = (Multiply(cross0, kFirstQuadratic, E[0][0], kFirstLinear) +
                        Multiply(cross1, kFirstQuadratic, E[0][1], kFirstLinear) +
                        Multiply(cross2, kFirstQuadratic, E[0][2], kFirstLinear))
                           .transpose();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Polynomial entry = -Multiply(trace, kFirstQuadratic, E[i][j], kFirstLinear);
      for (int k = 0; k < 3; ++k) {
        entry += 2.0 * Multiply(E_Et[i][k], kFirstQuadratic, E[k][j], kFirstLinear);
      }
      constraints.row(1 + 3 * i + j) = entry.transpose();
    }
  }
  return constraints;
}

}  // namespace

void EstimateEssentialMatrixFivePoint(const std::vector<Eigen::Vector2d>& points1,
                                      const std::vector<Eigen::Vector2d>& points2,
                                      std::vector<Eigen::Matrix3d>* models) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  models->clear();
  if (points1.size() < 5) return;
  Eigen::Matrix<double, 9, 4> null_space;
  if (!EssentialNullSpace(points1, points2, &null_space)) return;

  const Eigen::Matrix<double, 10, kNumMonomials> constraints = BuildConstraints(null_space);
  // Gauss-Jordan on the cubic monomials: cubic_k = -sum_j G(k, j) basis_j on the solutions.
  const Eigen::FullPivLU<Eigen::Matrix<double, 10, 10>> lu(constraints.leftCols<kNumCubic>());
  if (!lu.isInvertible()) return;
  const Eigen::Matrix<double, 10, 10> G = lu.solve(constraints.rightCols<10>());
  if (!G.allFinite()) return;

  // Row i of the action matrix writes x * basis_i in the basis: a basis monomial itself or a
  // reduced cubic. Then action * b(p) = x(p) b(p) at every solution p.
  Eigen::Matrix<double, 10, 10> action = Eigen::Matrix<double, 10, 10>::Zero();
  for (int i = 0; i < 10; ++i) {
    const int product = kProduct.index[kMonomialX][kFirstQuadratic + i];
    if (product < kNumCubic) {
      action.row(i) = -G.row(product);
    } else {
      action(i, product - kFirstQuadratic) = 1.0;
    }
  }

  const Eigen::EigenSolver<Eigen::Matrix<double, 10, 10>> eigen_solver(action, true);
  if (eigen_solver.info() != Eigen::Success) return;
  const auto& eigenvalues = eigen_solver.eigenvalues();
  const auto& eigenvectors = eigen_solver.eigenvectors();
  constexpr int kBasisY = 17 - kFirstQuadratic;
  constexpr int kBasisZ = 18 - kFirstQuadratic;
  constexpr int kBasisOne = 19 - kFirstQuadratic;
  for (int k = 0; k < 10; ++k) {
    const std::complex<double> eigenvalue = eigenvalues(k);
    if (std::abs(eigenvalue.imag()) > kMaxImaginaryRatio * std::max(1.0, std::abs(eigenvalue))) {
      continue;
    }
    const std::complex<double> one = eigenvectors(kBasisOne, k);
    if (std::abs(one) <= 0.0) continue;
    const double x = eigenvalue.real();
    const double y = (eigenvectors(kBasisY, k) / one).real();
    const double z = (eigenvectors(kBasisZ, k) / one).real();
    const Vector9d entries =
        x * null_space.col(0) + y * null_space.col(1) + z * null_space.col(2) + null_space.col(3);
    Eigen::Matrix3d E = Eigen::Map<const RowMajorMatrix3d>(entries.data());
    const double norm = E.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) continue;
    models->push_back(E / norm);
  }
}

void EstimateEssentialMatrixEightPoint(const std::vector<Eigen::Vector2d>& points1,
                                       const std::vector<Eigen::Vector2d>& points2,
                                       std::vector<Eigen::Matrix3d>* models) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  models->clear();
  Eigen::Matrix3d normalized_E, T1, T2;
  if (!SolveNormalizedEpipolarSystem(points1, points2, &normalized_E, &T1, &T2)) return;
  // Project onto the essential manifold in the original normalised coordinates, where E's
  // structure (two equal singular values) holds.
  const Eigen::Matrix3d E_unconstrained = T2.transpose() * normalized_E * T1;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(E_unconstrained,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d E = svd.matrixU() * Eigen::Vector3d(1, 1, 0).asDiagonal() *
                            svd.matrixV().transpose() / std::sqrt(2.0);
  if (!E.allFinite()) return;
  models->push_back(E);
}

}  // namespace parallax
