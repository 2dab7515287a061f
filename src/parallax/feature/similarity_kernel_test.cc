#include "parallax/feature/similarity_kernel.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "parallax/math/random.h"

namespace parallax {
namespace {

constexpr int kDim = 128;

struct Blocks {
  int num_a = 0;
  int padded_a = 0;
  int num_b = 0;
  std::vector<float> a;         // num_a x kDim.
  std::vector<float> a_packed;  // PackSimilarityColumns(a).
  std::vector<float> b;         // num_b x kDim.
};

// Descriptor-like values: non-negative, of mixed magnitude, so that the order of the sums
// matters in the last bit.
Blocks RandomBlocks(int num_a, int num_b) {
  Blocks blocks;
  blocks.num_a = num_a;
  blocks.num_b = num_b;
  blocks.a.resize(static_cast<size_t>(num_a) * kDim);
  for (size_t n = 0; n < blocks.a.size(); ++n) {
    blocks.a[n] = RandomUniformReal(0.0f, 1.0f) * (n % 7 == 0 ? 100.0f : 0.01f);
  }
  blocks.padded_a = PackSimilarityColumns(blocks.a.data(), num_a, kDim, &blocks.a_packed);
  blocks.b.resize(static_cast<size_t>(num_b) * kDim);
  for (float& value : blocks.b) value = RandomUniformReal(0.0f, 1.0f);
  return blocks;
}

std::vector<float> Similarities(const Blocks& blocks, SimilarityKernel kernel) {
  std::vector<float> out(static_cast<size_t>(blocks.num_b) * blocks.padded_a, -1.0f);
  ComputeSimilarities(blocks.a_packed.data(), blocks.padded_a, blocks.b.data(), blocks.num_b, kDim,
                      out.data(), kernel);
  return out;
}

TEST(SimilarityKernel, ScalarReferenceIsTheDotProduct) {
  const Blocks blocks = RandomBlocks(45, 7);
  EXPECT_EQ(blocks.padded_a, 64);
  const std::vector<float> out = Similarities(blocks, SimilarityKernel::kScalar);
  for (int j = 0; j < blocks.num_b; ++j) {
    for (int i = 0; i < blocks.padded_a; ++i) {
      const float value = out[j * blocks.padded_a + i];
      if (i >= blocks.num_a) {
        EXPECT_EQ(value, 0.0f) << "padding column " << i;
        continue;
      }
      double dot = 0.0;
      for (int k = 0; k < kDim; ++k) {
        dot += static_cast<double>(blocks.b[j * kDim + k]) * blocks.a[i * kDim + k];
      }
      EXPECT_NEAR(value, dot, 1e-5 * std::max(1.0, dot)) << j << " " << i;
    }
  }
}

// Every kernel the CPU runs gives the reference's bits, for row counts that exercise the
// 4-row tiles and the single-row rest, and for one and several column groups.
TEST(SimilarityKernel, EveryKernelGivesTheReferenceBits) {
  int compared = 0;
  for (const auto& [num_a, num_b] :
       {std::pair{45, 7}, std::pair{256, 256}, std::pair{1, 1}, std::pair{100, 13}}) {
    const Blocks blocks = RandomBlocks(num_a, num_b);
    const std::vector<float> reference = Similarities(blocks, SimilarityKernel::kScalar);
    for (const SimilarityKernel kernel : {SimilarityKernel::kAvx2, SimilarityKernel::kAvx512}) {
      if (!SimilarityKernelAvailable(kernel)) continue;
      const std::vector<float> out = Similarities(blocks, kernel);
      EXPECT_EQ(std::memcmp(out.data(), reference.data(), out.size() * sizeof(float)), 0)
          << "kernel " << static_cast<int>(kernel) << ", " << num_a << " x " << num_b;
      ++compared;
    }
  }
  // The default build targets x86-64-v3: its AVX2 kernel is always there to compare.
#if defined(__x86_64__) && defined(__AVX2__)
  EXPECT_GE(compared, 4);
#endif
}

TEST(SimilarityKernel, BestKernelRunsHere) {
  EXPECT_TRUE(SimilarityKernelAvailable(BestSimilarityKernel()));
}

}  // namespace
}  // namespace parallax
