#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace parallax {

// One seeded generator per thread. SetPRNGSeed reseeds the calling thread's generator;
// threads that never call it start from a fixed seed, so every run is repeatable.
void SetPRNGSeed(uint64_t seed);
std::mt19937_64& ThreadLocalPRNG();

// Uniform integer in [min, max] (inclusive).
int64_t RandomUniformInteger(int64_t min, int64_t max);
// Uniform real in [min, max).
double RandomUniformReal(double min, double max);
// Normal sample with the given mean and standard deviation.
double RandomGaussian(double mean, double stddev);

// Fisher-Yates shuffle of the first `num_to_shuffle` elements of `elements`.
template <typename T>
void Shuffle(size_t num_to_shuffle, std::vector<T>* elements) {
  const size_t last = elements->size() - 1;
  for (size_t i = 0; i < num_to_shuffle && i < elements->size(); ++i) {
    const size_t j = static_cast<size_t>(RandomUniformInteger(i, last));
    std::swap((*elements)[i], (*elements)[j]);
  }
}

}  // namespace parallax
