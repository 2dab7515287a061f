#pragma once

#include <Eigen/Core>
#include <vector>

namespace parallax {

// Polynomials are coefficient vectors with the highest degree first:
// coeffs(0) x^n + coeffs(1) x^(n-1) + ... + coeffs(n).

// Evaluates the polynomial at x (Horner).
double EvaluatePolynomial(const Eigen::VectorXd& coeffs, double x);

// Real roots of a polynomial of any degree from the eigenvalues of its companion matrix,
// each polished by a few Newton steps. Leading zero coefficients are stripped first.
// Roots whose imaginary part exceeds `max_imag` (relative) are dropped.
std::vector<double> RealPolynomialRoots(const Eigen::VectorXd& coeffs, double max_imag = 1e-8);

// Real roots of a x^2 + b x + c (any of a, b may be zero). Returns the count found.
int SolveQuadraticReal(double a, double b, double c, double roots[2]);

// Real roots of a x^3 + b x^2 + c x + d, a != 0 (closed form, then one Newton step each).
int SolveCubicReal(double a, double b, double c, double d, double roots[3]);

}  // namespace parallax
