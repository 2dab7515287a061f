#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace parallax {

// A seed for the stream `stream` of a run seeded with `seed` (SplitMix64 of both): the pair
// of a matching run, the image of a registration, the cluster of a partitioned run. Nearby
// inputs give unrelated seeds.
uint64_t DeriveSeed(uint64_t seed, uint64_t stream);

// Fisher-Yates shuffle of the first `num_to_shuffle` elements of `elements`, drawn from
// `generator`.
template <typename T>
void Shuffle(size_t num_to_shuffle, std::vector<T>* elements, std::mt19937_64* generator) {
  if (elements->empty()) return;
  const size_t last = elements->size() - 1;
  for (size_t i = 0; i < num_to_shuffle && i < elements->size(); ++i) {
    const size_t j = std::uniform_int_distribution<size_t>(i, last)(*generator);
    std::swap((*elements)[i], (*elements)[j]);
  }
}

// The generators below are for tests and benchmarks, which make their data with them: one
// per thread, seeded by SetPRNGSeed (the test main seeds it). Library code never uses them;
// it takes seeds through its options.
void SetPRNGSeed(uint64_t seed);
std::mt19937_64& ThreadLocalPRNG();

// Uniform integer in [min, max] (inclusive).
int64_t RandomUniformInteger(int64_t min, int64_t max);
// Uniform real in [min, max).
double RandomUniformReal(double min, double max);
// Normal sample with the given mean and standard deviation.
double RandomGaussian(double mean, double stddev);

// Fisher-Yates shuffle with the thread's generator.
template <typename T>
void Shuffle(size_t num_to_shuffle, std::vector<T>* elements) {
  Shuffle(num_to_shuffle, elements, &ThreadLocalPRNG());
}

}  // namespace parallax
