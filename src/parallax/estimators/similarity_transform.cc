#include "parallax/estimators/similarity_transform.h"

#include <optional>
#include <utility>

#include "parallax/geometry/similarity.h"
#include "parallax/optim/ransac.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// Umeyama on any number >= 3 of correspondences: minimal in RANSAC, least squares in LO.
struct Sim3dEstimator {
  using X_t = Eigen::Vector3d;
  using Y_t = Eigen::Vector3d;
  using M_t = Sim3d;
  static constexpr int kMinNumSamples = 3;

  void Estimate(const std::vector<X_t>& src, const std::vector<Y_t>& dst,
                std::vector<M_t>* models) const {
    models->clear();
    if (std::optional<Sim3d> dst_from_src = EstimateSim3d(src, dst)) {
      models->push_back(*dst_from_src);
    }
  }

  void Residuals(const std::vector<X_t>& src, const std::vector<Y_t>& dst, const M_t& dst_from_src,
                 std::vector<double>* squared_residuals) const {
    const Eigen::Matrix3d scaled_rotation =
        dst_from_src.scale * dst_from_src.rotation.toRotationMatrix();
    squared_residuals->resize(src.size());
    for (size_t i = 0; i < src.size(); ++i) {
      (*squared_residuals)[i] =
          (scaled_rotation * src[i] + dst_from_src.translation - dst[i]).squaredNorm();
    }
  }
};

}  // namespace

RansacOptions Sim3dRansacOptions(double max_error) {
  RansacOptions options;
  options.max_error = max_error;
  options.max_num_trials = 2000;
  options.confidence = 0.9999;
  options.min_inlier_ratio = 0.1;
  return options;
}

Sim3dRansacReport EstimateSim3dRansac(const std::vector<Eigen::Vector3d>& src,
                                      const std::vector<Eigen::Vector3d>& dst,
                                      const RansacOptions& options) {
  PARALLAX_CHECK_EQ(src.size(), dst.size());
  Sim3dRansacReport report;
  const LoRansac<Sim3dEstimator> ransac(options);
  const RansacReport<Sim3d> ransac_report = ransac.Estimate(src, dst);
  if (!ransac_report.success) return report;

  // Final least-squares refit on all inliers (LO refits only while the score improves).
  std::vector<Eigen::Vector3d> src_inliers;
  std::vector<Eigen::Vector3d> dst_inliers;
  for (size_t i = 0; i < src.size(); ++i) {
    if (ransac_report.inlier_mask[i]) {
      src_inliers.push_back(src[i]);
      dst_inliers.push_back(dst[i]);
    }
  }
  const Sim3dEstimator estimator;
  std::vector<double> squared_residuals;
  const double max_squared_error = options.max_error * options.max_error;
  auto count_inliers = [&](const Sim3d& dst_from_src, std::vector<char>* inlier_mask) {
    estimator.Residuals(src, dst, dst_from_src, &squared_residuals);
    inlier_mask->resize(src.size());
    size_t num_inliers = 0;
    for (size_t i = 0; i < src.size(); ++i) {
      (*inlier_mask)[i] = squared_residuals[i] <= max_squared_error;
      num_inliers += (*inlier_mask)[i];
    }
    return num_inliers;
  };

  report.dst_from_src = ransac_report.model;
  report.inlier_mask = ransac_report.inlier_mask;
  report.num_inliers = ransac_report.num_inliers;
  if (std::optional<Sim3d> refit = EstimateSim3d(src_inliers, dst_inliers)) {
    std::vector<char> refit_inlier_mask;
    const size_t refit_num_inliers = count_inliers(*refit, &refit_inlier_mask);
    // Keep the refit only when it keeps at least the support of the RANSAC model.
    if (refit_num_inliers >= report.num_inliers) {
      report.dst_from_src = *refit;
      report.inlier_mask = std::move(refit_inlier_mask);
      report.num_inliers = refit_num_inliers;
    }
  }
  report.success = true;
  return report;
}

}  // namespace parallax
