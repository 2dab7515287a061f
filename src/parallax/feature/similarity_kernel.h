#pragma once

#include <vector>

namespace parallax {

// Dot products of descriptor blocks for the matcher, each summed in one fixed order: a chain
// of fused multiply-adds over the dimensions, k = 0, 1, ..., dim - 1, starting from 0. Every
// implementation computes exactly that chain per output (vectorised across outputs, never
// across k), so the AVX-512 kernel, the AVX2 kernel and the scalar std::fma reference give
// the same bits, and a model does not depend on which one the CPU runs
// (docs/portable-build.md).
enum class SimilarityKernel {
  kScalar,  // std::fma, one output at a time: the reference.
  kAvx2,    // 8 lanes (x86-64-v3).
  kAvx512,  // 16 lanes, where the CPU has AVX-512F.
};

// The fastest kernel this CPU runs (chosen once per process).
SimilarityKernel BestSimilarityKernel();

// Whether `kernel` runs on this CPU and in this build.
bool SimilarityKernelAvailable(SimilarityKernel kernel);

// The descriptors of block a as the kernels read them: panels of kSimilarityPanelWidth
// columns, each panel k-major (packed[(p * dim + k) * kSimilarityPanelWidth + c] = a[p * width
// + c][k]), so that a micro-tile streams one contiguous panel. Columns past num_a are zero.
// Returns the padded column count (a multiple of the panel width).
constexpr int kSimilarityPanelWidth = 32;
int PackSimilarityColumns(const float* a, int num_a, int dim, std::vector<float>* packed);

// similarities[j * padded_a + i] = b[j] . a[i] for j < num_b and i < padded_a (0 for the
// padding columns), with a packed by PackSimilarityColumns and b holding num_b descriptors of
// `dim` floats as rows.
void ComputeSimilarities(const float* a_packed, int padded_a, const float* b, int num_b, int dim,
                         float* similarities, SimilarityKernel kernel = BestSimilarityKernel());

}  // namespace parallax
