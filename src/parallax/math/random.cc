#include "parallax/math/random.h"

namespace parallax {

namespace {
constexpr uint64_t kDefaultSeed = 0x5eed;
}

std::mt19937_64& ThreadLocalPRNG() {
  thread_local std::mt19937_64 generator(kDefaultSeed);
  return generator;
}

void SetPRNGSeed(uint64_t seed) { ThreadLocalPRNG().seed(seed); }

int64_t RandomUniformInteger(int64_t min, int64_t max) {
  std::uniform_int_distribution<int64_t> distribution(min, max);
  return distribution(ThreadLocalPRNG());
}

double RandomUniformReal(double min, double max) {
  std::uniform_real_distribution<double> distribution(min, max);
  return distribution(ThreadLocalPRNG());
}

double RandomGaussian(double mean, double stddev) {
  std::normal_distribution<double> distribution(mean, stddev);
  return distribution(ThreadLocalPRNG());
}

}  // namespace parallax
