#include "parallax/feature/similarity_kernel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "parallax/math/random.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

constexpr int kDim = 128;

struct Blocks {
  int num_a = 0;
  int num_b = 0;
  std::vector<uint8_t> a;  // num_a x kDim.
  std::vector<float> a_scales;
  std::vector<uint8_t> b;  // num_b x kDim.
  std::vector<float> b_scales;
  std::vector<int32_t> b_sums;
};

// Bytes over their whole range, the extremes often (0 and 255 test the 16-bit and signed-byte
// arithmetic at its limits), and one row of each block all 255.
std::vector<uint8_t> RandomBytes(int rows) {
  std::vector<uint8_t> bytes(static_cast<size_t>(rows) * kDim);
  for (uint8_t& value : bytes) {
    const int64_t kind = RandomUniformInteger(0, 3);
    value = kind == 0 ? 0 : kind == 1 ? 255 : static_cast<uint8_t>(RandomUniformInteger(0, 255));
  }
  std::fill_n(bytes.begin(), kDim, uint8_t{255});
  return bytes;
}

Blocks RandomBlocks(int num_a, int num_b) {
  Blocks blocks;
  blocks.num_a = num_a;
  blocks.num_b = num_b;
  blocks.a = RandomBytes(num_a);
  blocks.b = RandomBytes(num_b);
  for (int i = 0; i < num_a; ++i) blocks.a_scales.push_back(RandomUniformReal(1e-4f, 1e-2f));
  for (int j = 0; j < num_b; ++j) {
    blocks.b_scales.push_back(RandomUniformReal(1e-4f, 1e-2f));
    int32_t sum = 0;
    for (int k = 0; k < kDim; ++k) sum += blocks.b[j * kDim + k];
    blocks.b_sums.push_back(sum);
  }
  return blocks;
}

std::vector<float> Similarities(const Blocks& blocks, SimilarityKernel kernel, int* num_columns) {
  PackedSimilarityColumns packed;
  PackSimilarityColumns(blocks.a.data(), blocks.a_scales.data(), blocks.num_a, kDim, kernel,
                        &packed);
  *num_columns = packed.num_columns;
  std::vector<float> out(static_cast<size_t>(blocks.num_b) * packed.num_columns, -1.0f);
  ComputeSimilarities(packed,
                      {blocks.b.data(), blocks.b_scales.data(), blocks.b_sums.data(), blocks.num_b},
                      out.data());
  return out;
}

TEST(SimilarityKernel, ScalarReferenceIsTheScaledIntegerDotProduct) {
  const Blocks blocks = RandomBlocks(45, 7);
  int num_columns = 0;
  const std::vector<float> out = Similarities(blocks, SimilarityKernel::kScalar, &num_columns);
  EXPECT_EQ(num_columns, 64);
  for (int j = 0; j < blocks.num_b; ++j) {
    for (int i = 0; i < num_columns; ++i) {
      const float value = out[j * num_columns + i];
      if (i >= blocks.num_a) {
        EXPECT_EQ(value, 0.0f) << "padding column " << i;
        continue;
      }
      int64_t dot = 0;
      for (int k = 0; k < kDim; ++k)
        dot += int64_t{blocks.b[j * kDim + k]} * blocks.a[i * kDim + k];
      EXPECT_EQ(value, static_cast<float>(dot) * blocks.a_scales[i] * blocks.b_scales[j])
          << j << " " << i;
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
    int reference_columns = 0;
    const std::vector<float> reference =
        Similarities(blocks, SimilarityKernel::kScalar, &reference_columns);
    for (const SimilarityKernel kernel : {SimilarityKernel::kAvx2, SimilarityKernel::kAvx512Vnni}) {
      if (!SimilarityKernelAvailable(kernel)) continue;
      int num_columns = 0;
      const std::vector<float> out = Similarities(blocks, kernel, &num_columns);
      ASSERT_EQ(num_columns, reference_columns);
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

// A slice of whole panels of a block packed once gives what packing the slice's
// descriptors alone gives, in every kernel this CPU runs (the matcher slices an image's
// rows packed once into row blocks).
TEST(SimilarityKernel, PanelsOfAPackedBlockAreTheSlicePackedAlone) {
  const Blocks blocks = RandomBlocks(150, 9);  // Five panels, the last partly padding.
  for (const SimilarityKernel kernel :
       {SimilarityKernel::kScalar, SimilarityKernel::kAvx2, SimilarityKernel::kAvx512Vnni}) {
    if (!SimilarityKernelAvailable(kernel)) continue;
    PackedSimilarityColumns whole;
    PackSimilarityColumns(blocks.a.data(), blocks.a_scales.data(), blocks.num_a, kDim, kernel,
                          &whole);
    const SimilarityRows rows{blocks.b.data(), blocks.b_scales.data(), blocks.b_sums.data(),
                              blocks.num_b};
    for (const auto& [first, count] :
         {std::pair{0, 150}, std::pair{32, 64}, std::pair{64, 86}, std::pair{128, 1}}) {
      const SimilarityColumns slice = whole.Panels(first, count);
      ASSERT_EQ(slice.num_columns % kSimilarityPanelWidth, 0);
      ASSERT_GE(slice.num_columns, count);
      PackedSimilarityColumns alone;
      PackSimilarityColumns(blocks.a.data() + first * kDim, blocks.a_scales.data() + first,
                            std::min(count, blocks.num_a - first), kDim, kernel, &alone);
      ASSERT_EQ(alone.num_columns, slice.num_columns);
      std::vector<float> from_slice(static_cast<size_t>(blocks.num_b) * slice.num_columns, -1.0f);
      std::vector<float> from_alone(from_slice.size(), -2.0f);
      ComputeSimilarities(slice, rows, from_slice.data());
      ComputeSimilarities(alone, rows, from_alone.data());
      // The slice's own columns; past them, a slice that ends inside the block holds the
      // next descriptors of its last panel where the block packed alone has padding.
      for (int j = 0; j < blocks.num_b; ++j) {
        for (int i = 0; i < count; ++i) {
          const size_t k = static_cast<size_t>(j) * slice.num_columns + i;
          ASSERT_EQ(from_slice[k], from_alone[k])
              << "kernel " << static_cast<int>(kernel) << ", columns " << first << " + " << count
              << ", row " << j << ", column " << i;
        }
      }
    }
  }
  PackedSimilarityColumns whole;
  PackSimilarityColumns(blocks.a.data(), blocks.a_scales.data(), blocks.num_a, kDim,
                        SimilarityKernel::kScalar, &whole);
  EXPECT_THROW(whole.Panels(16, 32), CheckError);   // Not at a panel's start.
  EXPECT_THROW(whole.Panels(128, 64), CheckError);  // Past the last panel.
}

TEST(SimilarityKernel, BestKernelRunsHere) {
  EXPECT_TRUE(SimilarityKernelAvailable(BestSimilarityKernel()));
}

}  // namespace
}  // namespace parallax
