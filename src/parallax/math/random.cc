#include "parallax/math/random.h"

namespace parallax {

namespace {
constexpr uint64_t kDefaultSeed = 0x5eed;
}

uint64_t DeriveSeed(uint64_t seed, uint64_t stream) {
  // Two rounds of SplitMix64's finaliser (Steele, Lea & Flood 2014) over seed and stream.
  const auto mix = [](uint64_t z) {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  };
  return mix(mix(seed) ^ stream);
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
