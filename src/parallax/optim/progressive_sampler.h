#pragma once

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include "parallax/util/check.h"

namespace parallax {

// PROSAC's sampler (Chum & Matas, "Matching with PROSAC - Progressive Sample Consensus", CVPR
// 2005, sec. 2 and Algorithm 1). The N correspondences are taken as sorted from the most to
// the least likely inlier (for feature matches: by Lowe's ratio). Trial t draws its m points
// from the n best, n growing from m to N so that, by the trial T_N (`num_trials_to_all`),
// the samples drawn from every set of the n best are as many as uniform sampling would have
// drawn from it in T_N trials: T_n = T_N C(n, m) / C(N, m). A sample drawn from the n best
// while n is the newest holds the n-th point and m - 1 of the n - 1 before it, so no sample
// repeats one drawn from a smaller set; once n = N the samples are uniform among all.
//
// One departure from the paper's indexing: the first trial draws exactly the m best points
// (the paper's first trial already grows n to m + 1). Deterministic for a generator's seed.
class ProgressiveSampler {
 public:
  ProgressiveSampler(size_t num_points, size_t sample_size, double num_trials_to_all)
      : num_points_(num_points), sample_size_(sample_size), n_(sample_size) {
    PARALLAX_CHECK_GT(sample_size, 0u);
    PARALLAX_CHECK_GE(num_points, sample_size);
    PARALLAX_CHECK_GT(num_trials_to_all, 0.0);
    // T_m = T_N C(m, m) / C(N, m) = T_N prod_{i < m} (m - i) / (N - i).
    T_n_ = num_trials_to_all;
    for (size_t i = 0; i < sample_size; ++i) {
      T_n_ *= static_cast<double>(sample_size - i) / static_cast<double>(num_points - i);
    }
  }

  // The next trial's sample: `sample_size` distinct indices into the sorted correspondences.
  void Sample(std::mt19937_64* generator, std::vector<size_t>* sample) {
    ++trial_;
    // Past the last trial of the n best: the (n + 1)-th joins, for the trials
    // T'_{n+1} = T'_n + ceil(T_{n+1} - T_n).
    if (trial_ > T_prime_n_ && n_ < num_points_) {
      const double T_next =
          T_n_ * static_cast<double>(n_ + 1) / static_cast<double>(n_ + 1 - sample_size_);
      T_prime_n_ += static_cast<size_t>(std::ceil(T_next - T_n_));
      T_n_ = T_next;
      ++n_;
    }
    sample->clear();
    if (trial_ > T_prime_n_) {
      // n = N and past T'_N: uniform sampling of all.
      DrawDistinct(n_, sample_size_, generator, sample);
    } else {
      DrawDistinct(n_ - 1, sample_size_ - 1, generator, sample);
      sample->push_back(n_ - 1);
    }
  }

  // The number of best correspondences the last sample was drawn from.
  size_t NumPointsSampled() const { return n_; }

 private:
  // `count` distinct indices below `limit` (count <= limit), uniformly, appended.
  static void DrawDistinct(size_t limit, size_t count, std::mt19937_64* generator,
                           std::vector<size_t>* sample) {
    if (count == 0) return;
    std::uniform_int_distribution<size_t> index(0, limit - 1);
    const size_t begin = sample->size();
    while (sample->size() < begin + count) {
      const size_t candidate = index(*generator);
      bool repeated = false;
      for (size_t i = begin; i < sample->size(); ++i)
        repeated = repeated || (*sample)[i] == candidate;
      if (!repeated) sample->push_back(candidate);
    }
  }

  const size_t num_points_, sample_size_;
  size_t n_;              // The samples come from the n best.
  double T_n_;            // T_n: uniform sampling's expected samples from the n best.
  size_t T_prime_n_ = 1;  // T'_n: the last trial that draws from the n best.
  size_t trial_ = 0;
};

}  // namespace parallax
