#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "parallax/util/types.h"

namespace parallax {

using visual_word_t = uint32_t;

struct VocabularyTreeOptions {
  int branching = 10;                     // Children per node (the k of the hierarchical k-means).
  int depth = 5;                          // Levels below the root: up to branching^depth words.
  int max_training_descriptors = 400000;  // A uniform sample of the collection is enough.
  int kmeans_iterations = 8;              // Lloyd iterations per node (fewer if it converges).
  uint64_t seed = 0;                      // Sampling and k-means++ seeding: same seed, same tree.
  int num_threads = -1;                   // -1: all cores. The tree does not depend on it.
  void Check() const;
};

// A vocabulary tree (Nister & Stewenius, "Scalable Recognition with a Vocabulary Tree", CVPR
// 2006): hierarchical k-means on descriptors (unit float rows, as ToUnitRows makes them),
// the leaves being the visual words. Distances are summed in one fixed order of fused
// multiply-adds whatever the CPU (AVX2 or scalar), the batch or the thread count: a descriptor
// always gets the same word, and a seed the same tree.
class VocabularyTree {
 public:
  using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  VocabularyTree() = default;  // Empty: no words; Quantize fails its check.

  // Hierarchical k-means (k-means++ seeding) on a sample of the rows of `descriptors` (any
  // dimension D). A node with fewer than `branching` descriptors, or whose descriptors are all
  // equal, becomes a leaf; so does every node at `depth`.
  static VocabularyTree Train(const RowMatrixXf& descriptors, const VocabularyTreeOptions& options);

  // The leaf word of each row: greedy descent to the nearest child (L2) at every level.
  std::vector<visual_word_t> Quantize(const RowMatrixXf& descriptors, int num_threads = -1) const;

  int NumWords() const { return num_words_; }
  int NumNodes() const { return static_cast<int>(nodes_.size()); }
  int DescriptorDimension() const { return dimension_; }
  int Branching() const { return branching_; }
  int Depth() const { return depth_; }  // Of the deepest leaf (0: the root is the only word).

  // Binary, little-endian: "PLXVOCAB", uint32 format version, dimension, branching, node count,
  // word count; per node uint32 first child, child count, word (0xFFFFFFFF for inner nodes) and
  // D float centroid (zero for the root); then the XXH3-128 hex digest (32 bytes) of all the
  // bytes before it. Children of a node are consecutive and numbered after it.
  void Write(std::ostream& stream) const;
  void Write(const std::filesystem::path& path) const;  // Atomically (WriteFileAtomically).

  // Throws InputError "<name>: ..." (one line) when the data is not a vocabulary tree, is
  // truncated, has trailing bytes, fails its checksum or is inconsistent; and, when
  // expected_dimension > 0, when the tree is for another descriptor dimension.
  static VocabularyTree Read(const std::filesystem::path& path, int expected_dimension = -1);
  static VocabularyTree Read(std::istream& stream, const std::string& name,
                             int expected_dimension = -1);

  // Centroids per panel group: the distance kernel's two 8-float AVX2 vectors. The panels are
  // laid out by it, and Write reads them back in the file's order.
  static constexpr int kPanelLanes = 16;

 private:
  struct Node {
    uint32_t first_child = 0;
    uint32_t num_children = 0;  // 0: a leaf.
    uint32_t word = 0;          // Leaves: the word. Inner nodes: index of the children's panel.
  };

  static VocabularyTree FromBytes(const std::string& bytes, const std::string& name,
                                  int expected_dimension);
  // Packs the children's centroids (rows of `centroids`, one per node) for the kernel and sets
  // the words and the depth.
  void Build(const std::vector<float>& centroids);

  int dimension_ = 0;
  int branching_ = 0;
  int num_groups_ = 0;  // Centroid groups (of the kernel's lane count) per inner node.
  int num_words_ = 0;
  int depth_ = 0;
  std::vector<Node> nodes_;
  // Per inner node, num_groups_ panels of D x lanes child centroids (k-major), and their squared
  // norms (+inf for the padding lanes).
  std::vector<float> panels_;
  std::vector<float> norms_;
};

// tf-idf inverted-file index over images (Sivic & Zisserman, "Video Google", ICCV 2003; Nister &
// Stewenius 2006): an image is the L2-normalised vector of count(w) * log(N / n_w) over its words,
// and similarity is the cosine, summed over the inverted files of the query's words only.
class RetrievalIndex {
 public:
  explicit RetrievalIndex(int num_words);

  // Before Finalize; each image id once.
  void AddImage(image_t image_id, const std::vector<visual_word_t>& words);
  // Computes the idf weights and the normalised image vectors; then the index can be queried.
  void Finalize();

  // Up to `max_results` images by descending cosine similarity (ties: ascending image id);
  // images sharing no weighted word are left out. An indexed query image is included (score 1
  // up to rounding): callers drop it. Words no indexed image has carry no weight.
  std::vector<std::pair<image_t, float>> Query(const std::vector<visual_word_t>& words,
                                               int max_results) const;
  // Query with an indexed image's own words.
  std::vector<std::pair<image_t, float>> QueryImage(image_t image_id, int max_results) const;

  size_t NumImages() const { return image_ids_.size(); }
  bool HasImage(image_t image_id) const { return image_indices_.count(image_id) > 0; }

 private:
  struct Posting {
    uint32_t image_index;
    float weight;  // The word's count before Finalize, the normalised tf-idf weight after.
  };
  using WeightedWords = std::vector<std::pair<visual_word_t, float>>;
  std::vector<std::pair<image_t, float>> Rank(const WeightedWords& query, int max_results) const;

  int num_words_;
  bool finalized_ = false;
  std::vector<std::vector<Posting>> postings_;  // Per word, by ascending image index.
  std::vector<float> idf_;
  std::vector<image_t> image_ids_;  // By image index (order of AddImage).
  std::unordered_map<image_t, uint32_t> image_indices_;
  // Distinct words of image i (ascending): image_words_[image_word_begin_[i], [i + 1]).
  std::vector<visual_word_t> image_words_;
  std::vector<size_t> image_word_begin_{0};
};

}  // namespace parallax
