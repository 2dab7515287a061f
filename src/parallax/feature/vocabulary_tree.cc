// The vocabulary tree: hierarchical k-means training and quantisation (the file format is
// vocabulary_tree_io.cc, the retrieval index retrieval_index.cc).

#include "parallax/feature/vocabulary_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "parallax/util/check.h"
#include "parallax/util/threading.h"

namespace parallax {
namespace {

using RowMatrixXf = VocabularyTree::RowMatrixXf;

constexpr int kLanes = VocabularyTree::kPanelLanes;
constexpr int kRows = 4;  // Rows per kernel call: 4 x 2 accumulators hide the FMA latency.
// Fixed work units: partial sums are reduced in chunk order, so no result depends on threads.
constexpr size_t kChunkRows = 2048;
constexpr size_t kQuantizeChunkRows = 256;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

// SplitMix64: decorrelated per-node seeds from (seed, node id).
uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// From the raw 64 bits, not std::uniform_real_distribution, whose algorithm the library picks.
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

size_t NumChunks(size_t n, size_t chunk) { return (n + chunk - 1) / chunk; }

// out[r * kLanes + c] = rows[r] . column c of the dim x kLanes panel of row r, each one fused
// multiply-add chain over k = 0, 1, ..., dim - 1: the AVX2 and the scalar path give the same bits.
template <bool kSharedPanel>
void Dots(const float* const* rows, const float* const* panels, int dim, float* out) {
#if defined(__AVX2__) && defined(__FMA__)
  __m256 sum[kRows][2];
  for (int r = 0; r < kRows; ++r) sum[r][0] = sum[r][1] = _mm256_setzero_ps();
  for (int k = 0; k < dim; ++k) {
    if constexpr (kSharedPanel) {
      const __m256 a0 = _mm256_loadu_ps(panels[0] + k * kLanes);
      const __m256 a1 = _mm256_loadu_ps(panels[0] + k * kLanes + 8);
      for (int r = 0; r < kRows; ++r) {
        const __m256 b = _mm256_broadcast_ss(rows[r] + k);
        sum[r][0] = _mm256_fmadd_ps(b, a0, sum[r][0]);
        sum[r][1] = _mm256_fmadd_ps(b, a1, sum[r][1]);
      }
    } else {
      for (int r = 0; r < kRows; ++r) {
        const __m256 b = _mm256_broadcast_ss(rows[r] + k);
        sum[r][0] = _mm256_fmadd_ps(b, _mm256_loadu_ps(panels[r] + k * kLanes), sum[r][0]);
        sum[r][1] = _mm256_fmadd_ps(b, _mm256_loadu_ps(panels[r] + k * kLanes + 8), sum[r][1]);
      }
    }
  }
  for (int r = 0; r < kRows; ++r) {
    _mm256_storeu_ps(out + r * kLanes, sum[r][0]);
    _mm256_storeu_ps(out + r * kLanes + 8, sum[r][1]);
  }
#else
  for (int r = 0; r < kRows; ++r) {
    const float* panel = panels[kSharedPanel ? 0 : r];
    for (int c = 0; c < kLanes; ++c) {
      float sum = 0.0f;
      for (int k = 0; k < dim; ++k) sum = std::fma(rows[r][k], panel[k * kLanes + c], sum);
      out[r * kLanes + c] = sum;
    }
  }
#endif
}

// Packed centroids (PackCentroids): num_groups panels and their squared norms.
struct CentroidSet {
  const float* panels;
  const float* norms;
  uint32_t num;
};

// The nearest centroid of sets[r] (sets[0] for all rows if shared) to rows[r] by ||x - c||^2 -
// ||x||^2 = ||c||^2 - 2 x.c; the first index wins a tie (a NaN row gets centroid 0).
template <bool kShared>
void Nearest(const float* const* rows, const CentroidSet* sets, int num_groups, int dim,
             uint32_t* best) {
  float best_score[kRows], dots[kRows * kLanes];
  std::fill_n(best_score, kRows, kInfinity);
  std::fill_n(best, kRows, 0u);
  for (int g = 0; g < num_groups; ++g) {
    const float* panels[kRows];
    for (int r = 0; r < kRows; ++r)
      panels[r] = sets[kShared ? 0 : r].panels + size_t(g) * dim * kLanes;
    Dots<kShared>(rows, panels, dim, dots);
    for (int r = 0; r < kRows; ++r) {
      const CentroidSet& set = sets[kShared ? 0 : r];
      for (uint32_t c = g * kLanes; c < std::min<uint32_t>(set.num, (g + 1) * kLanes); ++c) {
        const float score = std::fma(-2.0f, dots[r * kLanes + c % kLanes], set.norms[c]);
        if (score < best_score[r]) {
          best_score[r] = score;
          best[r] = c;
        }
      }
    }
  }
}

float SquaredNorm(const float* x, int dim) {
  float sum = 0.0f;
  for (int k = 0; k < dim; ++k) sum = std::fma(x[k], x[k], sum);
  return sum;
}

// k-means++ only: 16 interleaved partial sums (lane k % 16) added up in one fixed tree, so the
// AVX2 and the scalar path give the same bits.
float SquaredDistance(const float* a, const float* b, int dim) {
  float lanes[kLanes] = {};
  int k = 0;
#if defined(__AVX2__) && defined(__FMA__)
  __m256 sum0 = _mm256_setzero_ps(), sum1 = _mm256_setzero_ps();
  for (; k + kLanes <= dim; k += kLanes) {
    const __m256 d0 = _mm256_sub_ps(_mm256_loadu_ps(a + k), _mm256_loadu_ps(b + k));
    const __m256 d1 = _mm256_sub_ps(_mm256_loadu_ps(a + k + 8), _mm256_loadu_ps(b + k + 8));
    sum0 = _mm256_fmadd_ps(d0, d0, sum0);
    sum1 = _mm256_fmadd_ps(d1, d1, sum1);
  }
  _mm256_storeu_ps(lanes, sum0);
  _mm256_storeu_ps(lanes + 8, sum1);
#endif
  for (; k < dim; ++k) lanes[k % kLanes] = std::fma(a[k] - b[k], a[k] - b[k], lanes[k % kLanes]);
  for (int width = kLanes / 2; width > 0; width /= 2) {
    for (int l = 0; l < width; ++l) lanes[l] += lanes[l + width];
  }
  return lanes[0];
}

// Centroids (num rows of dim floats) as the kernel reads them: group g is a dim x kLanes panel
// of centroids g * kLanes + c, k-major. Padding lanes are zero with norm +inf.
void PackCentroids(const float* centroids, int num, int dim, int num_groups, float* panels,
                   float* norms) {
  std::fill_n(panels, static_cast<size_t>(num_groups) * dim * kLanes, 0.0f);
  std::fill_n(norms, static_cast<size_t>(num_groups) * kLanes, kInfinity);
  for (int i = 0; i < num; ++i) {
    const float* centroid = centroids + static_cast<size_t>(i) * dim;
    float* panel = panels + static_cast<size_t>(i / kLanes) * dim * kLanes + i % kLanes;
    for (int k = 0; k < dim; ++k) panel[k * kLanes] = centroid[k];
    norms[i] = SquaredNorm(centroid, dim);
  }
}

// One node's rows (indices into the training matrix) and the k-means result on them.
struct NodeClustering {
  std::vector<float> centroids;     // num x dim
  std::vector<size_t> child_begin;  // Offsets of the children's rows after reordering.
  int num = 0;
};

class NodeKMeans {
 public:
  NodeKMeans(const RowMatrixXf& data, uint32_t* rows, size_t n, int num_groups, int num_threads)
      : data_(data),
        rows_(rows),
        n_(n),
        dim_(static_cast<int>(data.cols())),
        num_groups_(num_groups),
        num_threads_(num_threads),
        labels_(n, 0) {}

  // Clusters the rows and reorders them by cluster; fewer than 2 clusters: a leaf.
  NodeClustering Run(int k, int iterations, uint64_t seed) {
    std::mt19937_64 rng(seed);
    NodeClustering result;
    int num = SeedPlusPlus(k, rng);
    if (num < 2) return result;
    std::vector<double> sums;
    std::vector<uint32_t> counts;
    bool converged = false;
    for (int iteration = 0; iteration < iterations && !converged; ++iteration) {
      // No label changed: the centroids are already these labels' means.
      converged = Assign(num, &sums, &counts) == 0 && iteration > 0;
      if (!converged) Update(num, sums, counts);
    }
    if (!converged) Assign(num, nullptr, &counts);
    // Drop empty clusters: no row is nearer to them, so removing them changes no label.
    std::vector<uint32_t> relabel(num);
    int kept = 0;
    for (int c = 0; c < num; ++c) {
      relabel[c] = kept;
      if (counts[c] == 0) continue;
      std::copy_n(centroids_.begin() + c * dim_, dim_, centroids_.begin() + kept * dim_);
      counts[kept++] = counts[c];
    }
    if (kept < 2) return result;
    result.num = kept;
    result.centroids.assign(centroids_.begin(), centroids_.begin() + kept * dim_);
    // A stable counting sort of the rows by label: each child's rows become one range.
    result.child_begin.assign(kept + 1, 0);
    for (int c = 0; c < kept; ++c) result.child_begin[c + 1] = result.child_begin[c] + counts[c];
    std::vector<size_t> next(result.child_begin.begin(), result.child_begin.end() - 1);
    std::vector<uint32_t> sorted(n_);
    for (size_t i = 0; i < n_; ++i) sorted[next[relabel[labels_[i]]]++] = rows_[i];
    std::copy(sorted.begin(), sorted.end(), rows_);
    return result;
  }

 private:
  const float* Row(size_t i) const { return data_.row(rows_[i]).data(); }

  // k-means++ (Arthur & Vassilvitskii 2007); stops early when every row is on a centroid.
  int SeedPlusPlus(int k, std::mt19937_64& rng) {
    centroids_.clear();
    auto add = [&](size_t i) { centroids_.insert(centroids_.end(), Row(i), Row(i) + dim_); };
    add(std::min(n_ - 1, static_cast<size_t>(Uniform01(rng) * n_)));
    std::vector<float> min_distance(n_, kInfinity);
    std::vector<double> chunk_sums(NumChunks(n_, kChunkRows));
    for (int num = 1; num < k; ++num) {
      const float* newest = centroids_.data() + (num - 1) * dim_;
      ParallelFor(0, chunk_sums.size(), num_threads_, [&](size_t chunk) {
        double sum = 0.0;
        for (size_t i = chunk * kChunkRows; i < std::min(n_, (chunk + 1) * kChunkRows); ++i) {
          min_distance[i] = std::min(min_distance[i], SquaredDistance(Row(i), newest, dim_));
          sum += min_distance[i];
        }
        chunk_sums[chunk] = sum;
      });
      double total = 0.0;
      for (const double sum : chunk_sums) total += sum;
      if (!(total > 0.0)) return num;
      // The row where the running sum passes u * total (the last positive one on rounding).
      double target = Uniform01(rng) * total;
      size_t chunk = 0;
      while (chunk + 1 < chunk_sums.size() && target >= chunk_sums[chunk]) {
        target -= chunk_sums[chunk++];
      }
      size_t pick = n_;
      for (size_t i = chunk * kChunkRows; i < n_ && !(target < 0.0); ++i) {
        if (min_distance[i] <= 0.0f) continue;
        pick = i;
        target -= min_distance[i];
      }
      for (size_t i = chunk * kChunkRows; pick == n_ && i-- > 0;) {
        if (min_distance[i] > 0.0f) pick = i;
      }
      if (pick == n_) return num;
      add(pick);
    }
    return k;
  }

  // Labels every row with its nearest centroid; returns how many labels changed. With `sums`,
  // adds each row to its cluster's sum in its chunk's slot.
  size_t Assign(int num, std::vector<double>* sums, std::vector<uint32_t>* counts) {
    std::vector<float> panels(static_cast<size_t>(num_groups_) * dim_ * kLanes);
    std::vector<float> norms(static_cast<size_t>(num_groups_) * kLanes);
    PackCentroids(centroids_.data(), num, dim_, num_groups_, panels.data(), norms.data());
    const size_t num_chunks = NumChunks(n_, kChunkRows);
    if (sums != nullptr) sums->assign(num_chunks * num * dim_, 0.0);
    std::vector<uint32_t> chunk_counts(num_chunks * num, 0);
    std::vector<size_t> chunk_changed(num_chunks, 0);
    ParallelFor(0, num_chunks, num_threads_, [&](size_t chunk) {
      const size_t begin = chunk * kChunkRows, end = std::min(n_, begin + kChunkRows);
      const CentroidSet set{panels.data(), norms.data(), static_cast<uint32_t>(num)};
      for (size_t i = begin; i < end; i += kRows) {
        const float* rows[kRows];
        // A short last group repeats its last row (the same bits, the result unused).
        for (int r = 0; r < kRows; ++r) rows[r] = Row(std::min(i + r, end - 1));
        uint32_t best[kRows];
        Nearest<true>(rows, &set, num_groups_, dim_, best);
        for (size_t r = 0; r < kRows && i + r < end; ++r) {
          chunk_changed[chunk] += labels_[i + r] != best[r];
          labels_[i + r] = best[r];
          ++chunk_counts[chunk * num + best[r]];
          if (sums == nullptr) continue;
          double* sum = sums->data() + (chunk * num + best[r]) * dim_;
          for (int d = 0; d < dim_; ++d) sum[d] += rows[r][d];
        }
      }
    });
    counts->assign(num, 0);
    size_t changed = 0;
    for (size_t chunk = 0; chunk < num_chunks; ++chunk) {
      changed += chunk_changed[chunk];
      for (int c = 0; c < num; ++c) (*counts)[c] += chunk_counts[chunk * num + c];
    }
    return changed;
  }

  // Centroids from the chunk sums (in chunk order); an empty cluster restarts at the row
  // farthest from its centroid (Lloyd's usual remedy), or stays put when every row is on one.
  void Update(int num, const std::vector<double>& sums, const std::vector<uint32_t>& counts) {
    const size_t num_chunks = NumChunks(n_, kChunkRows);
    std::vector<double> total(dim_);
    std::vector<float> distances;
    for (int c = 0; c < num; ++c) {
      if (counts[c] == 0) continue;
      std::fill(total.begin(), total.end(), 0.0);
      for (size_t chunk = 0; chunk < num_chunks; ++chunk) {
        const double* sum = sums.data() + (chunk * num + c) * dim_;
        for (int d = 0; d < dim_; ++d) total[d] += sum[d];
      }
      for (int d = 0; d < dim_; ++d)
        centroids_[c * dim_ + d] = static_cast<float>(total[d] / counts[c]);
    }
    for (int c = 0; c < num; ++c) {
      if (counts[c] != 0) continue;
      if (distances.empty()) {
        distances.resize(n_);
        for (size_t i = 0; i < n_; ++i) {
          distances[i] = SquaredDistance(Row(i), centroids_.data() + labels_[i] * dim_, dim_);
        }
      }
      const size_t farthest =
          std::max_element(distances.begin(), distances.end()) - distances.begin();
      if (!(distances[farthest] > 0.0f)) break;
      distances[farthest] = 0.0f;
      std::copy_n(Row(farthest), dim_, centroids_.begin() + c * dim_);
    }
  }

  const RowMatrixXf& data_;
  uint32_t* rows_;
  size_t n_;
  int dim_, num_groups_, num_threads_;
  std::vector<uint32_t> labels_;
  std::vector<float> centroids_;  // num x dim
};

// A uniform sample of `num` of [0, total), ascending (Knuth's selection sampling, Algorithm S).
std::vector<uint32_t> SampleRows(size_t total, size_t num, std::mt19937_64& rng) {
  std::vector<uint32_t> rows;
  rows.reserve(std::min(total, num));
  for (size_t i = 0; i < total && rows.size() < num; ++i) {
    if (total - i <= num - rows.size() || Uniform01(rng) * (total - i) < num - rows.size()) {
      rows.push_back(static_cast<uint32_t>(i));
    }
  }
  return rows;
}

}  // namespace

void VocabularyTreeOptions::Check() const {
  PARALLAX_CHECK_GE(branching, 2);
  PARALLAX_CHECK_LE(branching, 4096);
  PARALLAX_CHECK_GE(depth, 1);
  PARALLAX_CHECK_LE(depth, 32);
  PARALLAX_CHECK_GE(max_training_descriptors, 1);
  PARALLAX_CHECK_GE(kmeans_iterations, 0);
  PARALLAX_CHECK(num_threads == -1 || num_threads > 0);
}

VocabularyTree VocabularyTree::Train(const RowMatrixXf& descriptors,
                                     const VocabularyTreeOptions& options) {
  options.Check();
  PARALLAX_CHECK_GT(descriptors.rows(), 0);
  PARALLAX_CHECK_GT(descriptors.cols(), 0);
  PARALLAX_CHECK_LE(descriptors.rows(), Eigen::Index{std::numeric_limits<uint32_t>::max()});
  const int dim = static_cast<int>(descriptors.cols());
  const int num_threads = EffectiveNumThreads(options.num_threads);
  std::mt19937_64 rng(options.seed);
  std::vector<uint32_t> rows =
      SampleRows(descriptors.rows(), options.max_training_descriptors, rng);

  VocabularyTree tree;
  tree.dimension_ = dim;
  tree.branching_ = options.branching;
  tree.num_groups_ = (options.branching + kLanes - 1) / kLanes;
  tree.nodes_.resize(1);
  std::vector<float> centroids(dim, 0.0f);                             // The root's is unused.
  std::vector<std::pair<size_t, size_t>> ranges = {{0, rows.size()}};  // Rows of each node.
  std::vector<uint32_t> level = {0};
  for (int depth = 0; depth < options.depth && !level.empty(); ++depth) {
    std::vector<NodeClustering> results(level.size());
    auto split = [&](size_t j, int threads) {
      const auto [begin, end] = ranges[level[j]];
      if (end - begin < static_cast<size_t>(options.branching)) return;
      NodeKMeans kmeans(descriptors, rows.data() + begin, end - begin, tree.num_groups_, threads);
      results[j] = kmeans.Run(options.branching, options.kmeans_iterations,
                              Mix(options.seed ^ Mix(level[j])));
    };
    // Few large nodes: each one in parallel; many: one node per thread.
    if (level.size() >= 4 * static_cast<size_t>(num_threads)) {
      ParallelFor(0, level.size(), num_threads, [&](size_t j) { split(j, 1); });
    } else {
      for (size_t j = 0; j < level.size(); ++j) split(j, num_threads);
    }
    std::vector<uint32_t> next_level;
    for (size_t j = 0; j < level.size(); ++j) {
      const NodeClustering& result = results[j];
      if (result.num < 2) continue;
      const uint32_t parent = level[j];
      const size_t begin = ranges[parent].first;
      tree.nodes_[parent].first_child = static_cast<uint32_t>(tree.nodes_.size());
      tree.nodes_[parent].num_children = result.num;
      for (int c = 0; c < result.num; ++c) {
        next_level.push_back(static_cast<uint32_t>(tree.nodes_.size()));
        tree.nodes_.emplace_back();
        ranges.emplace_back(begin + result.child_begin[c], begin + result.child_begin[c + 1]);
      }
      centroids.insert(centroids.end(), result.centroids.begin(), result.centroids.end());
    }
    level = std::move(next_level);
  }
  uint32_t num_words = 0;  // In node order: breadth first.
  for (Node& node : tree.nodes_) {
    if (node.num_children == 0) node.word = num_words++;
  }
  tree.Build(centroids);
  return tree;
}

void VocabularyTree::Build(const std::vector<float>& centroids) {
  const size_t panel_size = static_cast<size_t>(num_groups_) * dimension_ * kLanes;
  // Leaves keep their words; an inner node's `word` is the index of its children's panel.
  uint32_t num_inner = 0;
  num_words_ = 0;
  for (Node& node : nodes_) {
    if (node.num_children == 0) {
      ++num_words_;
    } else {
      node.word = num_inner++;
    }
  }
  panels_.assign(num_inner * panel_size, 0.0f);
  norms_.assign(static_cast<size_t>(num_inner) * num_groups_ * kLanes, 0.0f);
  std::vector<int> node_depth(nodes_.size(), 0);
  depth_ = 0;
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& node = nodes_[i];
    depth_ = std::max(depth_, node_depth[i]);
    if (node.num_children == 0) continue;
    for (uint32_t c = 0; c < node.num_children; ++c)
      node_depth[node.first_child + c] = node_depth[i] + 1;
    PackCentroids(centroids.data() + static_cast<size_t>(node.first_child) * dimension_,
                  node.num_children, dimension_, num_groups_,
                  panels_.data() + node.word * panel_size,
                  norms_.data() + static_cast<size_t>(node.word) * num_groups_ * kLanes);
  }
}

std::vector<visual_word_t> VocabularyTree::Quantize(const RowMatrixXf& descriptors,
                                                    int num_threads) const {
  PARALLAX_CHECK(!nodes_.empty());
  PARALLAX_CHECK_EQ(descriptors.cols(), Eigen::Index{dimension_});
  const size_t n = descriptors.rows();
  const size_t panel_size = static_cast<size_t>(num_groups_) * dimension_ * kLanes;
  std::vector<visual_word_t> words(n);
  ParallelFor(0, NumChunks(n, kQuantizeChunkRows), num_threads, [&](size_t chunk) {
    const size_t begin = chunk * kQuantizeChunkRows, end = std::min(n, begin + kQuantizeChunkRows);
    std::vector<uint32_t> node(end - begin, 0);
    std::vector<uint32_t> active;  // Rows still at an inner node, descended a level per pass.
    if (nodes_[0].num_children > 0) {
      for (size_t i = 0; i < node.size(); ++i) active.push_back(static_cast<uint32_t>(i));
    }
    while (!active.empty()) {
      for (size_t a = 0; a < active.size(); a += kRows) {
        const float* rows[kRows];
        CentroidSet sets[kRows];
        uint32_t best[kRows];
        for (size_t r = 0; r < kRows; ++r) {
          const uint32_t i = active[std::min(a + r, active.size() - 1)];
          const Node& inner = nodes_[node[i]];
          rows[r] = descriptors.row(begin + i).data();
          sets[r] = {panels_.data() + inner.word * panel_size,
                     norms_.data() + static_cast<size_t>(inner.word) * num_groups_ * kLanes,
                     inner.num_children};
        }
        Nearest<false>(rows, sets, num_groups_, dimension_, best);
        for (size_t r = 0; r < kRows && a + r < active.size(); ++r) {
          node[active[a + r]] = nodes_[node[active[a + r]]].first_child + best[r];
        }
      }
      std::erase_if(active, [&](uint32_t i) { return nodes_[node[i]].num_children == 0; });
    }
    for (size_t i = 0; i < node.size(); ++i) words[begin + i] = nodes_[node[i]].word;
  });
  return words;
}

}  // namespace parallax
