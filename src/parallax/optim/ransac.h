#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "parallax/math/random.h"
#include "parallax/optim/progressive_sampler.h"
#include "parallax/util/check.h"

namespace parallax {

// The one RANSAC of Parallax. An estimator is any type with
//
//   using X_t = ...; using Y_t = ...; using M_t = ...;
//   static constexpr int kMinNumSamples = ...;
//   // Every model consistent with the points (minimal or least squares on more); may return none.
//   void Estimate(const std::vector<X_t>& X, const std::vector<Y_t>& Y, std::vector<M_t>* models)
//   const;
//   // Squared residual of every correspondence under `model`.
//   void Residuals(const std::vector<X_t>& X, const std::vector<Y_t>& Y, const M_t& model,
//                  std::vector<double>* squared_residuals) const;
//
// LoRansac draws minimal samples, scores each model by MSAC (sum of truncated squared
// residuals), and whenever a new best model appears runs local optimisation: the local
// estimator (non-minimal, e.g. the 8-point on all inliers) re-fits on the inliers, iterated
// while the score improves (Chum et al., "Locally Optimized RANSAC", 2003). The number of
// trials adapts to the best inlier ratio seen. Samples are uniform, or progressive (PROSAC)
// for correspondences sorted from the most to the least likely inlier.

// How LoRansac draws its minimal samples.
enum class RansacSampler {
  kUniform,      // Uniformly among all correspondences.
  kProgressive,  // PROSAC (ProgressiveSampler): the correspondences' order is their quality.
};

struct RansacOptions {
  // Inlier threshold on the residual (the estimator's unit, not squared; estimators that
  // take pixels say so and convert).
  double max_error = 1.0;
  // Lowest inlier ratio searched for: bounds the number of trials from above, to the count
  // that finds a sample of this ratio with `confidence`, times the multiplier. A caller that
  // knows how many inliers would change its outcome raises it (two-view verification).
  double min_inlier_ratio = 0.1;
  double min_inlier_ratio_trials_multiplier = 3.0;
  // Probability of having drawn at least one all-inlier sample when stopping.
  double confidence = 0.9999;
  // Multiplier on the adaptive trial count (>1 to be conservative with non-uniform outliers).
  double dynamic_num_trials_multiplier = 3.0;
  int min_num_trials = 0;
  int max_num_trials = 10000;
  // Local optimisation rounds per new best model (0 disables LO).
  int local_optimization_iterations = 10;
  // How samples are drawn; kProgressive only where the correspondences come sorted by quality
  // (feature matches by Lowe's ratio: FeatureMatchingOptions::order_by_ratio). Uniform by
  // default: progressive sampling verified fewer image pairs (docs/performance.md, "Two-view
  // RANSAC: uniform samples, not PROSAC").
  RansacSampler sampler = RansacSampler::kUniform;
  // kProgressive: the trial by which its samples have grown to all correspondences (PROSAC's
  // T_N; Chum & Matas's 200,000). Beyond the trial caps, so that a search stopped early has
  // sampled mostly the best matches.
  double progressive_num_trials = 200000;
  // kProgressive's stopping rule, PROSAC's (ProsacTermination): the share of correspondences
  // that a wrong model explains by chance (its beta), bounding how many inliers among the n
  // best a model must have to mean anything.
  double progressive_chance_inlier_ratio = 0.05;
  // Seed of the run's own generator: the same seed and data draw the same samples, whatever
  // thread runs it. Callers that run many estimations derive one seed per run (DeriveSeed).
  uint64_t random_seed = 0;

  void Check() const {
    PARALLAX_CHECK_GT(max_error, 0.0);
    PARALLAX_CHECK(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0);
    PARALLAX_CHECK_GT(min_inlier_ratio_trials_multiplier, 0.0);
    PARALLAX_CHECK(confidence > 0.0 && confidence < 1.0);
    PARALLAX_CHECK_GE(dynamic_num_trials_multiplier, 0.0);
    PARALLAX_CHECK_GE(min_num_trials, 0);
    PARALLAX_CHECK_GT(max_num_trials, 0);
    PARALLAX_CHECK_LE(min_num_trials, max_num_trials);
    PARALLAX_CHECK_GE(local_optimization_iterations, 0);
    PARALLAX_CHECK(sampler == RansacSampler::kUniform || sampler == RansacSampler::kProgressive);
    PARALLAX_CHECK_GT(progressive_num_trials, 0.0);
    PARALLAX_CHECK(progressive_chance_inlier_ratio > 0.0 && progressive_chance_inlier_ratio < 1.0);
  }
};

template <typename Model>
struct RansacReport {
  bool success = false;
  size_t num_trials = 0;
  size_t num_inliers = 0;
  // 1 for inliers of `model`, one entry per correspondence.
  std::vector<char> inlier_mask;
  Model model;
};

// Number of trials needed to draw one all-inlier sample of size `sample_size` with
// probability `confidence`, when `num_inliers` of the `num_samples` correspondences are
// inliers. A sample is drawn without replacement, so it is all inliers with probability
//   P = prod_{i < k} (num_inliers - i) / (num_samples - i),
// not (num_inliers / num_samples)^k, which overstates P (and understates the trials) the
// more the fewer the inliers or correspondences (Schoenberger, Larsson & Pollefeys, "Fixing
// the RANSAC stopping criterion", 2025; COLMAP's since). The maximum when P is 0 (fewer
// inliers than the sample), 1 when every correspondence is an inlier.
inline size_t ComputeNumRansacTrials(size_t num_inliers, size_t num_samples, size_t sample_size,
                                     double confidence, double multiplier) {
  num_inliers = std::min(num_inliers, num_samples);
  if (num_inliers < sample_size) return std::numeric_limits<size_t>::max();
  double all_inlier_probability = 1.0;
  for (size_t i = 0; i < sample_size; ++i) {
    all_inlier_probability *=
        static_cast<double>(num_inliers - i) / static_cast<double>(num_samples - i);
  }
  if (all_inlier_probability <= std::numeric_limits<double>::epsilon()) {
    return std::numeric_limits<size_t>::max();
  }
  if (all_inlier_probability >= 1.0 - std::numeric_limits<double>::epsilon()) return 1;
  const double trials = std::log(1.0 - confidence) / std::log(1.0 - all_inlier_probability);
  const double needed = std::ceil(multiplier * trials);
  if (!(needed < static_cast<double>(std::numeric_limits<size_t>::max()))) {
    return std::numeric_limits<size_t>::max();
  }
  return static_cast<size_t>(needed);
}

// PROSAC's stopping rule (Chum & Matas 2005, sec. 2.2) for progressive sampling, whose
// samples all come from the n best correspondences: stop once the best model's inliers among
// them, I_n,
//  - are not random: a model fit to a sample with an outlier has each other correspondence
//    as an inlier with probability beta, so I_n - m ~ Binomial(n - m, beta); I_n must be at
//    least the count that such a model reaches with probability below 5 %;
//  - are maximal: the trials so far would have drawn an all-inlier sample of the n best with
//    `confidence` (ComputeNumRansacTrials of I_n among n, with `multiplier`). The progressive
//    samples of a quality order are at least as likely all inliers as uniform ones of the n
//    best, so this is the uniform bound on a smaller, cleaner set.
// Where the best matches come first, the n best hold far fewer outliers than all N, and the
// search stops long before the bound for all N (which still applies).
class ProsacTermination {
 public:
  ProsacTermination(size_t sample_size, double confidence, double multiplier,
                    double chance_inlier_ratio)
      : sample_size_(sample_size),
        confidence_(confidence),
        multiplier_(multiplier),
        beta_(chance_inlier_ratio) {}

  // After `num_trials` trials drawn from the n best, of which the best model explains
  // `num_inliers`.
  bool Satisfied(size_t num_trials, size_t n, size_t num_inliers) {
    if (num_inliers < MinNonRandomInliers(n)) return false;
    return num_trials >=
           ComputeNumRansacTrials(num_inliers, n, sample_size_, confidence_, multiplier_);
  }

  // m + the smallest j with P[Binomial(n - m, beta) >= j] < 5 %.
  size_t MinNonRandomInliers(size_t n) {
    if (n < min_inliers_.size()) return min_inliers_[n];
    min_inliers_.resize(n + 1, 0);
    for (size_t k = first_unknown_; k <= n; ++k) {
      const size_t trials = k > sample_size_ ? k - sample_size_ : 0;
      // P[X <= j - 1] >= 0.95 first at j: the pmf summed up from 0, in logs to not underflow.
      const double log_beta = std::log(beta_), log_rest = std::log1p(-beta_);
      const double log_n_factorial = std::lgamma(static_cast<double>(trials) + 1.0);
      double cdf = 0.0;
      size_t j = 0;
      for (; j <= trials && cdf < 1.0 - kPsi; ++j) {
        cdf += std::exp(log_n_factorial - std::lgamma(static_cast<double>(j) + 1.0) -
                        std::lgamma(static_cast<double>(trials - j) + 1.0) +
                        static_cast<double>(j) * log_beta +
                        static_cast<double>(trials - j) * log_rest);
      }
      min_inliers_[k] = sample_size_ + j;
    }
    first_unknown_ = n + 1;
    return min_inliers_[n];
  }

 private:
  static constexpr double kPsi = 0.05;  // The paper's chance of a random model passing.
  const size_t sample_size_;
  const double confidence_, multiplier_, beta_;
  std::vector<size_t> min_inliers_;  // By n, computed up to first_unknown_ - 1.
  size_t first_unknown_ = 0;
};

template <typename Estimator, typename LocalEstimator = Estimator>
class LoRansac {
 public:
  using X_t = typename Estimator::X_t;
  using Y_t = typename Estimator::Y_t;
  using M_t = typename Estimator::M_t;
  using Report = RansacReport<M_t>;

  explicit LoRansac(const RansacOptions& options, Estimator estimator = {},
                    LocalEstimator local_estimator = {})
      : options_(options),
        estimator_(std::move(estimator)),
        local_estimator_(std::move(local_estimator)) {
    options_.Check();
  }

  Report Estimate(const std::vector<X_t>& X, const std::vector<Y_t>& Y) const {
    return Estimate(X, Y, [](const M_t&, size_t) { return size_t{0}; });
  }

  // As above, with `inliers_sought(model, num_inliers)`: the fewest inliers a model like
  // this new best one would need to matter to the caller (two-view verification: the count
  // its significance test needs at this model's chance rate). While the best model has fewer,
  // the trials are bounded by the ratio of that count, with min_inlier_ratio's multiplier, as
  // min_inlier_ratio bounds them: RANSAC stops searching for models the caller would reject
  // anyway, instead of proving to `confidence` that no such model exists.
  template <typename InliersSought>
  Report Estimate(const std::vector<X_t>& X, const std::vector<Y_t>& Y,
                  const InliersSought& inliers_sought) const {
    PARALLAX_CHECK_EQ(X.size(), Y.size());
    Report report;
    const size_t num_samples = X.size();
    constexpr size_t kSampleSize = Estimator::kMinNumSamples;
    if (num_samples < kSampleSize) return report;

    const double max_squared_error = options_.max_error * options_.max_error;
    std::vector<size_t> indices(num_samples);
    std::iota(indices.begin(), indices.end(), 0);
    std::vector<X_t> X_sample(kSampleSize);
    std::vector<Y_t> Y_sample(kSampleSize);
    std::vector<M_t> models;
    std::vector<double> residuals;

    Score best;
    M_t best_model{};
    std::mt19937_64 generator(options_.random_seed);
    size_t max_trials = static_cast<size_t>(options_.max_num_trials);
    max_trials = std::min(
        max_trials,
        ComputeNumRansacTrials(
            static_cast<size_t>(std::ceil(options_.min_inlier_ratio * num_samples)), num_samples,
            kSampleSize, options_.confidence, options_.min_inlier_ratio_trials_multiplier));
    const size_t max_trials_floor = static_cast<size_t>(options_.min_num_trials);
    max_trials = std::max(max_trials, max_trials_floor);

    const bool progressive = options_.sampler == RansacSampler::kProgressive;
    ProgressiveSampler progressive_sampler(num_samples, kSampleSize,
                                           options_.progressive_num_trials);
    ProsacTermination prosac_termination(kSampleSize, options_.confidence,
                                         options_.dynamic_num_trials_multiplier,
                                         options_.progressive_chance_inlier_ratio);
    std::vector<size_t> sample;
    // Progressive: the best model's inliers among the i best correspondences, by i.
    std::vector<size_t> best_inliers_in_head;
    size_t trial = 0;
    for (; trial < max_trials; ++trial) {
      if (progressive) {
        progressive_sampler.Sample(&generator, &sample);
      } else {
        Shuffle(kSampleSize, &indices, &generator);
      }
      const std::vector<size_t>& sample_indices = progressive ? sample : indices;
      for (size_t i = 0; i < kSampleSize; ++i) {
        X_sample[i] = X[sample_indices[i]];
        Y_sample[i] = Y[sample_indices[i]];
      }
      models.clear();
      estimator_.Estimate(X_sample, Y_sample, &models);
      for (const M_t& model : models) {
        const Score score = ScoreModel(X, Y, model, max_squared_error, &residuals);
        if (!score.BetterThan(best)) continue;
        best = score;
        best_model = model;
        if (options_.local_optimization_iterations > 0) {
          LocalOptimize(X, Y, max_squared_error, &best, &best_model, &residuals);
        }
        size_t needed =
            ComputeNumRansacTrials(best.num_inliers, num_samples, kSampleSize, options_.confidence,
                                   options_.dynamic_num_trials_multiplier);
        const size_t sought = inliers_sought(best_model, best.num_inliers);
        if (best.num_inliers < sought) {
          needed =
              std::min(needed, ComputeNumRansacTrials(std::min(sought, num_samples), num_samples,
                                                      kSampleSize, options_.confidence,
                                                      options_.min_inlier_ratio_trials_multiplier));
        }
        max_trials = std::max<size_t>(std::min(max_trials, needed), options_.min_num_trials);
        if (progressive) {
          estimator_.Residuals(X, Y, best_model, &residuals);
          best_inliers_in_head.assign(num_samples + 1, 0);
          for (size_t i = 0; i < num_samples; ++i) {
            best_inliers_in_head[i + 1] =
                best_inliers_in_head[i] + (residuals[i] <= max_squared_error);
          }
        }
      }
      if (progressive && !best_inliers_in_head.empty() && trial + 1 >= max_trials_floor) {
        const size_t n = progressive_sampler.NumPointsSampled();
        if (prosac_termination.Satisfied(trial + 1, n, best_inliers_in_head[n])) {
          ++trial;
          break;
        }
      }
    }

    report.num_trials = trial;
    if (best.num_inliers < kSampleSize) return report;
    report.success = true;
    report.model = best_model;
    estimator_.Residuals(X, Y, best_model, &residuals);
    report.inlier_mask.resize(num_samples);
    report.num_inliers = 0;
    for (size_t i = 0; i < num_samples; ++i) {
      report.inlier_mask[i] = residuals[i] <= max_squared_error;
      report.num_inliers += report.inlier_mask[i];
    }
    return report;
  }

 private:
  struct Score {
    size_t num_inliers = 0;
    double msac = std::numeric_limits<double>::max();
    bool BetterThan(const Score& other) const { return msac < other.msac; }
  };

  Score ScoreModel(const std::vector<X_t>& X, const std::vector<Y_t>& Y, const M_t& model,
                   double max_squared_error, std::vector<double>* residuals) const {
    estimator_.Residuals(X, Y, model, residuals);
    Score score;
    score.msac = 0;
    for (double r : *residuals) {
      // NaN residuals (degenerate model) count as outliers.
      if (r <= max_squared_error) {
        ++score.num_inliers;
        score.msac += r;
      } else {
        score.msac += max_squared_error;
      }
    }
    return score;
  }

  void LocalOptimize(const std::vector<X_t>& X, const std::vector<Y_t>& Y, double max_squared_error,
                     Score* best, M_t* best_model, std::vector<double>* residuals) const {
    std::vector<X_t> X_inliers;
    std::vector<Y_t> Y_inliers;
    std::vector<M_t> local_models;
    for (int iteration = 0; iteration < options_.local_optimization_iterations; ++iteration) {
      estimator_.Residuals(X, Y, *best_model, residuals);
      X_inliers.clear();
      Y_inliers.clear();
      for (size_t i = 0; i < X.size(); ++i) {
        if ((*residuals)[i] <= max_squared_error) {
          X_inliers.push_back(X[i]);
          Y_inliers.push_back(Y[i]);
        }
      }
      if (X_inliers.size() < static_cast<size_t>(LocalEstimator::kMinNumSamples)) return;
      local_models.clear();
      local_estimator_.Estimate(X_inliers, Y_inliers, &local_models);
      bool improved = false;
      for (const M_t& model : local_models) {
        const Score score = ScoreModel(X, Y, model, max_squared_error, residuals);
        if (score.BetterThan(*best)) {
          *best = score;
          *best_model = model;
          improved = true;
        }
      }
      if (!improved) return;
    }
  }

  RansacOptions options_;
  Estimator estimator_;
  LocalEstimator local_estimator_;
};

}  // namespace parallax
