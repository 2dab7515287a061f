#include "parallax/math/polynomial.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace parallax {

double EvaluatePolynomial(const Eigen::VectorXd& coeffs, double x) {
  double value = 0.0;
  for (Eigen::Index i = 0; i < coeffs.size(); ++i) value = value * x + coeffs(i);
  return value;
}

namespace {
double EvaluateDerivative(const Eigen::VectorXd& coeffs, double x) {
  const Eigen::Index degree = coeffs.size() - 1;
  double value = 0.0;
  for (Eigen::Index i = 0; i < degree; ++i) value = value * x + coeffs(i) * (degree - i);
  return value;
}

double PolishRoot(const Eigen::VectorXd& coeffs, double x) {
  for (int iteration = 0; iteration < 3; ++iteration) {
    const double derivative = EvaluateDerivative(coeffs, x);
    if (derivative == 0.0) break;
    const double step = EvaluatePolynomial(coeffs, x) / derivative;
    if (!std::isfinite(step)) break;
    x -= step;
  }
  return x;
}
}  // namespace

std::vector<double> RealPolynomialRoots(const Eigen::VectorXd& coeffs_in, double max_imag) {
  Eigen::Index first = 0;
  while (first < coeffs_in.size() && coeffs_in(first) == 0.0) ++first;
  const Eigen::VectorXd coeffs = coeffs_in.tail(coeffs_in.size() - first);
  std::vector<double> roots;
  const Eigen::Index degree = coeffs.size() - 1;
  if (degree < 1) return roots;
  if (degree == 1) {
    roots.push_back(-coeffs(1) / coeffs(0));
    return roots;
  }
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  companion.row(0) = -coeffs.tail(degree).transpose() / coeffs(0);
  companion.bottomLeftCorner(degree - 1, degree - 1).setIdentity();
  Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, /*computeEigenvectors=*/false);
  if (solver.info() != Eigen::Success) return roots;
  for (Eigen::Index i = 0; i < degree; ++i) {
    const std::complex<double> root = solver.eigenvalues()(i);
    if (std::abs(root.imag()) <= max_imag * std::max(1.0, std::abs(root))) {
      roots.push_back(PolishRoot(coeffs, root.real()));
    }
  }
  return roots;
}

int SolveQuadraticReal(double a, double b, double c, double roots[2]) {
  if (a == 0.0) {
    if (b == 0.0) return 0;
    roots[0] = -c / b;
    return 1;
  }
  const double discriminant = b * b - 4.0 * a * c;
  if (discriminant < 0.0) return 0;
  // Numerically stable form: avoid cancellation between -b and sqrt(disc).
  const double q = -0.5 * (b + std::copysign(std::sqrt(discriminant), b));
  if (q == 0.0) {
    roots[0] = roots[1] = 0.0;
    return 2;
  }
  roots[0] = q / a;
  roots[1] = c / q;
  return 2;
}

int SolveCubicReal(double a, double b, double c, double d, double roots[3]) {
  const double inv_a = 1.0 / a;
  const double b_n = b * inv_a, c_n = c * inv_a, d_n = d * inv_a;
  // Depressed cubic t^3 + p t + q with x = t - b/3.
  const double p = c_n - b_n * b_n / 3.0;
  const double q = 2.0 * b_n * b_n * b_n / 27.0 - b_n * c_n / 3.0 + d_n;
  const double shift = -b_n / 3.0;
  const double discriminant = q * q / 4.0 + p * p * p / 27.0;
  int count = 0;
  if (discriminant > 0.0) {
    const double sqrt_disc = std::sqrt(discriminant);
    roots[count++] = std::cbrt(-q / 2.0 + sqrt_disc) + std::cbrt(-q / 2.0 - sqrt_disc) + shift;
  } else if (p == 0.0) {
    roots[count++] = shift;
  } else {
    const double radius = 2.0 * std::sqrt(-p / 3.0);
    const double argument = std::clamp(3.0 * q / (p * radius), -1.0, 1.0);
    const double angle = std::acos(argument) / 3.0;
    for (int k = 0; k < 3; ++k) {
      roots[count++] = radius * std::cos(angle - 2.0 * M_PI * k / 3.0) + shift;
    }
  }
  for (int i = 0; i < count; ++i) {
    const double x = roots[i];
    const double f = ((x + b_n) * x + c_n) * x + d_n;
    const double df = (3.0 * x + 2.0 * b_n) * x + c_n;
    if (df != 0.0) roots[i] = x - f / df;
  }
  return count;
}

}  // namespace parallax
