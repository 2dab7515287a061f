#include "parallax/math/polynomial.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace parallax {
namespace {

TEST(Polynomial, CompanionRootsOfKnownPolynomial) {
  // (x - 1)(x + 2)(x - 3.5)(x^2 + 1): three real roots, one complex pair.
  Eigen::VectorXd coeffs(6);
  coeffs << 1, -2.5, -4.5, 4.5, -5.5, 7;
  // Verify the expansion by evaluation at the roots rather than trusting the literal.
  std::vector<double> roots = RealPolynomialRoots(coeffs);
  for (double root : roots) EXPECT_NEAR(EvaluatePolynomial(coeffs, root), 0.0, 1e-9);
  std::sort(roots.begin(), roots.end());
  ASSERT_EQ(roots.size(), 3u);
  EXPECT_NEAR(roots[0], -2.0, 1e-10);
  EXPECT_NEAR(roots[1], 1.0, 1e-10);
  EXPECT_NEAR(roots[2], 3.5, 1e-10);
}

TEST(Polynomial, LeadingZerosAndLinear) {
  Eigen::VectorXd coeffs(3);
  coeffs << 0, 2, -3;
  const auto roots = RealPolynomialRoots(coeffs);
  ASSERT_EQ(roots.size(), 1u);
  EXPECT_DOUBLE_EQ(roots[0], 1.5);
}

TEST(Polynomial, CubicThreeAndOneRealRoots) {
  double roots[3];
  // (x-1)(x-2)(x-3) = x^3 - 6x^2 + 11x - 6
  ASSERT_EQ(SolveCubicReal(1, -6, 11, -6, roots), 3);
  std::sort(roots, roots + 3);
  EXPECT_NEAR(roots[0], 1, 1e-12);
  EXPECT_NEAR(roots[1], 2, 1e-12);
  EXPECT_NEAR(roots[2], 3, 1e-12);
  // (x-2)(x^2+1) = x^3 - 2x^2 + x - 2
  ASSERT_EQ(SolveCubicReal(1, -2, 1, -2, roots), 1);
  EXPECT_NEAR(roots[0], 2, 1e-12);
}

TEST(Polynomial, QuadraticStable) {
  double roots[2];
  ASSERT_EQ(SolveQuadraticReal(1, -1e8, 1, roots), 2);
  std::sort(roots, roots + 2);
  EXPECT_NEAR(roots[0], 1e-8, 1e-20);
  EXPECT_NEAR(roots[1], 1e8, 1e-4);
  EXPECT_EQ(SolveQuadraticReal(1, 0, 1, roots), 0);
}

}  // namespace
}  // namespace parallax
