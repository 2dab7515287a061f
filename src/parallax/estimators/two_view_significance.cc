#include "parallax/estimators/two_view_significance.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace parallax {
namespace {
// Re-paired matches evaluated to estimate the chance that an unrelated match is an inlier.
constexpr size_t kMaxNumChancePairs = 4096;
}  // namespace

double Log10BinomialTail(size_t n, size_t k, double p) {
  if (k == 0) return 0.0;
  if (k > n || p <= 0.0) return -std::numeric_limits<double>::infinity();
  if (p >= 1.0) return 0.0;
  const double log_p = std::log(p), log_q = std::log1p(-p);
  const double lgamma_n = std::lgamma(static_cast<double>(n) + 1.0);
  double max_term = -std::numeric_limits<double>::infinity();
  double sum = 0.0;  // Of exp(term - max_term).
  for (size_t j = k; j <= n; ++j) {
    const double jd = static_cast<double>(j), rest = static_cast<double>(n - j);
    const double term =
        lgamma_n - std::lgamma(jd + 1.0) - std::lgamma(rest + 1.0) + jd * log_p + rest * log_q;
    if (term > max_term) {
      sum = sum * std::exp(max_term - term) + 1.0;
      max_term = term;
    } else {
      sum += std::exp(term - max_term);
      // Past the mode the terms fall geometrically: the rest no longer counts.
      if (term < max_term - 40.0) break;
    }
  }
  return (max_term + std::log(sum)) / std::log(10.0);
}

void ChancePairs(const std::vector<Eigen::Vector2d>& points1,
                 const std::vector<Eigen::Vector2d>& points2, uint64_t seed,
                 std::vector<Eigen::Vector2d>* chance1, std::vector<Eigen::Vector2d>* chance2) {
  const size_t n = points1.size();
  chance1->clear();
  chance2->clear();
  if (n < 2) return;
  if (n * (n - 1) <= kMaxNumChancePairs) {
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = 0; j < n; ++j) {
        if (i == j) continue;
        chance1->push_back(points1[i]);
        chance2->push_back(points2[j]);
      }
    }
    return;
  }
  std::mt19937_64 generator(seed);
  std::uniform_int_distribution<size_t> first(0, n - 1), second(0, n - 2);
  for (size_t pair = 0; pair < kMaxNumChancePairs; ++pair) {
    const size_t i = first(generator);
    size_t j = second(generator);
    if (j >= i) ++j;
    chance1->push_back(points1[i]);
    chance2->push_back(points2[j]);
  }
}

double Log10NumFalseAlarmsFromChance(size_t n, size_t sample_size, size_t num_inliers, double p,
                                     int models_per_sample) {
  const size_t s = sample_size;
  if (num_inliers <= s || n <= s) return std::numeric_limits<double>::infinity();
  const double log10_num_samples =
      (std::lgamma(static_cast<double>(n) + 1.0) - std::lgamma(static_cast<double>(s) + 1.0) -
       std::lgamma(static_cast<double>(n - s) + 1.0)) /
      std::log(10.0);
  return std::log10(static_cast<double>(models_per_sample)) + log10_num_samples +
         Log10BinomialTail(n - s, num_inliers - s, p);
}

bool AreNearlyCollinear(const std::vector<Eigen::Vector2d>& points, const std::vector<char>& mask,
                        double tolerance) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  size_t count = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!mask[i]) continue;
    mean += points[i];
    ++count;
  }
  if (count < 3) return true;
  mean /= static_cast<double>(count);
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  for (size_t i = 0; i < points.size(); ++i) {
    if (!mask[i]) continue;
    const Eigen::Vector2d centered = points[i] - mean;
    covariance += centered * centered.transpose();
  }
  covariance /= static_cast<double>(count);
  // Smallest eigenvalue of the symmetric 2x2 covariance in closed form.
  const double half_trace = 0.5 * covariance.trace();
  const double half_difference = 0.5 * (covariance(0, 0) - covariance(1, 1));
  const double min_variance = half_trace - std::sqrt(half_difference * half_difference +
                                                     covariance(0, 1) * covariance(0, 1));
  return !(min_variance > tolerance * tolerance);
}

size_t CountDistinctKeypoints(const FeatureMatches& matches, const std::vector<char>& mask) {
  std::vector<point2D_t> indices1, indices2;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (!mask[i]) continue;
    indices1.push_back(matches[i].point2D_idx1);
    indices2.push_back(matches[i].point2D_idx2);
  }
  const auto count_distinct = [](std::vector<point2D_t>* indices) {
    std::sort(indices->begin(), indices->end());
    return static_cast<size_t>(std::unique(indices->begin(), indices->end()) - indices->begin());
  };
  return std::min(count_distinct(&indices1), count_distinct(&indices2));
}

}  // namespace parallax
