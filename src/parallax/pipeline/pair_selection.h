#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "parallax/feature/vocabulary_tree.h"
#include "parallax/scene/database.h"

namespace parallax {

// Which image pairs are matched.
enum class PairMode {
  kAuto,        // Exhaustive for small collections, retrieval (plus spatial with GPS) above.
  kExhaustive,  // Every pair.
  kSequential,  // Each image with the next `sequential_overlap` images in name order.
  kRetrieval,   // Each image with the images a vocabulary tree finds most alike.
  kSpatial,     // Each image with its nearest neighbours by EXIF GPS position.
  kList,        // The pairs a text file names (COLMAP's matches_importer --match_type pairs).
};

// "auto", "exhaustive", "sequential", "retrieval", "spatial", "list"; nullopt for anything
// else.
std::optional<PairMode> PairModeFromName(const std::string& name);
std::string PairModeName(PairMode mode);

struct RetrievalPairOptions {
  // Images retrieved per image; a pair found from both sides counts once.
  int num_neighbors = 40;
  // The same where GPS neighbours are matched too (auto mode with positions): those find the
  // nearby overlaps at nine in ten verified, retrieval then only has to find the distant
  // ones, and the loop rounds the rest (docs/pair-selection.md).
  int num_neighbors_with_gps = 20;
  // After the retrieved pairs are verified, each image is also matched with up to this many
  // images it shares the most verified neighbours with (0: none). Such pairs close the loops
  // of the view graph that retrieval misses: overlapping views that look less alike than
  // repeated roofs and fields elsewhere.
  int num_loop_neighbors = 20;
  // Rounds of that: each starts from the pairs verified so far.
  int num_loop_rounds = 3;
  // A saved vocabulary tree to use; empty: reuse the one saved beside the database, or train
  // one on a sample of the collection's descriptors and save it there.
  std::filesystem::path vocab_tree_path;
  // Training of the tree when there is none.
  VocabularyTreeOptions tree;
  void Check() const;
};

struct SpatialPairOptions {
  // Nearest images by GPS position per image.
  int num_neighbors = 20;
  // Farther images are never paired, metres.
  double max_distance = 150.0;
  // Compare horizontal positions only: GPS altitude is the noisiest coordinate, and a survey
  // flies at one height.
  bool ignore_altitude = true;
  void Check() const;
};

struct PairSelectionOptions {
  PairMode mode = PairMode::kAuto;
  // Sequential mode: neighbours per image in name order.
  int sequential_overlap = 10;
  // Exhaustive mode walks blocks of this many images so that only about two blocks of
  // prepared descriptors are held in memory at once.
  int block_size = 50;
  // Auto mode: up to this many images every pair is matched (the preemptive test keeps that
  // cheap); above it, retrieval.
  int auto_exhaustive_max_images = 120;
  // Auto mode adds spatial pairs when at least this share of the images has a GPS position.
  double auto_spatial_min_gps_share = 0.5;
  RetrievalPairOptions retrieval;
  SpatialPairOptions spatial;
  // List mode: one pair per line, two image names apart by a space ('#' starts a comment).
  std::filesystem::path pair_list_path;
  // Threads for training the tree and quantizing descriptors (-1: all cores).
  int num_threads = -1;
  void Check() const;
};

// The pairs to match and how they were chosen.
struct PairSelection {
  std::vector<std::pair<image_t, image_t>> pairs;  // In processing order.
  std::vector<PairMode> modes;                     // The modes that gave them (auto resolved).
  std::string reason;                              // Why, in words, for the log.
  size_t num_retrieval_pairs = 0;
  size_t num_spatial_pairs = 0;
  size_t num_loop_pairs = 0;              // Added after verification (retrieval).
  std::filesystem::path vocab_tree_path;  // The tree used (retrieval), read or saved.
  bool trained_vocab_tree = false;
  double seconds = 0;  // Choosing the pairs, training included.
};

// Image pairs in processing order, smaller position in `image_ids` first. `image_ids` are
// sorted by image name by the caller.
std::vector<std::pair<image_t, image_t>> ExhaustivePairs(const std::vector<image_t>& image_ids,
                                                         int block_size);
std::vector<std::pair<image_t, image_t>> SequentialPairs(const std::vector<image_t>& image_ids,
                                                         int overlap);
// Each image with its `num_neighbors` nearest within `max_distance` (positions in metres).
std::vector<std::pair<image_t, image_t>> SpatialPairs(
    const std::vector<std::pair<image_t, Eigen::Vector3d>>& positions,
    const SpatialPairOptions& options);
// Each indexed image with the `num_neighbors` images it retrieves best (itself excluded). The
// queries run on `num_threads` threads (-1: all cores); the pairs do not depend on it.
std::vector<std::pair<image_t, image_t>> RetrievalPairs(const RetrievalIndex& index,
                                                        const std::vector<image_t>& image_ids,
                                                        int num_neighbors, int num_threads);
// Pairs that close loops of the verified view graph `verified` (pair id, inliers): each image
// with the up to `num_neighbors` images it is not paired with that share the most verified
// neighbours with it (at least two; ties: more inliers through them, then smaller id).
std::vector<std::pair<image_t, image_t>> LoopClosingPairs(
    const std::vector<std::pair<image_pair_t, int>>& verified,
    const std::vector<image_t>& image_ids, int num_neighbors);
// Orders unordered pairs so that the images of consecutive pairs stay few (breadth-first over
// the pair graph), which keeps the matcher's descriptor cache small; each pair smaller
// order position first.
std::vector<std::pair<image_t, image_t>> OrderPairsForLocality(
    std::vector<std::pair<image_t, image_t>> pairs, const std::vector<image_t>& image_ids);

// The pairs of a list file (PairSelectionOptions::pair_list_path), by image name in `database`;
// a pair given twice or in both orders counts once, an image paired with itself is skipped.
// Throws InputError "<file>:<line>: <reason>" for a line without two names or a name the
// database does not hold.
std::vector<std::pair<image_t, image_t>> ReadPairList(const std::filesystem::path& path,
                                                      const Database& database);

// Where the tree trained for a database is saved: beside it, `<stem>.vocab_tree`.
std::filesystem::path DefaultVocabTreePath(const std::filesystem::path& database_path);

// The mode that chooses the pairs of `num_images` images: options.mode, with `auto` resolved
// to exhaustive up to auto_exhaustive_max_images and to retrieval above (to which SelectPairs
// adds spatial pairs when enough images have GPS).
PairMode ResolvedPairMode(const PairSelectionOptions& options, size_t num_images);

// Chooses the pairs to match among `image_ids` (sorted by name) of `database`. `seed`: of
// the vocabulary tree's training, when retrieval trains one (its options' seed is not used).
PairSelection SelectPairs(const PairSelectionOptions& options,
                          const std::vector<image_t>& image_ids, const Database& database,
                          uint64_t seed = 0);

}  // namespace parallax
