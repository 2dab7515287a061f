#include "parallax/estimators/solvers/essential_matrix.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/math/dense_decompositions.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr double kMinRankRatio = 1e-10;
// Largest ||2 E E^T E - tr(E E^T) E|| of a unit-norm candidate (an exact one gives ~1e-15).
constexpr double kMaxEssentialResidual = 1e-6;

using RowMajorMatrix3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

// Polynomials in (x, y, z) of degree <= 3 as 20 coefficients: the 10 cubic monomials, then
// x^2, xy, xz, y^2, yz, z^2, x, y, z, 1.
constexpr int kNumMonomials = 20;
constexpr int kFirstQuadratic = 10;
constexpr int kFirstLinear = 16;
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

// The same row for unit rays (or any homogeneous 3-vectors): x2^T E x1 in E's row-major
// entries.
inline Vector9d EpipolarRow(const Eigen::Vector3d& x1, const Eigen::Vector3d& x2) {
  Vector9d row;
  row << x2.x() * x1.x(), x2.x() * x1.y(), x2.x() * x1.z(), x2.y() * x1.x(), x2.y() * x1.y(),
      x2.y() * x1.z(), x2.z() * x1.x(), x2.z() * x1.y(), x2.z() * x1.z();
  return row;
}

// Four vectors spanning the null space of the epipolar system (row-major E entries), of
// normalised image points (Vector2d, z = 1) or of unit rays (Vector3d).
template <typename Point>
bool EssentialNullSpace(const std::vector<Point>& points1, const std::vector<Point>& points2,
                        Eigen::Matrix<double, 9, 4>* null_space) {
  const size_t num_points = points1.size();
  if (num_points == 5) {
    // Minimal case without the heap: the last four columns of Q in A^T = QR. (Elimination
    // would be faster, but its basis puts the solutions at large or tiny x, y, z, where the
    // degree-10 polynomial below loses them.)
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
  Eigen::MatrixXd A =
      Eigen::MatrixXd::Zero(std::max<Eigen::Index>(static_cast<Eigen::Index>(num_points), 9), 9);
  for (size_t i = 0; i < num_points; ++i) {
    A.row(static_cast<Eigen::Index>(i)) = EpipolarRow(points1[i], points2[i]).transpose();
  }
  if (!A.allFinite()) return false;
  Eigen::VectorXd singular_values;
  Eigen::MatrixXd V;
  RightSingularSystem(A, &singular_values, &V);
  if (!(singular_values(4) > kMinRankRatio * singular_values(0))) return false;
  *null_space = V.rightCols<4>();
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

// Polynomials in one variable, lowest degree first, of degree <= kMaxDegree.
constexpr int kMaxDegree = 10;
// Relative precision at which root polishing stops (PolishSolution refines further when the
// constraints need it).
constexpr double kRootTolerance = 1e-13;
using UnivariatePolynomial = std::array<double, kMaxDegree + 1>;

double EvaluateUnivariate(const UnivariatePolynomial& p, int degree, double z) {
  double value = p[degree];
  for (int i = degree - 1; i >= 0; --i) value = value * z + p[i];
  return value;
}

// The product of a (degree da) and b (degree db), da + db <= kMaxDegree.
UnivariatePolynomial MultiplyUnivariate(const UnivariatePolynomial& a, int da,
                                        const UnivariatePolynomial& b, int db) {
  UnivariatePolynomial product{};
  for (int i = 0; i <= da; ++i) {
    for (int j = 0; j <= db; ++j) product[i + j] += a[i] * b[j];
  }
  return product;
}

// Distinct real roots of the polynomial p of the given degree by Sturm sequences: bisection
// isolates each root (the chain counts the roots in an interval), then safeguarded Newton
// steps on p polish it. Returns the number of roots written.
int RealRootsBySturm(UnivariatePolynomial p, int degree, double roots[kMaxDegree]) {
  double max_coeff = 0.0;
  for (int i = 0; i <= degree; ++i) max_coeff = std::max(max_coeff, std::abs(p[i]));
  if (!(max_coeff > 0.0) || !std::isfinite(max_coeff)) return 0;
  // A vanishing leading coefficient is a root at infinity (no essential matrix): drop it.
  while (degree > 0 && std::abs(p[degree]) <= 1e-14 * max_coeff) --degree;
  if (degree == 0) return 0;
  for (int i = 0; i < degree; ++i) p[i] /= p[degree];
  p[degree] = 1.0;

  // Fujiwara's bound on the magnitude of the roots.
  double bound = 0.0;
  for (int i = 0; i < degree; ++i) {
    const double scale = i == 0 ? 0.5 : 1.0;
    bound = std::max(bound, std::pow(scale * std::abs(p[i]), 1.0 / (degree - i)));
  }
  bound = 2.0 * bound + 1e-12;

  // Sturm chain: s0 = p, s1 = p', s_{k+1} = -(s_{k-1} mod s_k).
  std::array<UnivariatePolynomial, kMaxDegree + 1> chain{};
  std::array<int, kMaxDegree + 1> chain_degree{};
  chain[0] = p;
  chain_degree[0] = degree;
  for (int i = 1; i <= degree; ++i) chain[1][i - 1] = i * p[i];
  chain_degree[1] = degree - 1;
  int chain_length = 2;
  while (chain_degree[chain_length - 1] > 0) {
    UnivariatePolynomial remainder = chain[chain_length - 2];
    const UnivariatePolynomial& divisor = chain[chain_length - 1];
    const int divisor_degree = chain_degree[chain_length - 1];
    for (int i = chain_degree[chain_length - 2]; i >= divisor_degree; --i) {
      const double factor = remainder[i] / divisor[divisor_degree];
      for (int j = 0; j <= divisor_degree; ++j)
        remainder[i - divisor_degree + j] -= factor * divisor[j];
      remainder[i] = 0.0;
    }
    int remainder_degree = divisor_degree - 1;
    double remainder_scale = 0.0;
    for (int i = 0; i <= remainder_degree; ++i) {
      remainder_scale = std::max(remainder_scale, std::abs(remainder[i]));
    }
    double divisor_scale = 0.0;
    for (int i = 0; i <= divisor_degree; ++i) {
      divisor_scale = std::max(divisor_scale, std::abs(divisor[i]));
    }
    // A zero remainder means repeated roots: the chain so far still counts distinct ones.
    if (!(remainder_scale > 1e-13 * divisor_scale)) break;
    while (remainder_degree > 0 &&
           std::abs(remainder[remainder_degree]) <= 1e-15 * remainder_scale) {
      --remainder_degree;
    }
    // Rescaling by a positive factor keeps the signs the chain counts.
    for (int i = 0; i <= remainder_degree; ++i) {
      chain[chain_length][i] = -remainder[i] / remainder_scale;
    }
    chain_degree[chain_length] = remainder_degree;
    ++chain_length;
  }
  const auto sign_changes = [&](double z) {
    int changes = 0;
    double previous = 0.0;
    for (int k = 0; k < chain_length; ++k) {
      const double value = EvaluateUnivariate(chain[k], chain_degree[k], z);
      if (value == 0.0) continue;
      if (previous != 0.0 && (value < 0.0) != (previous < 0.0)) ++changes;
      previous = value;
    }
    return changes;
  };

  // Polishes the single root in (lower, upper).
  const auto polish = [&](double lower, double upper) {
    double f_lower = EvaluateUnivariate(p, degree, lower);
    double z = 0.5 * (lower + upper);
    for (int iteration = 0; iteration < 100; ++iteration) {
      double value = p[degree], derivative = 0.0;
      for (int i = degree - 1; i >= 0; --i) {
        derivative = derivative * z + value;
        value = value * z + p[i];
      }
      if (value == 0.0) break;
      if ((value < 0.0) == (f_lower < 0.0)) {
        lower = z;
        f_lower = value;
      } else {
        upper = z;
      }
      double next = z - value / derivative;
      // Newton when it stays inside the bracket, bisection otherwise.
      if (!(next > lower && next < upper)) next = 0.5 * (lower + upper);
      // Near the root the step is rounding noise; the last Newton step is as close as p allows.
      const double tolerance = kRootTolerance * std::max(1.0, std::abs(z));
      if (std::abs(next - z) <= tolerance || upper - lower <= tolerance) {
        z = next;
        break;
      }
      z = next;
    }
    return z;
  };

  int num_roots = 0;
  struct Interval {
    double lower, upper;
    int changes_lower, changes_upper;
  };
  std::array<Interval, 64> stack;
  int stack_size = 0;
  stack[stack_size++] = {-bound, bound, sign_changes(-bound), sign_changes(bound)};
  while (stack_size > 0 && num_roots < kMaxDegree) {
    const Interval interval = stack[--stack_size];
    const int count = interval.changes_lower - interval.changes_upper;
    if (count <= 0) continue;
    const double width = interval.upper - interval.lower;
    if (count == 1 && EvaluateUnivariate(p, degree, interval.lower) *
                              EvaluateUnivariate(p, degree, interval.upper) <
                          0.0) {
      roots[num_roots++] = polish(interval.lower, interval.upper);
      continue;
    }
    const double middle = interval.lower + 0.5 * width;
    if (width <= 1e-12 * std::max(1.0, std::abs(middle)) || stack_size + 2 > 64) {
      // Clustered (or repeated) roots: one representative.
      roots[num_roots++] = middle;
      continue;
    }
    const int changes_middle = sign_changes(middle);
    stack[stack_size++] = {interval.lower, middle, interval.changes_lower, changes_middle};
    stack[stack_size++] = {middle, interval.upper, changes_middle, interval.changes_upper};
  }
  return num_roots;
}

// The monomials of kExponents at (x, y, z) and, when `derivatives` is given, their partial
// derivatives (one column per variable).
void EvaluateMonomials(const Eigen::Vector3d& point,
                       Eigen::Matrix<double, kNumMonomials, 1>* monomials,
                       Eigen::Matrix<double, kNumMonomials, 3>* derivatives) {
  const double x = point(0), y = point(1), z = point(2);
  const double xx = x * x, yy = y * y, zz = z * z, xy = x * y, xz = x * z, yz = y * z;
  *monomials << xx * x, xx * y, xx * z, x * yy, xy * z, x * zz, yy * y, yy * z, y * zz, zz * z, xx,
      xy, xz, yy, yz, zz, x, y, z, 1.0;
  if (derivatives == nullptr) return;
  // d/dx, d/dy, d/dz of each monomial, in the same order.
  *derivatives << 3 * xx, 0, 0,  //
      2 * xy, xx, 0,             //
      2 * xz, 0, xx,             //
      yy, 2 * xy, 0,             //
      yz, xz, xy,                //
      zz, 0, 2 * xz,             //
      0, 3 * yy, 0,              //
      0, 2 * yz, yy,             //
      0, zz, 2 * yz,             //
      0, 0, 3 * zz,              //
      2 * x, 0, 0,               //
      y, x, 0,                   //
      z, 0, x,                   //
      0, 2 * y, 0,               //
      0, z, y,                   //
      0, 0, 2 * z,               //
      1, 0, 0,                   //
      0, 1, 0,                   //
      0, 0, 1,                   //
      0, 0, 0;
}

// Gauss-Newton steps on the 10 cubic constraints at (x, y, z) when they are not met to
// working precision: the degree-10 polynomial loses digits when two solutions lie close, the
// constraints themselves do not.
void PolishSolution(const Eigen::Matrix<double, 10, kNumMonomials>& constraints,
                    Eigen::Vector3d* xyz) {
  Eigen::Matrix<double, kNumMonomials, 1> monomials;
  Eigen::Matrix<double, kNumMonomials, 3> derivatives;
  EvaluateMonomials(*xyz, &monomials, nullptr);
  Eigen::Matrix<double, 10, 1> residual = constraints.lazyProduct(monomials);
  double cost = residual.squaredNorm();
  const double scale = constraints.squaredNorm() * monomials.squaredNorm();
  for (int iteration = 0; iteration < 3 && cost > 1e-26 * scale; ++iteration) {
    EvaluateMonomials(*xyz, &monomials, &derivatives);
    const Eigen::Matrix<double, 10, 3> jacobian = constraints.lazyProduct(derivatives);
    const Eigen::Matrix3d normal = jacobian.transpose().lazyProduct(jacobian);
    const Eigen::Vector3d step = normal.inverse() * (-jacobian.transpose().lazyProduct(residual));
    if (!step.allFinite()) return;
    const Eigen::Vector3d candidate = *xyz + step;
    EvaluateMonomials(candidate, &monomials, nullptr);
    const Eigen::Matrix<double, 10, 1> candidate_residual = constraints.lazyProduct(monomials);
    const double candidate_cost = candidate_residual.squaredNorm();
    if (!(candidate_cost < cost)) return;
    *xyz = candidate;
    residual = candidate_residual;
    cost = candidate_cost;
  }
}

// The 5-point algorithm on normalised points or unit rays: only the epipolar rows of the
// null space differ.
template <typename Point>
void FivePoint(const std::vector<Point>& points1, const std::vector<Point>& points2,
               std::vector<Eigen::Matrix3d>* models) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  models->clear();
  if (points1.size() < 5) return;
  Eigen::Matrix<double, 9, 4> null_space;
  if (!EssentialNullSpace(points1, points2, &null_space)) return;
  const Eigen::Matrix<double, 10, kNumMonomials> constraints = BuildConstraints(null_space);

  // Nister's elimination: order the monomials as
  //   x^3 y^3 x^2y xy^2 x^2z x^2 y^2z y^2 xyz xy | xz^2 xz x yz^2 yz y z^3 z^2 z 1
  // and reduce the first ten columns to the identity. Rows (x^2z, x^2), (y^2z, y^2) and
  // (xyz, xy) then differ by a factor z in their leading monomial: row_a - z row_b leaves
  // x p1(z) + y p2(z) + p3(z) = 0 (degrees 3, 3, 4). Three such equations have the common
  // solution (x, y, 1) only where the determinant of their 3 x 3 polynomial matrix, of degree
  // 10 in z, vanishes.
  constexpr int kLeading[10] = {0, 6, 1, 3, 2, 10, 7, 13, 4, 11};
  constexpr int kTrailing[10] = {5, 12, 16, 8, 14, 17, 9, 15, 18, 19};
  // Gauss-Jordan with partial pivoting on [leading | trailing], in place: B = leading^-1 trailing.
  double reduced[10][20];
  for (int row = 0; row < 10; ++row) {
    for (int i = 0; i < 10; ++i) {
      reduced[row][i] = constraints(row, kLeading[i]);
      reduced[row][10 + i] = constraints(row, kTrailing[i]);
    }
  }
  double max_pivot = 0.0;
  for (int column = 0; column < 10; ++column) {
    int pivot_row = column;
    for (int row = column + 1; row < 10; ++row) {
      if (std::abs(reduced[row][column]) > std::abs(reduced[pivot_row][column])) pivot_row = row;
    }
    const double pivot = reduced[pivot_row][column];
    max_pivot = std::max(max_pivot, std::abs(pivot));
    if (!(std::abs(pivot) > kMinRankRatio * max_pivot)) return;
    if (pivot_row != column) std::swap(reduced[pivot_row], reduced[column]);
    const double inverse_pivot = 1.0 / pivot;
    for (int i = column; i < 20; ++i) reduced[column][i] *= inverse_pivot;
    for (int row = 0; row < 10; ++row) {
      if (row == column) continue;
      const double factor = reduced[row][column];
      if (factor == 0.0) continue;
      for (int i = column; i < 20; ++i) reduced[row][i] -= factor * reduced[column][i];
    }
  }
  Eigen::Matrix<double, 10, 10> B;
  for (int row = 0; row < 10; ++row) {
    for (int i = 0; i < 10; ++i) B(row, i) = reduced[row][10 + i];
  }
  if (!B.allFinite()) return;

  // Polynomial entries, lowest degree first: [row][0] x's (degree 3), [1] y's (3), [2] 1's (4).
  UnivariatePolynomial P[3][3];
  for (int row = 0; row < 3; ++row) {
    const auto a = B.row(4 + 2 * row);  // The row whose leading monomial has the factor z.
    const auto b = B.row(5 + 2 * row);
    P[row][0] = {a(2), a(1) - b(2), a(0) - b(1), -b(0)};
    P[row][1] = {a(5), a(4) - b(5), a(3) - b(4), -b(3)};
    P[row][2] = {a(9), a(8) - b(9), a(7) - b(8), a(6) - b(7), -b(6)};
  }
  const auto minor = [&](int r1, int r2, int c1, int d1, int c2, int d2) {
    const UnivariatePolynomial first = MultiplyUnivariate(P[r1][c1], d1, P[r2][c2], d2);
    const UnivariatePolynomial second = MultiplyUnivariate(P[r1][c2], d2, P[r2][c1], d1);
    UnivariatePolynomial difference;
    for (int i = 0; i <= kMaxDegree; ++i) difference[i] = first[i] - second[i];
    return difference;
  };
  // Cofactor expansion along the first row; column degrees are 3, 3, 4.
  const UnivariatePolynomial minor0 = minor(1, 2, 1, 3, 2, 4);  // Degree 7.
  const UnivariatePolynomial minor1 = minor(1, 2, 0, 3, 2, 4);  // Degree 7.
  const UnivariatePolynomial minor2 = minor(1, 2, 0, 3, 1, 3);  // Degree 6.
  const UnivariatePolynomial term0 = MultiplyUnivariate(P[0][0], 3, minor0, 7);
  const UnivariatePolynomial term1 = MultiplyUnivariate(P[0][1], 3, minor1, 7);
  const UnivariatePolynomial term2 = MultiplyUnivariate(P[0][2], 4, minor2, 6);
  UnivariatePolynomial determinant;
  for (int i = 0; i <= kMaxDegree; ++i) determinant[i] = term0[i] - term1[i] + term2[i];

  double roots[kMaxDegree];
  const int num_roots = RealRootsBySturm(determinant, kMaxDegree, roots);
  for (int k = 0; k < num_roots; ++k) {
    const double z = roots[k];
    Eigen::Matrix3d numeric;
    for (int row = 0; row < 3; ++row) {
      numeric(row, 0) = EvaluateUnivariate(P[row][0], 3, z);
      numeric(row, 1) = EvaluateUnivariate(P[row][1], 3, z);
      numeric(row, 2) = EvaluateUnivariate(P[row][2], 4, z);
    }
    // (x, y, 1) spans the null space of the rank-2 matrix: the largest cross product of two
    // of its rows.
    Eigen::Vector3d solution = numeric.row(0).cross(numeric.row(1));
    for (const auto& [r1, r2] : {std::pair{0, 2}, std::pair{1, 2}}) {
      const Eigen::Vector3d candidate = numeric.row(r1).cross(numeric.row(r2));
      if (candidate.squaredNorm() > solution.squaredNorm()) solution = candidate;
    }
    if (!(std::abs(solution(2)) > 1e-14 * solution.norm())) continue;
    Eigen::Vector3d xyz(solution(0) / solution(2), solution(1) / solution(2), z);
    PolishSolution(constraints, &xyz);
    const Vector9d entries = xyz(0) * null_space.col(0) + xyz(1) * null_space.col(1) +
                             xyz(2) * null_space.col(2) + null_space.col(3);
    Eigen::Matrix3d E = Eigen::Map<const RowMajorMatrix3d>(entries.data());
    const double norm = E.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) continue;
    E /= norm;
    // A root the polishing could not bring onto the essential manifold (two solutions
    // merging) is no solution.
    const Eigen::Matrix3d E_Et = E * E.transpose();
    if ((2.0 * E_Et * E - E_Et.trace() * E).norm() > kMaxEssentialResidual) continue;
    models->push_back(E);
  }
}

// The nearest essential matrix (singular values (1, 1, 0), Hartley & Zisserman result 9.18)
// of a least-squares solution, unit Frobenius norm, appended when finite.
void PushEssentialProjection(const Eigen::Matrix3d& E_unconstrained,
                             std::vector<Eigen::Matrix3d>* models) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(E_unconstrained,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d E = svd.matrixU() * Eigen::Vector3d(1, 1, 0).asDiagonal() *
                            svd.matrixV().transpose() / std::sqrt(2.0);
  if (E.allFinite()) models->push_back(E);
}

}  // namespace

void EstimateEssentialMatrixFivePoint(const std::vector<Eigen::Vector2d>& points1,
                                      const std::vector<Eigen::Vector2d>& points2,
                                      std::vector<Eigen::Matrix3d>* models) {
  FivePoint(points1, points2, models);
}

void EstimateEssentialMatrixFivePointFromRays(const std::vector<Eigen::Vector3d>& rays1,
                                              const std::vector<Eigen::Vector3d>& rays2,
                                              std::vector<Eigen::Matrix3d>* models) {
  FivePoint(rays1, rays2, models);
}

void EstimateEssentialMatrixEightPointFromRays(const std::vector<Eigen::Vector3d>& rays1,
                                               const std::vector<Eigen::Vector3d>& rays2,
                                               std::vector<Eigen::Matrix3d>* models) {
  PARALLAX_CHECK_EQ(rays1.size(), rays2.size());
  models->clear();
  const size_t num_rays = rays1.size();
  if (num_rays < 8) return;
  // Unit rays need no Hartley normalisation: every entry of a row is at most 1.
  Eigen::MatrixXd A(static_cast<Eigen::Index>(num_rays), 9);
  for (size_t i = 0; i < num_rays; ++i) {
    A.row(static_cast<Eigen::Index>(i)) = EpipolarRow(rays1[i], rays2[i]).transpose();
  }
  if (!A.allFinite()) return;
  Eigen::VectorXd singular_values;
  Eigen::MatrixXd V;
  RightSingularSystem(A, &singular_values, &V);
  if (!(singular_values(7) > kMinRankRatio * singular_values(0))) return;
  const Vector9d entries = V.col(8);
  const Eigen::Matrix3d E_unconstrained = Eigen::Map<const RowMajorMatrix3d>(entries.data());
  PushEssentialProjection(E_unconstrained, models);
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
  PushEssentialProjection(E_unconstrained, models);
}

}  // namespace parallax
