#include "parallax/geometry/similarity.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

#include "parallax/util/check.h"

namespace parallax {
namespace {

// Below this ratio of the second to the first principal variance the source points count as
// collinear: the rotation about their common line is then undetermined.
constexpr double kMinVarianceRatio = 1e-12;

}  // namespace

std::optional<Sim3d> EstimateSim3d(const std::vector<Eigen::Vector3d>& src,
                                   const std::vector<Eigen::Vector3d>& dst) {
  PARALLAX_CHECK_EQ(src.size(), dst.size());
  const size_t num_points = src.size();
  if (num_points < 3) return std::nullopt;

  Eigen::Vector3d src_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d dst_mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    if (!src[i].allFinite() || !dst[i].allFinite()) return std::nullopt;
    src_mean += src[i];
    dst_mean += dst[i];
  }
  src_mean /= static_cast<double>(num_points);
  dst_mean /= static_cast<double>(num_points);

  // Cross-covariance Sigma = 1/n sum (dst_i - mu_dst)(src_i - mu_src)^T and source scatter.
  Eigen::Matrix3d cross_covariance = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d src_covariance = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < num_points; ++i) {
    const Eigen::Vector3d src_centered = src[i] - src_mean;
    cross_covariance.noalias() += (dst[i] - dst_mean) * src_centered.transpose();
    src_covariance.noalias() += src_centered * src_centered.transpose();
  }
  cross_covariance /= static_cast<double>(num_points);
  src_covariance /= static_cast<double>(num_points);

  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> src_eigen(src_covariance,
                                                                 Eigen::EigenvaluesOnly);
  const Eigen::Vector3d src_variances = src_eigen.eigenvalues();  // Ascending.
  const double src_variance = src_covariance.trace();
  if (!(src_variance > 0) || src_variances(1) <= kMinVarianceRatio * src_variances(2)) {
    return std::nullopt;
  }

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross_covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d singular_values = svd.singularValues();
  // A rank < 2 cross-covariance (e.g. all dst points equal) leaves the rotation free.
  if (!(singular_values(1) > kMinVarianceRatio * singular_values(0))) return std::nullopt;

  // S flips the weakest axis when U V^T would be a reflection (Umeyama's eq. 39).
  Eigen::Vector3d signs = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) signs(2) = -1;
  const Eigen::Matrix3d rotation = svd.matrixU() * signs.asDiagonal() * svd.matrixV().transpose();
  const double scale = singular_values.dot(signs) / src_variance;
  if (!std::isfinite(scale) || scale <= 0) return std::nullopt;

  Sim3d dst_from_src;
  dst_from_src.scale = scale;
  dst_from_src.rotation = Eigen::Quaterniond(rotation).normalized();
  dst_from_src.translation = dst_mean - scale * (rotation * src_mean);
  return dst_from_src;
}

}  // namespace parallax
