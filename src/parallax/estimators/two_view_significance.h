#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "parallax/estimators/solvers/essential_matrix.h"
#include "parallax/estimators/solvers/fundamental_matrix.h"
#include "parallax/estimators/solvers/homography_matrix.h"
#include "parallax/feature/types.h"

namespace parallax {

// Whether a two-view model found by RANSAC means anything: the a-contrario significance of
// its inliers, and the degenerate inlier sets (collinear, or one keypoint matched many times)
// that every model of the family explains.

// Largest numbers of models one minimal sample of each solver yields: the multiplicity of
// the a-contrario test.
template <typename Estimator>
inline constexpr int kMaxModelsPerSample = 1;
template <>
inline constexpr int kMaxModelsPerSample<EssentialMatrixFivePointEstimator> = 10;
template <>
inline constexpr int kMaxModelsPerSample<FundamentalMatrixSevenPointEstimator> = 3;

// log10 of the binomial tail P[X >= k], X ~ Binomial(n, p).
double Log10BinomialTail(size_t n, size_t k, double p);

// The matched keypoints re-paired (x1_i with x2_j, i != j): all such pairs when few, else
// 4,096 drawn from a generator seeded with `seed`.
void ChancePairs(const std::vector<Eigen::Vector2d>& points1,
                 const std::vector<Eigen::Vector2d>& points2, uint64_t seed,
                 std::vector<Eigen::Vector2d>* chance1, std::vector<Eigen::Vector2d>* chance2);

// log10 of the number of false alarms of a model with `num_inliers` of n matches, from the
// chance p that an unrelated match is an inlier (see Log10NumFalseAlarms).
double Log10NumFalseAlarmsFromChance(size_t n, size_t sample_size, size_t num_inliers, double p,
                                     int models_per_sample);

// The chance p that an unrelated match is an inlier of `model`: the share of the re-paired
// matches (ChancePairs) within max_error, with one inlier more than seen, so that a finite
// sample never gives p = 0. `residuals` is scratch space.
template <typename Estimator>
double ChanceInlierRate(const Estimator& estimator, const std::vector<Eigen::Vector2d>& chance1,
                        const std::vector<Eigen::Vector2d>& chance2, const Eigen::Matrix3d& model,
                        double max_error, std::vector<double>* residuals) {
  estimator.Residuals(chance1, chance2, model, residuals);
  const double max_squared_error = max_error * max_error;
  size_t num_chance_inliers = 0;
  for (const double residual : *residuals) num_chance_inliers += residual <= max_squared_error;
  return static_cast<double>(num_chance_inliers + 1) / static_cast<double>(residuals->size() + 1);
}

// The a-contrario number of false alarms of a model with `num_inliers` of the n matches
// (Moisan & Stival, "A probabilistic criterion to detect rigid point matches between two
// images and estimate the fundamental matrix", IJCV 2004): the expected number of models,
// among the up to models_per_sample * C(n, s) that minimal samples of s matches yield, that
// would explain as many matches if these were chance pairings,
//   NFA = models_per_sample * C(n, s) * P[Binomial(n - s, p) >= num_inliers - s].
// p, the chance that an unrelated match is an inlier, is measured on the matched keypoints
// themselves re-paired (ChancePairs), so it reflects where keypoints lie in these images
// (often a small part of them) rather than a uniform spread. Returns log10(NFA).
template <typename Estimator>
double Log10NumFalseAlarms(const Estimator& estimator, const std::vector<Eigen::Vector2d>& points1,
                           const std::vector<Eigen::Vector2d>& points2,
                           const Eigen::Matrix3d& model, double max_error, size_t num_inliers,
                           uint64_t seed) {
  const size_t n = points1.size();
  constexpr size_t s = Estimator::kMinNumSamples;
  if (num_inliers <= s || n <= s) return std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector2d> chance1, chance2;
  ChancePairs(points1, points2, seed, &chance1, &chance2);
  std::vector<double> residuals;
  const double p = ChanceInlierRate(estimator, chance1, chance2, model, max_error, &residuals);
  return Log10NumFalseAlarmsFromChance(n, s, num_inliers, p, kMaxModelsPerSample<Estimator>);
}

// The fewest inliers with which a model would pass the significance test, log10(NFA) <=
// max_log10_num_false_alarms, at the chance rate p of a given model: RANSAC's inliers_sought
// in two-view verification, so that on a pair whose matches are chance it stops once the
// models it finds are far from significant, instead of proving to its confidence that no
// model has min_num_inliers (on templeRing such pairs, two thirds of the exhaustive ones,
// took most of verification's time). The re-pairing is drawn once, with the seed of the
// final test, so p is the one that test measures for the same model. Returns 0 for a model
// that is significant already, n + 1 when no count of inliers would make it so.
template <typename Estimator>
class SignificantInlierCount {
 public:
  SignificantInlierCount(const std::vector<Eigen::Vector2d>& points1,
                         const std::vector<Eigen::Vector2d>& points2, double max_error,
                         uint64_t seed, double max_log10_num_false_alarms)
      : n_(points1.size()),
        max_error_(max_error),
        max_log10_num_false_alarms_(max_log10_num_false_alarms) {
    ChancePairs(points1, points2, seed, &chance1_, &chance2_);
  }

  size_t operator()(const Eigen::Matrix3d& model, size_t num_inliers) const {
    constexpr size_t s = Estimator::kMinNumSamples;
    if (n_ <= s || chance1_.empty()) return 0;
    const double p =
        ChanceInlierRate(Estimator(), chance1_, chance2_, model, max_error_, &residuals_);
    const auto significant = [&](size_t k) {
      return Log10NumFalseAlarmsFromChance(n_, s, k, p, kMaxModelsPerSample<Estimator>) <=
             max_log10_num_false_alarms_;
    };
    if (significant(num_inliers)) return 0;
    if (!significant(n_)) return n_ + 1;
    // The number of false alarms falls as the inliers grow: the first significant count.
    size_t low = num_inliers, high = n_;  // significant(high), !significant(low).
    while (high - low > 1) {
      const size_t middle = low + (high - low) / 2;
      (significant(middle) ? high : low) = middle;
    }
    return high;
  }

 private:
  size_t n_;
  double max_error_;
  double max_log10_num_false_alarms_;
  std::vector<Eigen::Vector2d> chance1_, chance2_;
  mutable std::vector<double> residuals_;
};

// True when the masked points spread less than `tolerance` across their principal line (or
// all coincide): no two-view model is determined by them.
bool AreNearlyCollinear(const std::vector<Eigen::Vector2d>& points, const std::vector<char>& mask,
                        double tolerance);

// The smaller of the numbers of distinct keypoints of image 1 and of image 2 among the
// masked matches.
size_t CountDistinctKeypoints(const FeatureMatches& matches, const std::vector<char>& mask);

}  // namespace parallax
