#include "parallax/estimators/solvers/p3p.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "parallax/math/polynomial.h"

namespace parallax {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// tr(adj(A) B): the rows of adj(A) are cross products of the columns of A. With it,
//   det(A + g B) = det(A) + g tr(adj(A) B) + g^2 tr(adj(B) A) + g^3 det(B).
double TraceAdjugateProduct(const Matrix3d& A, const Matrix3d& B) {
  return A.col(1).cross(A.col(2)).dot(B.col(0)) + A.col(2).cross(A.col(0)).dot(B.col(1)) +
         A.col(0).cross(A.col(1)).dot(B.col(2));
}

// Unit vector spanning the null space of a (numerically) rank-2 symmetric 3x3 matrix: the
// longest cross product of two of its rows.
Vector3d NullVector(const Matrix3d& A) {
  const Vector3d r0 = A.row(0).transpose(), r1 = A.row(1).transpose(), r2 = A.row(2).transpose();
  const Vector3d c01 = r0.cross(r1), c02 = r0.cross(r2), c12 = r1.cross(r2);
  const double n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
  if (n01 >= n02 && n01 >= n12) return c01 / std::sqrt(n01);
  if (n02 >= n12) return c02 / std::sqrt(n02);
  return c12 / std::sqrt(n12);
}

// Sum of the principal 2x2 minors: the product of the two non-zero eigenvalues of a singular
// symmetric matrix, negative iff the conic it defines is a pair of real lines.
double PrincipalMinorSum(const Matrix3d& D) {
  return D(0, 0) * D(1, 1) - D(0, 1) * D(0, 1) + D(0, 0) * D(2, 2) - D(0, 2) * D(0, 2) +
         D(1, 1) * D(2, 2) - D(1, 2) * D(1, 2);
}

// Orthonormal frame (as columns) attached to a triangle; identical for congruent triangles up
// to the rotation between them.
Matrix3d TriangleFrame(const Vector3d& p0, const Vector3d& p1, const Vector3d& p2) {
  Matrix3d frame;
  frame.col(0) = (p1 - p0).normalized();
  frame.col(2) = frame.col(0).cross(p2 - p0).normalized();
  frame.col(1) = frame.col(2).cross(frame.col(0));
  return frame;
}

struct DepthEquations {
  // lambda_i^2 + lambda_j^2 + b_ij lambda_i lambda_j = a_ij for (ij) = (01), (02), (12).
  double a01, a02, a12;
  double b01, b02, b12;

  Vector3d Residuals(const Vector3d& l) const {
    return Vector3d(l(0) * l(0) + l(1) * l(1) + b01 * l(0) * l(1) - a01,
                    l(0) * l(0) + l(2) * l(2) + b02 * l(0) * l(2) - a02,
                    l(1) * l(1) + l(2) * l(2) + b12 * l(1) * l(2) - a12);
  }

  // A few Gauss-Newton (here Newton, 3 equations in 3 unknowns) steps, each kept only when it
  // lowers the residual: the closed form loses digits in the eigen-decomposition.
  void Refine(Vector3d* lambda) const {
    Vector3d residuals = Residuals(*lambda);
    double cost = residuals.squaredNorm();
    for (int iteration = 0; iteration < 5 && cost > 0; ++iteration) {
      const Vector3d& l = *lambda;
      Matrix3d jacobian;
      jacobian << 2 * l(0) + b01 * l(1), 2 * l(1) + b01 * l(0), 0,  //
          2 * l(0) + b02 * l(2), 0, 2 * l(2) + b02 * l(0),          //
          0, 2 * l(1) + b12 * l(2), 2 * l(2) + b12 * l(1);
      Matrix3d inverse;
      bool invertible = false;
      jacobian.computeInverseWithCheck(inverse, invertible, 1e-14);
      if (!invertible) return;
      const Vector3d candidate = l - inverse * residuals;
      const Vector3d candidate_residuals = Residuals(candidate);
      const double candidate_cost = candidate_residuals.squaredNorm();
      if (!(candidate_cost < cost)) return;
      *lambda = candidate;
      residuals = candidate_residuals;
      cost = candidate_cost;
    }
  }
};

}  // namespace

void SolveP3P(const std::array<Eigen::Vector3d, 3>& rays_in_cam,
              const std::array<Eigen::Vector3d, 3>& points_in_world,
              std::vector<Rigid3d>* cams_from_world) {
  cams_from_world->clear();
  std::array<Vector3d, 3> y;
  for (int i = 0; i < 3; ++i) {
    if (!rays_in_cam[i].allFinite() || !points_in_world[i].allFinite()) return;
    const double norm = rays_in_cam[i].norm();
    if (!(norm > 0)) return;
    y[i] = rays_in_cam[i] / norm;
  }
  const Vector3d& x0 = points_in_world[0];
  const Vector3d& x1 = points_in_world[1];
  const Vector3d& x2 = points_in_world[2];
  const Vector3d d01 = x0 - x1, d02 = x0 - x2, d12 = x1 - x2;

  // Collinear or coincident world points leave the rotation about their line free.
  const double scale2 = std::max({d01.squaredNorm(), d02.squaredNorm(), d12.squaredNorm()});
  if (!(scale2 > 0) ||
      d01.cross(d02).squaredNorm() <= 1e-20 * d01.squaredNorm() * d02.squaredNorm()) {
    return;
  }

  // Work with the world triangle scaled to unit longest side; depths scale back at the end.
  DepthEquations equations;
  equations.a01 = d01.squaredNorm() / scale2;
  equations.a02 = d02.squaredNorm() / scale2;
  equations.a12 = d12.squaredNorm() / scale2;
  equations.b01 = -2 * y[0].dot(y[1]);
  equations.b02 = -2 * y[0].dot(y[2]);
  equations.b12 = -2 * y[1].dot(y[2]);
  const double a01 = equations.a01, a02 = equations.a02, a12 = equations.a12;

  // Quadric forms: lambda^T M_ij lambda = a_ij.
  Matrix3d M01, M02, M12;
  M01 << 1, equations.b01 / 2, 0, equations.b01 / 2, 1, 0, 0, 0, 0;
  M02 << 1, 0, equations.b02 / 2, 0, 0, 0, equations.b02 / 2, 0, 1;
  M12 << 0, 0, 0, 0, 1, equations.b12 / 2, 0, equations.b12 / 2, 1;
  // Two homogeneous conics through every solution: lambda^T D lambda = 0.
  const Matrix3d D1 = a12 * M01 - a01 * M12;
  const Matrix3d D2 = a12 * M02 - a02 * M12;

  // Degenerate members D0 of the pencil: det(D1 + g D2) = 0, a cubic in g (or in 1/g when
  // the g^3 coefficient is the smaller one, so that the leading coefficient is never zero).
  const double c3 = D2.determinant();
  const double c2 = TraceAdjugateProduct(D2, D1);
  const double c1 = TraceAdjugateProduct(D1, D2);
  const double c0 = D1.determinant();
  std::array<Matrix3d, 3> degenerate_conics;
  int num_degenerate_conics = 0;
  double roots[3];
  if (c3 == 0 && c0 == 0) {
    degenerate_conics[num_degenerate_conics++] = D1;
    degenerate_conics[num_degenerate_conics++] = D2;
  } else if (std::abs(c3) >= std::abs(c0)) {
    const int num_roots = SolveCubicReal(c3, c2, c1, c0, roots);
    for (int i = 0; i < num_roots; ++i)
      degenerate_conics[num_degenerate_conics++] = D1 + roots[i] * D2;
  } else {
    const int num_roots = SolveCubicReal(c0, c1, c2, c3, roots);
    for (int i = 0; i < num_roots; ++i)
      degenerate_conics[num_degenerate_conics++] = roots[i] * D1 + D2;
  }

  // Every real line pair of the pencil passes through all real solutions; take the member
  // that is most clearly a line pair (most negative eigenvalue product, scale-free).
  Matrix3d D0;
  double best_minor_sum = std::numeric_limits<double>::max();
  for (int i = 0; i < num_degenerate_conics; ++i) {
    const double norm = degenerate_conics[i].norm();
    if (!(norm > 0) || !std::isfinite(norm)) continue;
    const Matrix3d normalized = degenerate_conics[i] / norm;
    const double minor_sum = PrincipalMinorSum(normalized);
    if (minor_sum < best_minor_sum) {
      best_minor_sum = minor_sum;
      D0 = normalized;
    }
  }
  if (best_minor_sum == std::numeric_limits<double>::max()) return;

  // Factor the line pair: D0 = s_a e_a e_a^T + s_b e_b e_b^T with s_a s_b < 0, so
  // lambda^T D0 lambda = s_a (e_a.l - r e_b.l)(e_a.l + r e_b.l), r = sqrt(-s_b / s_a).
  std::array<Vector3d, 2> lines;
  int num_lines = 0;
  const double trace = D0.trace();
  if (best_minor_sum < -1e-14) {
    const double discriminant = std::sqrt(trace * trace - 4 * best_minor_sum);
    // s_a: the eigenvalue of largest magnitude, whose eigenvector is best conditioned.
    const double s_a = trace >= 0 ? (trace + discriminant) / 2 : (trace - discriminant) / 2;
    const double s_b = best_minor_sum / s_a;
    const Vector3d e_a = NullVector(D0 - s_a * Matrix3d::Identity());
    const Vector3d e_b = NullVector(D0).cross(e_a).normalized();
    const double r = std::sqrt(-s_b / s_a);
    lines[num_lines++] = e_a - r * e_b;
    lines[num_lines++] = e_a + r * e_b;
  } else if (std::abs(best_minor_sum) < 1e-14 && std::abs(trace) > 1e-7) {
    // Rank one: a double line, the row of largest norm.
    int row = 0;
    D0.rowwise().squaredNorm().maxCoeff(&row);
    lines[num_lines++] = D0.row(row).transpose();
  } else {
    return;  // Only the singular point is real: no positive depths.
  }

  const double d1_norm = D1.norm(), d2_norm = D2.norm();
  const Vector3d centroid_in_world = (x0 + x1 + x2) / 3;
  const Matrix3d world_frame = TriangleFrame(x0, x1, x2);
  const double scale = std::sqrt(scale2);
  for (int line_idx = 0; line_idx < num_lines; ++line_idx) {
    const Vector3d& n = lines[line_idx];
    // On the line n.lambda = 0 solve for the component with the largest coefficient:
    // lambda = p u + q w.
    int i = 0;
    n.cwiseAbs().maxCoeff(&i);
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    if (!(std::abs(n(i)) > 0)) continue;
    Vector3d u = Vector3d::Unit(j), w = Vector3d::Unit(k);
    u(i) = -n(j) / n(i);
    w(i) = -n(k) / n(i);

    // Restrict one of D1, D2 to the line; both vanish at the solutions there, and the one
    // that keeps more of its magnitude keeps more digits.
    const double quadratic1[3] = {u.dot(D1 * u), u.dot(D1 * w), w.dot(D1 * w)};
    const double quadratic2[3] = {u.dot(D2 * u), u.dot(D2 * w), w.dot(D2 * w)};
    const double magnitude1 =
        std::max({std::abs(quadratic1[0]), std::abs(quadratic1[1]), std::abs(quadratic1[2])}) /
        d1_norm;
    const double magnitude2 =
        std::max({std::abs(quadratic2[0]), std::abs(quadratic2[1]), std::abs(quadratic2[2])}) /
        d2_norm;
    const double* quadratic = magnitude1 >= magnitude2 ? quadratic1 : quadratic2;
    const double A = quadratic[0], B = quadratic[1], C = quadratic[2];

    // A p^2 + 2 B p q + C q^2 = 0, solved for the better conditioned ratio.
    double ratios[2];
    const bool solve_for_p = std::abs(A) >= std::abs(C);
    const int num_ratios = solve_for_p ? SolveQuadraticReal(A, 2 * B, C, ratios)
                                       : SolveQuadraticReal(C, 2 * B, A, ratios);
    for (int ratio_idx = 0; ratio_idx < num_ratios; ++ratio_idx) {
      const Vector3d direction =
          solve_for_p ? Vector3d(ratios[ratio_idx] * u + w) : Vector3d(u + ratios[ratio_idx] * w);
      // The scale from the best conditioned of the three distance equations.
      const double v01 = direction.dot(M01 * direction);
      const double v02 = direction.dot(M02 * direction);
      const double v12 = direction.dot(M12 * direction);
      double lambda_scale2 = 0;
      if (v01 >= v02 && v01 >= v12) {
        lambda_scale2 = a01 / v01;
      } else if (v02 >= v12) {
        lambda_scale2 = a02 / v02;
      } else {
        lambda_scale2 = a12 / v12;
      }
      if (!(lambda_scale2 > 0) || !std::isfinite(lambda_scale2)) continue;
      Vector3d lambda = std::sqrt(lambda_scale2) * direction;
      if (lambda.sum() < 0) lambda = -lambda;
      if (!(lambda.minCoeff() > 0)) continue;  // A point behind the camera.
      equations.Refine(&lambda);
      if (!(lambda.minCoeff() > 0)) continue;

      lambda *= scale;
      const Vector3d p0 = lambda(0) * y[0], p1 = lambda(1) * y[1], p2 = lambda(2) * y[2];
      const Matrix3d rotation = TriangleFrame(p0, p1, p2) * world_frame.transpose();
      const Vector3d translation = (p0 + p1 + p2) / 3 - rotation * centroid_in_world;
      if (!rotation.allFinite() || !translation.allFinite()) continue;
      cams_from_world->emplace_back(Eigen::Quaterniond(rotation).normalized(), translation);
    }
  }
}

void ComputeSquaredReprojectionErrors(const std::vector<Eigen::Vector2d>& points2D,
                                      const std::vector<Eigen::Vector3d>& points3D,
                                      const Rigid3d& cam_from_world,
                                      std::vector<double>* squared_errors) {
  const Matrix3d rotation = cam_from_world.rotation.toRotationMatrix();
  const Vector3d& translation = cam_from_world.translation;
  const size_t num_points = points2D.size();
  squared_errors->resize(num_points);
  double* errors = squared_errors->data();
  for (size_t i = 0; i < num_points; ++i) {
    const Vector3d point_in_cam = rotation * points3D[i] + translation;
    // Also false for NaN: such points are never inliers.
    if (point_in_cam.z() > std::numeric_limits<double>::epsilon()) {
      const double inverse_depth = 1 / point_in_cam.z();
      const double dx = point_in_cam.x() * inverse_depth - points2D[i].x();
      const double dy = point_in_cam.y() * inverse_depth - points2D[i].y();
      errors[i] = dx * dx + dy * dy;
    } else {
      errors[i] = std::numeric_limits<double>::max();
    }
  }
}

void SolveP3PFromFirstThree(const std::vector<Eigen::Vector2d>& points2D,
                            const std::vector<Eigen::Vector3d>& points3D,
                            std::vector<Rigid3d>* cams_from_world) {
  SolveP3P({points2D[0].homogeneous(), points2D[1].homogeneous(), points2D[2].homogeneous()},
           {points3D[0], points3D[1], points3D[2]}, cams_from_world);
}

}  // namespace parallax
