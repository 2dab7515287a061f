#pragma once

#include <cstdint>
#include <vector>

namespace parallax {

// Cosine similarities of descriptor blocks for the matcher. The dot product of two stored
// (uint8) descriptors is an integer, summed exactly by every implementation, and the
// similarity is float(dot) * scale_a * scale_b, multiplied in that order. So every kernel
// gives the same bits, and a model does not depend on which one the CPU runs
// (docs/portable-build.md).
enum class SimilarityKernel {
  kScalar,      // int32 sums, one output at a time: the reference.
  kAvx2,        // vpmaddwd on 16-bit pairs, 8 columns per vector (x86-64-v3).
  kAvx512Vnni,  // vpdpbusd on byte quads, 16 columns per vector (AVX-512 VNNI).
};

// The fastest kernel this CPU runs (chosen once per process).
SimilarityKernel BestSimilarityKernel();

// Whether `kernel` runs on this CPU and in this build.
bool SimilarityKernelAvailable(SimilarityKernel kernel);

// Block a's descriptors in the layout `kernel` reads: panels of kSimilarityPanelWidth columns,
// each panel grouped by dimension (pairs of dimensions for kScalar and kAvx2, quads for
// kAvx512Vnni) so that a micro-tile streams one contiguous panel. Columns past the block's
// descriptors are zero with scale 0.
constexpr int kSimilarityPanelWidth = 32;

// Whole panels of packed columns, as the kernels read them (a view: the packed block owns
// the values).
struct SimilarityColumns {
  SimilarityKernel kernel = SimilarityKernel::kScalar;
  int num_columns = 0;  // A multiple of kSimilarityPanelWidth.
  int dim = 0;
  const int16_t* pairs = nullptr;  // kScalar, kAvx2.
  const int8_t* quads = nullptr;   // kAvx512Vnni.
  const float* scales = nullptr;
};

struct PackedSimilarityColumns {
  SimilarityKernel kernel = SimilarityKernel::kScalar;
  int num_columns = 0;         // Padded: a multiple of kSimilarityPanelWidth.
  int dim = 0;                 // A multiple of 4.
  std::vector<int16_t> pairs;  // kScalar, kAvx2: [panel][dim / 2][column][2].
  std::vector<int8_t> quads;   // kAvx512Vnni: [panel][dim / 4][column][4], value - 128.
  std::vector<float> scales;   // Per column.

  // Columns [first, first + count), count rounded up to whole panels; `first` must start a
  // panel. Panels are independent, so a block packed once serves every slice of it.
  SimilarityColumns Panels(int first, int count) const;
  SimilarityColumns All() const { return Panels(0, num_columns); }
};

// Packs num_a descriptors of `dim` bytes (rows of a) with their scales (1 / norm).
void PackSimilarityColumns(const uint8_t* a, const float* a_scales, int num_a, int dim,
                           SimilarityKernel kernel, PackedSimilarityColumns* packed);

// Image 2's side of the product: num_rows descriptors of `dim` bytes as rows, each with its
// scale (1 / norm) and the sum of its bytes (which the VNNI kernel adds back, times 128).
struct SimilarityRows {
  const uint8_t* bytes = nullptr;
  const float* scales = nullptr;
  const int32_t* sums = nullptr;
  int num_rows = 0;
};

// similarities[j * a.num_columns + i] = float(b[j] . a[i]) * a.scales[i] * b.scales[j] for
// j < b.num_rows and every column i of a (0 for the padding). Runs a's kernel.
void ComputeSimilarities(const SimilarityColumns& a, const SimilarityRows& b, float* similarities);
inline void ComputeSimilarities(const PackedSimilarityColumns& a, const SimilarityRows& b,
                                float* similarities) {
  ComputeSimilarities(a.All(), b, similarities);
}

}  // namespace parallax
