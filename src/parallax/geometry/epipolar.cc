#include "parallax/geometry/epipolar.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr double kMaxError = std::numeric_limits<double>::max();

// The nine entries as locals: the residual loops are RANSAC's inner loop, and copies that
// cannot alias the output let the compiler keep them in registers and vectorise.
struct Entries {
  double m00, m01, m02, m10, m11, m12, m20, m21, m22;
  explicit Entries(const Eigen::Matrix3d& M)
      : m00(M(0, 0)),
        m01(M(0, 1)),
        m02(M(0, 2)),
        m10(M(1, 0)),
        m11(M(1, 1)),
        m12(M(1, 2)),
        m20(M(2, 0)),
        m21(M(2, 1)),
        m22(M(2, 2)) {}
};

inline double SampsonError(const Entries& F, const Eigen::Vector2d& point1,
                           const Eigen::Vector2d& point2) {
  const double x1 = point1.x(), y1 = point1.y(), x2 = point2.x(), y2 = point2.y();
  const double line2_x = F.m00 * x1 + F.m01 * y1 + F.m02;  // F x1
  const double line2_y = F.m10 * x1 + F.m11 * y1 + F.m12;
  const double line2_z = F.m20 * x1 + F.m21 * y1 + F.m22;
  const double line1_x = F.m00 * x2 + F.m10 * y2 + F.m20;  // F^T x2
  const double line1_y = F.m01 * x2 + F.m11 * y2 + F.m21;
  const double epipolar = x2 * line2_x + y2 * line2_y + line2_z;
  const double gradient_squared =
      line2_x * line2_x + line2_y * line2_y + line1_x * line1_x + line1_y * line1_y;
  const double error = epipolar * epipolar / gradient_squared;
  // NaN and Inf fail the comparison, 0/0 from a zero gradient included (branch-free select).
  return error <= kMaxError ? error : kMaxError;
}

inline double TransferError(const Entries& H, const Eigen::Vector2d& point1,
                            const Eigen::Vector2d& point2) {
  const double x1 = point1.x(), y1 = point1.y();
  const double inverse_w = 1.0 / (H.m20 * x1 + H.m21 * y1 + H.m22);
  const double dx = (H.m00 * x1 + H.m01 * y1 + H.m02) * inverse_w - point2.x();
  const double dy = (H.m10 * x1 + H.m11 * y1 + H.m12) * inverse_w - point2.y();
  const double error = dx * dx + dy * dy;
  // A point mapped to infinity gives Inf or NaN, which fail the comparison.
  return error <= kMaxError ? error : kMaxError;
}

}  // namespace

double ComputeSquaredSampsonError(const Eigen::Vector2d& point1, const Eigen::Vector2d& point2,
                                  const Eigen::Matrix3d& F) {
  return SampsonError(Entries(F), point1, point2);
}

void ComputeSquaredSampsonError(const std::vector<Eigen::Vector2d>& points1,
                                const std::vector<Eigen::Vector2d>& points2,
                                const Eigen::Matrix3d& F, std::vector<double>* squared_errors) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  const size_t num_points = points1.size();
  squared_errors->resize(num_points);
  const Entries entries(F);
  const Eigen::Vector2d* first = points1.data();
  const Eigen::Vector2d* second = points2.data();
  double* errors = squared_errors->data();
  for (size_t i = 0; i < num_points; ++i) errors[i] = SampsonError(entries, first[i], second[i]);
}

double ComputeSquaredSphericalSampsonError(const Eigen::Vector3d& ray1, const Eigen::Vector3d& ray2,
                                           const Eigen::Matrix3d& E) {
  const Eigen::Vector3d line2 = E * ray1;              // Epipolar plane normal in view 2.
  const Eigen::Vector3d line1 = E.transpose() * ray2;  // And in view 1.
  const double residual = ray2.dot(line2);
  // The residual's gradient with respect to each ray, within the plane tangent to it.
  const Eigen::Vector3d gradient2 = line2 - ray2.dot(line2) * ray2;
  const Eigen::Vector3d gradient1 = line1 - ray1.dot(line1) * ray1;
  const double denominator = gradient1.squaredNorm() + gradient2.squaredNorm();
  return denominator > 0 ? residual * residual / denominator
                         : std::numeric_limits<double>::infinity();
}

void ComputeSquaredSphericalSampsonError(const std::vector<Eigen::Vector3d>& rays1,
                                         const std::vector<Eigen::Vector3d>& rays2,
                                         const Eigen::Matrix3d& E,
                                         std::vector<double>* squared_errors) {
  PARALLAX_CHECK_EQ(rays1.size(), rays2.size());
  squared_errors->resize(rays1.size());
  for (size_t i = 0; i < rays1.size(); ++i) {
    (*squared_errors)[i] = ComputeSquaredSphericalSampsonError(rays1[i], rays2[i], E);
  }
}

double ComputeSquaredHomographyError(const Eigen::Vector2d& point1, const Eigen::Vector2d& point2,
                                     const Eigen::Matrix3d& H) {
  return TransferError(Entries(H), point1, point2);
}

void ComputeSquaredHomographyError(const std::vector<Eigen::Vector2d>& points1,
                                   const std::vector<Eigen::Vector2d>& points2,
                                   const Eigen::Matrix3d& H, std::vector<double>* squared_errors) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  const size_t num_points = points1.size();
  squared_errors->resize(num_points);
  const Entries entries(H);
  const Eigen::Vector2d* first = points1.data();
  const Eigen::Vector2d* second = points2.data();
  double* errors = squared_errors->data();
  for (size_t i = 0; i < num_points; ++i) errors[i] = TransferError(entries, first[i], second[i]);
}

void ComputeSquaredSymmetricTransferError(const std::vector<Eigen::Vector2d>& points1,
                                          const std::vector<Eigen::Vector2d>& points2,
                                          const Eigen::Matrix3d& H,
                                          std::vector<double>* squared_errors) {
  PARALLAX_CHECK_EQ(points1.size(), points2.size());
  squared_errors->resize(points1.size());
  Eigen::Matrix3d H_inverse;
  bool invertible = false;
  double determinant = 0.0;
  H.computeInverseAndDetWithCheck(H_inverse, determinant, invertible,
                                  std::numeric_limits<double>::min());
  if (!invertible || !H_inverse.allFinite()) {
    std::fill(squared_errors->begin(), squared_errors->end(), kMaxError);
    return;
  }
  const Entries forward_entries(H), backward_entries(H_inverse);
  for (size_t i = 0; i < points1.size(); ++i) {
    const double forward = TransferError(forward_entries, points1[i], points2[i]);
    const double backward = TransferError(backward_entries, points2[i], points1[i]);
    (*squared_errors)[i] = (forward == kMaxError || backward == kMaxError)
                               ? kMaxError
                               : std::min(forward + backward, kMaxError);
  }
}

}  // namespace parallax
