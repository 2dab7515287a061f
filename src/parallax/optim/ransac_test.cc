#include "parallax/optim/ransac.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <iostream>
#include <limits>
#include <numeric>

#include "parallax/math/random.h"

namespace parallax {
namespace {

// Fits y = a x + b: minimal with two points, least squares with more.
struct LineEstimator {
  using X_t = double;
  using Y_t = double;
  using M_t = Eigen::Vector2d;
  static constexpr int kMinNumSamples = 2;

  void Estimate(const std::vector<X_t>& X, const std::vector<Y_t>& Y,
                std::vector<M_t>* models) const {
    Eigen::MatrixXd A(X.size(), 2);
    Eigen::VectorXd b(X.size());
    for (size_t i = 0; i < X.size(); ++i) {
      A(i, 0) = X[i];
      A(i, 1) = 1;
      b(i) = Y[i];
    }
    const Eigen::Vector2d model = A.colPivHouseholderQr().solve(b);
    if (model.allFinite()) models->push_back(model);
  }
  void Residuals(const std::vector<X_t>& X, const std::vector<Y_t>& Y, const M_t& model,
                 std::vector<double>* residuals) const {
    residuals->resize(X.size());
    for (size_t i = 0; i < X.size(); ++i) {
      const double r = Y[i] - (model(0) * X[i] + model(1));
      (*residuals)[i] = r * r;
    }
  }
};

TEST(LoRansac, RecoversLineWithHalfOutliers) {
  SetPRNGSeed(7);
  std::vector<double> X, Y;
  std::vector<bool> truth;
  for (int i = 0; i < 400; ++i) {
    const double x = RandomUniformReal(-10, 10);
    const bool inlier = i % 2 == 0;
    X.push_back(x);
    Y.push_back(inlier ? 2 * x - 1 + RandomGaussian(0, 0.05) : RandomUniformReal(-30, 30));
    truth.push_back(inlier);
  }
  RansacOptions options;
  options.max_error = 0.2;
  LoRansac<LineEstimator> ransac(options);
  const auto report = ransac.Estimate(X, Y);
  ASSERT_TRUE(report.success);
  EXPECT_NEAR(report.model(0), 2.0, 0.01);
  EXPECT_NEAR(report.model(1), -1.0, 0.02);
  size_t true_inliers_kept = 0, outliers_kept = 0;
  for (size_t i = 0; i < X.size(); ++i) {
    if (report.inlier_mask[i] && truth[i]) ++true_inliers_kept;
    if (report.inlier_mask[i] && !truth[i]) ++outliers_kept;
  }
  EXPECT_GE(true_inliers_kept, 195u);
  EXPECT_LE(outliers_kept, 4u);
  EXPECT_LT(report.num_trials, 1000u);
}

// A line estimator that records the x values of every minimal sample it is given.
struct RecordingLineEstimator : LineEstimator {
  std::vector<std::vector<double>>* samples = nullptr;
  void Estimate(const std::vector<X_t>& X, const std::vector<Y_t>& Y,
                std::vector<M_t>* models) const {
    samples->push_back(X);
    LineEstimator::Estimate(X, Y, models);
  }
};

std::vector<std::vector<double>> SamplesDrawn(uint64_t seed) {
  std::vector<double> X, Y;
  for (int i = 0; i < 100; ++i) {
    X.push_back(i);
    Y.push_back(i % 3 == 0 ? 1000.0 + i : 2.0 * i + 1.0);  // A third are outliers.
  }
  std::vector<std::vector<double>> samples;
  RecordingLineEstimator estimator;
  estimator.samples = &samples;
  RansacOptions options;
  options.random_seed = seed;
  options.local_optimization_iterations = 0;
  options.min_num_trials = 20;
  const LoRansac<RecordingLineEstimator> ransac(options, estimator);
  EXPECT_TRUE(ransac.Estimate(X, Y).success);
  return samples;
}

TEST(LoRansac, TheSeedAloneDecidesTheSamples) {
  // The thread's generator plays no part: reseeding it changes nothing.
  SetPRNGSeed(1);
  const auto first = SamplesDrawn(42);
  SetPRNGSeed(2);
  EXPECT_EQ(SamplesDrawn(42), first);
  const auto other = SamplesDrawn(43);
  ASSERT_GE(other.size(), 20u);
  EXPECT_NE(std::vector<std::vector<double>>(other.begin(), other.begin() + 20),
            std::vector<std::vector<double>>(first.begin(), first.begin() + 20));
}

// Points with no line among them: RANSAC searches to its min_inlier_ratio bound. A caller
// that would reject every model short of some count bounds the search by that count.
TEST(LoRansac, InliersSoughtBoundsTheSearchForModelsThatFallShort) {
  SetPRNGSeed(3);
  std::vector<double> X, Y;
  for (int i = 0; i < 200; ++i) {
    X.push_back(RandomUniformReal(-10, 10));
    Y.push_back(RandomUniformReal(-10, 10));
  }
  RansacOptions options;
  options.max_error = 0.05;
  options.min_inlier_ratio = 0.02;
  options.min_inlier_ratio_trials_multiplier = 1.0;
  options.max_num_trials = 100000;
  const LoRansac<LineEstimator> ransac(options);
  const auto plain = ransac.Estimate(X, Y);
  // Sought 0: the caller would keep any model; the same run, trial for trial.
  const auto keep_any = ransac.Estimate(X, Y, [](const Eigen::Vector2d&, size_t) { return 0; });
  EXPECT_EQ(keep_any.num_trials, plain.num_trials);
  EXPECT_EQ(keep_any.model, plain.model);
  EXPECT_EQ(keep_any.inlier_mask, plain.inlier_mask);

  // 100 of 200 sought: a sample of two inliers at ratio 0.5 is found to the confidence in
  // log(1 - c) / log(1 - 0.25) trials, 33 at c = 0.9999 (the bound starts at the first
  // best model, so a few more may be drawn before it).
  size_t calls = 0;
  const auto bounded = ransac.Estimate(X, Y, [&calls](const Eigen::Vector2d&, size_t num_inliers) {
    ++calls;
    EXPECT_LT(num_inliers, 100u);
    return 100;
  });
  const size_t half_ratio_trials = ComputeNumRansacTrials(100, 200, 2, options.confidence, 1.0);
  EXPECT_EQ(half_ratio_trials, 33u);
  EXPECT_GT(calls, 0u);
  EXPECT_LE(bounded.num_trials, half_ratio_trials + 5);
  EXPECT_GT(plain.num_trials, 10 * half_ratio_trials);
  // The best model found in those trials is still reported.
  EXPECT_TRUE(bounded.success);
}

// A model with as many inliers as sought: the caller keeps it, and the search is RANSAC's own.
TEST(LoRansac, InliersSoughtDoesNotStopASearchThatFoundEnough) {
  SetPRNGSeed(7);
  std::vector<double> X, Y;
  for (int i = 0; i < 200; ++i) {
    const double x = RandomUniformReal(-10, 10);
    X.push_back(x);
    Y.push_back(i % 4 == 0 ? 3 * x + 2 : RandomUniformReal(-30, 30));  // A quarter inliers.
  }
  RansacOptions options;
  options.max_error = 0.05;
  const LoRansac<LineEstimator> ransac(options);
  const auto plain = ransac.Estimate(X, Y);
  const auto sought = ransac.Estimate(X, Y, [](const Eigen::Vector2d&, size_t) { return 40; });
  ASSERT_TRUE(plain.success);
  EXPECT_EQ(sought.num_trials, plain.num_trials);
  EXPECT_EQ(sought.num_inliers, plain.num_inliers);
  EXPECT_EQ(sought.num_inliers, 50u);
}

// The all-inlier probability of a sample drawn without replacement, by hand: 10 inliers of
// 20, samples of 3: P = (10 9 8) / (20 19 18) = 2 / 19, so log(0.01) / log(17 / 19) = 41.4
// trials, 42; (10 / 20)^3 = 1 / 8 would have given 35.
TEST(ComputeNumRansacTrials, ExactProductForSamplingWithoutReplacement) {
  EXPECT_EQ(ComputeNumRansacTrials(10, 20, 3, 0.99, 1.0), 42u);
  EXPECT_EQ(ComputeNumRansacTrials(10, 20, 3, 0.99, 3.0), 125u);  // ceil(3 x 41.4)
  // 3 of 4, samples of 3: P = (3 2 1) / (4 3 2) = 1 / 4.
  EXPECT_EQ(ComputeNumRansacTrials(3, 4, 3, 0.99, 1.0), 17u);
  // 50 of 100, samples of 7: P = 0.00624, 1,104 trials at 0.999 (0.5^7 would give 881).
  EXPECT_EQ(ComputeNumRansacTrials(50, 100, 7, 0.999, 1.0), 1104u);
}

TEST(ComputeNumRansacTrials, EdgeCases) {
  constexpr size_t kMax = std::numeric_limits<size_t>::max();
  // Fewer inliers than a sample: no sample is all inliers.
  EXPECT_EQ(ComputeNumRansacTrials(2, 20, 3, 0.99, 1.0), kMax);
  EXPECT_EQ(ComputeNumRansacTrials(0, 20, 3, 0.99, 1.0), kMax);
  EXPECT_EQ(ComputeNumRansacTrials(0, 0, 3, 0.99, 1.0), kMax);
  // Every correspondence an inlier: the first sample is.
  EXPECT_EQ(ComputeNumRansacTrials(20, 20, 3, 0.99, 1.0), 1u);
  EXPECT_EQ(ComputeNumRansacTrials(3, 3, 3, 0.99, 3.0), 1u);
  // More inliers than correspondences count as all.
  EXPECT_EQ(ComputeNumRansacTrials(25, 20, 3, 0.99, 1.0), 1u);
  // Chances too small to count: the maximum, not an overflowing conversion.
  EXPECT_EQ(ComputeNumRansacTrials(8, 100000, 8, 0.99, 1.0), kMax);
  // A zero multiplier asks for no trials.
  EXPECT_EQ(ComputeNumRansacTrials(10, 20, 3, 0.99, 0.0), 0u);
}

// Points on a line, and four times as many outliers, in quality order: the 100 inliers rank
// among the first 150 (as matches with low ratios mostly are), the outliers fill the rest.
void QualityOrderedLine(std::vector<double>* X, std::vector<double>* Y) {
  for (int i = 0; i < 500; ++i) {
    const double x = RandomUniformReal(-10, 10);
    const bool inlier = i < 150 ? i % 3 != 2 : false;
    X->push_back(x);
    Y->push_back(inlier ? 2 * x - 1 + RandomGaussian(0, 0.05) : RandomUniformReal(-30, 30));
  }
}

TEST(LoRansac, ProgressiveSamplingFindsTheModelInFewerTrials) {
  SetPRNGSeed(11);
  std::vector<double> X, Y;
  QualityOrderedLine(&X, &Y);
  RansacOptions options;
  options.max_error = 0.2;
  const auto uniform = LoRansac<LineEstimator>(options).Estimate(X, Y);
  options.sampler = RansacSampler::kProgressive;
  const auto progressive = LoRansac<LineEstimator>(options).Estimate(X, Y);
  for (const auto* report : {&uniform, &progressive}) {
    ASSERT_TRUE(report->success);
    EXPECT_NEAR(report->model(0), 2.0, 0.01);
    EXPECT_NEAR(report->model(1), -1.0, 0.05);
    EXPECT_GE(report->num_inliers, 98u);
  }
  std::cerr << "trials: uniform " << uniform.num_trials << ", progressive "
            << progressive.num_trials << "\n";
  EXPECT_LT(5 * progressive.num_trials, uniform.num_trials);
  // The same seed, the same samples.
  const auto again = LoRansac<LineEstimator>(options).Estimate(X, Y);
  EXPECT_EQ(again.num_trials, progressive.num_trials);
  EXPECT_EQ(again.model, progressive.model);
  EXPECT_EQ(again.inlier_mask, progressive.inlier_mask);
}

// Without a quality order (inliers anywhere) progressive sampling still finds the model: it
// grows to all points and ends under the uniform bound.
TEST(LoRansac, ProgressiveSamplingWithoutAQualityOrder) {
  SetPRNGSeed(12);
  std::vector<double> X, Y;
  QualityOrderedLine(&X, &Y);
  std::vector<size_t> order(X.size());
  std::iota(order.begin(), order.end(), 0);
  Shuffle(order.size(), &order);
  std::vector<double> shuffled_X, shuffled_Y;
  for (const size_t i : order) {
    shuffled_X.push_back(X[i]);
    shuffled_Y.push_back(Y[i]);
  }
  RansacOptions options;
  options.max_error = 0.2;
  options.sampler = RansacSampler::kProgressive;
  const auto report = LoRansac<LineEstimator>(options).Estimate(shuffled_X, shuffled_Y);
  ASSERT_TRUE(report.success);
  EXPECT_NEAR(report.model(0), 2.0, 0.01);
  EXPECT_GE(report.num_inliers, 98u);
}

TEST(ProsacTermination, NonRandomnessAndMaximality) {
  ProsacTermination termination(2, 0.99, 1.0, 0.05);
  // Binomial(n - 2, 0.05) exceeds j with 5 % chance: n = 2 needs a third inlier it cannot
  // have; n = 5, two of the three others (P[X >= 2] = 0.007, P[X >= 1] = 0.14).
  EXPECT_EQ(termination.MinNonRandomInliers(2), 3u);
  EXPECT_EQ(termination.MinNonRandomInliers(5), 4u);
  EXPECT_GT(termination.MinNonRandomInliers(1000), 2u + 50u);  // Above the mean, 49.9.
  EXPECT_LT(termination.MinNonRandomInliers(1000), 2u + 70u);
  // 2 of 2 is random; 5 of 5 is not and needs one trial; 40 of 100 after 20 trials is not
  // yet maximal (ComputeNumRansacTrials(40, 100, 2, 0.99, 1) = 27), after 27 it is.
  EXPECT_FALSE(termination.Satisfied(100, 2, 2));
  EXPECT_TRUE(termination.Satisfied(1, 5, 5));
  EXPECT_EQ(ComputeNumRansacTrials(40, 100, 2, 0.99, 1.0), 27u);
  EXPECT_FALSE(termination.Satisfied(20, 100, 40));
  EXPECT_TRUE(termination.Satisfied(27, 100, 40));
}

TEST(LoRansac, TooFewPointsFails) {
  LoRansac<LineEstimator> ransac(RansacOptions{});
  const auto report = ransac.Estimate({1.0}, {2.0});
  EXPECT_FALSE(report.success);
}

TEST(LoRansac, InvalidOptionsThrow) {
  RansacOptions options;
  options.max_error = -1;
  EXPECT_THROW(LoRansac<LineEstimator>{options}, CheckError);
}

}  // namespace
}  // namespace parallax
