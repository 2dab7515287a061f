#include "parallax/pipeline/pair_selection.h"

#include <algorithm>
#include <deque>
#include <fstream>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "parallax/feature/matcher.h"
#include "parallax/util/check.h"
#include "parallax/util/logging.h"
#include "parallax/util/threading.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

using ImagePair = std::pair<image_t, image_t>;

// Unordered pairs once each, smaller id first.
std::vector<ImagePair> UniquePairs(std::vector<ImagePair> pairs) {
  for (ImagePair& pair : pairs) {
    if (pair.first > pair.second) std::swap(pair.first, pair.second);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

// A uniform sample of about `max_descriptors` of the collection's descriptors, the same
// share from every image, as unit rows.
VocabularyTree::RowMatrixXf SampleTrainingDescriptors(const std::vector<image_t>& image_ids,
                                                      const Database& database, int max_descriptors,
                                                      uint64_t seed) {
  size_t total = 0;
  for (const image_t image_id : image_ids) total += database.NumKeypoints(image_id);
  const double share =
      total == 0 ? 1.0 : std::min(1.0, static_cast<double>(max_descriptors) / total);
  std::mt19937_64 engine(seed);
  std::vector<UnitDescriptorRows> parts;
  Eigen::Index num_rows = 0, dimension = 0;
  for (const image_t image_id : image_ids) {
    const FeatureDescriptors descriptors = database.ReadDescriptors(image_id);
    std::vector<int> rows(static_cast<size_t>(descriptors.rows()));
    std::iota(rows.begin(), rows.end(), 0);
    std::shuffle(rows.begin(), rows.end(), engine);
    rows.resize(static_cast<size_t>(std::ceil(share * rows.size())));
    std::sort(rows.begin(), rows.end());
    FeatureDescriptors sample;
    GatherDescriptorRows(descriptors, rows, &sample);
    parts.push_back(ToUnitRows(sample));
    num_rows += sample.rows();
    dimension = std::max(dimension, sample.cols());
  }
  VocabularyTree::RowMatrixXf training(num_rows, dimension);
  Eigen::Index row = 0;
  for (const UnitDescriptorRows& part : parts) {
    if (part.rows() == 0) continue;
    training.middleRows(row, part.rows()) = part;
    row += part.rows();
  }
  return training;
}

// The tree to retrieve with: the given file, the one saved beside the database, or a new
// one trained on the collection and saved there.
VocabularyTree LoadOrTrainTree(const RetrievalPairOptions& options,
                               const std::vector<image_t>& image_ids, const Database& database,
                               int num_threads, uint64_t seed, PairSelection* selection) {
  const int dimension =
      image_ids.empty() ? -1 : static_cast<int>(database.ReadDescriptors(image_ids[0]).cols());
  const std::filesystem::path saved = DefaultVocabTreePath(database.Path());
  if (!options.vocab_tree_path.empty() || std::filesystem::exists(saved)) {
    selection->vocab_tree_path = options.vocab_tree_path.empty() ? saved : options.vocab_tree_path;
    return VocabularyTree::Read(selection->vocab_tree_path, dimension);
  }
  const Timer timer;
  VocabularyTreeOptions tree_options = options.tree;
  tree_options.num_threads = num_threads;
  tree_options.seed = seed;
  const VocabularyTree::RowMatrixXf training = SampleTrainingDescriptors(
      image_ids, database, tree_options.max_training_descriptors, tree_options.seed);
  VocabularyTree tree = VocabularyTree::Train(training, tree_options);
  tree.Write(saved);
  selection->vocab_tree_path = saved;
  selection->trained_vocab_tree = true;
  PARALLAX_LOG(Info) << "Retrieval: trained a vocabulary tree of " << tree.NumWords()
                     << " words on " << training.rows() << " descriptors in "
                     << timer.ElapsedSeconds() << " s; saved to " << saved.string();
  return tree;
}

std::vector<ImagePair> SelectRetrievalPairs(const PairSelectionOptions& options,
                                            const std::vector<image_t>& image_ids,
                                            const Database& database, uint64_t seed,
                                            PairSelection* selection) {
  const VocabularyTree tree =
      LoadOrTrainTree(options.retrieval, image_ids, database, options.num_threads, seed, selection);
  const Timer timer;
  RetrievalIndex index(tree.NumWords());
  for (const image_t image_id : image_ids) {
    const UnitDescriptorRows descriptors = ToUnitRows(database.ReadDescriptors(image_id));
    index.AddImage(image_id, tree.Quantize(descriptors, options.num_threads));
  }
  index.Finalize();
  const bool with_gps = std::find(selection->modes.begin(), selection->modes.end(),
                                  PairMode::kSpatial) != selection->modes.end();
  std::vector<ImagePair> pairs = RetrievalPairs(
      index, image_ids,
      with_gps ? options.retrieval.num_neighbors_with_gps : options.retrieval.num_neighbors,
      options.num_threads);
  PARALLAX_LOG(Info) << "Retrieval: " << image_ids.size() << " images indexed and queried in "
                     << timer.ElapsedSeconds() << " s, " << pairs.size() << " pairs";
  return pairs;
}

std::vector<ImagePair> SelectSpatialPairs(
    const SpatialPairOptions& options, const std::vector<image_t>& image_ids,
    const std::vector<std::pair<image_t, GeodeticPosition>>& gps) {
  const std::set<image_t> wanted(image_ids.begin(), image_ids.end());
  std::vector<std::pair<image_t, Eigen::Vector3d>> positions;
  for (const auto& [image_id, position] : gps) {
    if (wanted.count(image_id) == 0) continue;
    // Metres in the tangent plane at the first position: flat enough over tens of km.
    Eigen::Vector3d enu = EnuFromGeodetic(position, gps.front().second);
    if (options.ignore_altitude) enu.z() = 0.0;
    positions.emplace_back(image_id, enu);
  }
  return SpatialPairs(positions, options);
}

}  // namespace

std::optional<PairMode> PairModeFromName(const std::string& name) {
  for (const PairMode mode : {PairMode::kAuto, PairMode::kExhaustive, PairMode::kSequential,
                              PairMode::kRetrieval, PairMode::kSpatial, PairMode::kList}) {
    if (name == PairModeName(mode)) return mode;
  }
  return std::nullopt;
}

std::string PairModeName(PairMode mode) {
  switch (mode) {
    case PairMode::kAuto:
      return "auto";
    case PairMode::kExhaustive:
      return "exhaustive";
    case PairMode::kSequential:
      return "sequential";
    case PairMode::kRetrieval:
      return "retrieval";
    case PairMode::kSpatial:
      return "spatial";
    case PairMode::kList:
      return "list";
  }
  return "unknown";
}

void RetrievalPairOptions::Check() const {
  PARALLAX_CHECK_GT(num_neighbors, 0);
  PARALLAX_CHECK_GT(num_neighbors_with_gps, 0);
  PARALLAX_CHECK_GE(num_loop_neighbors, 0);
  PARALLAX_CHECK_GE(num_loop_rounds, 0);
  tree.Check();
}

void SpatialPairOptions::Check() const {
  PARALLAX_CHECK_GT(num_neighbors, 0);
  PARALLAX_CHECK_GT(max_distance, 0.0);
}

void PairSelectionOptions::Check() const {
  PARALLAX_CHECK_GT(sequential_overlap, 0);
  PARALLAX_CHECK_GT(block_size, 0);
  PARALLAX_CHECK_GE(auto_exhaustive_max_images, 2);
  PARALLAX_CHECK_GE(auto_spatial_min_gps_share, 0.0);
  PARALLAX_CHECK_LE(auto_spatial_min_gps_share, 1.0);
  retrieval.Check();
  spatial.Check();
}

std::vector<ImagePair> ExhaustivePairs(const std::vector<image_t>& image_ids, int block_size) {
  PARALLAX_CHECK_GT(block_size, 0);
  const size_t n = image_ids.size();
  const size_t block = static_cast<size_t>(block_size);
  std::vector<ImagePair> pairs;
  pairs.reserve(n * (n - std::min<size_t>(n, 1)) / 2);
  // Block by block, so that consecutive pairs share their images.
  for (size_t start1 = 0; start1 < n; start1 += block) {
    for (size_t start2 = start1; start2 < n; start2 += block) {
      for (size_t i = start1; i < std::min(n, start1 + block); ++i) {
        for (size_t j = std::max(start2, i + 1); j < std::min(n, start2 + block); ++j) {
          pairs.emplace_back(image_ids[i], image_ids[j]);
        }
      }
    }
  }
  return pairs;
}

std::vector<ImagePair> SequentialPairs(const std::vector<image_t>& image_ids, int overlap) {
  PARALLAX_CHECK_GT(overlap, 0);
  std::vector<ImagePair> pairs;
  for (size_t i = 0; i < image_ids.size(); ++i) {
    for (size_t j = i + 1; j < std::min(image_ids.size(), i + 1 + overlap); ++j) {
      pairs.emplace_back(image_ids[i], image_ids[j]);
    }
  }
  return pairs;
}

std::vector<ImagePair> SpatialPairs(
    const std::vector<std::pair<image_t, Eigen::Vector3d>>& positions,
    const SpatialPairOptions& options) {
  options.Check();
  std::vector<ImagePair> pairs;
  // Brute force: 10,000 images are 10^8 distances, well under a second.
  std::vector<std::pair<double, image_t>> neighbors;
  for (size_t i = 0; i < positions.size(); ++i) {
    neighbors.clear();
    for (size_t j = 0; j < positions.size(); ++j) {
      const double distance = (positions[i].second - positions[j].second).norm();
      if (j != i && distance <= options.max_distance)
        neighbors.emplace_back(distance, positions[j].first);
    }
    const size_t keep = std::min(neighbors.size(), static_cast<size_t>(options.num_neighbors));
    std::partial_sort(neighbors.begin(), neighbors.begin() + keep, neighbors.end());
    for (size_t k = 0; k < keep; ++k) pairs.emplace_back(positions[i].first, neighbors[k].second);
  }
  return UniquePairs(std::move(pairs));
}

std::vector<ImagePair> RetrievalPairs(const RetrievalIndex& index,
                                      const std::vector<image_t>& image_ids, int num_neighbors,
                                      int num_threads) {
  PARALLAX_CHECK_GT(num_neighbors, 0);
  // Each query reads posting lists that grow with the collection, so the queries together grow
  // with its square (docs/pair-selection.md, "Retrieval"): one image per task, its
  // neighbours kept apart and joined in image order.
  std::vector<std::vector<image_t>> neighbors(image_ids.size());
  ParallelFor(0, image_ids.size(), num_threads, [&](size_t i) {
    const image_t image_id = image_ids[i];
    if (!index.HasImage(image_id)) return;
    for (const auto& [other, score] : index.QueryImage(image_id, num_neighbors + 1)) {
      if (other == image_id || static_cast<int>(neighbors[i].size()) == num_neighbors) continue;
      neighbors[i].push_back(other);
    }
  });
  std::vector<ImagePair> pairs;
  for (size_t i = 0; i < image_ids.size(); ++i) {
    for (const image_t other : neighbors[i]) pairs.emplace_back(image_ids[i], other);
  }
  return UniquePairs(std::move(pairs));
}

std::vector<ImagePair> LoopClosingPairs(const std::vector<std::pair<image_pair_t, int>>& verified,
                                        const std::vector<image_t>& image_ids, int num_neighbors) {
  PARALLAX_CHECK_GE(num_neighbors, 0);
  std::unordered_map<image_t, std::unordered_map<image_t, int>> graph;
  for (const auto& [pair_id, num_inliers] : verified) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    graph[image_id1][image_id2] = num_inliers;
    graph[image_id2][image_id1] = num_inliers;
  }
  std::vector<ImagePair> pairs;
  for (const image_t image_id : image_ids) {
    const auto it = graph.find(image_id);
    if (it == graph.end()) continue;
    // Per two-step neighbour: common neighbours, and the weaker link's inliers summed.
    std::unordered_map<image_t, std::pair<int, int64_t>> candidates;
    for (const auto& [middle, inliers1] : it->second) {
      for (const auto& [other, inliers2] : graph[middle]) {
        if (other == image_id || it->second.count(other) > 0) continue;
        auto& candidate = candidates[other];
        ++candidate.first;
        candidate.second += std::min(inliers1, inliers2);
      }
    }
    std::vector<std::tuple<int, int64_t, image_t>> ranked;
    for (const auto& [other, score] : candidates) {
      if (score.first >= 2) ranked.emplace_back(score.first, score.second, other);
    }
    const size_t keep = std::min(ranked.size(), static_cast<size_t>(num_neighbors));
    std::partial_sort(ranked.begin(), ranked.begin() + keep, ranked.end(),
                      [](const auto& a, const auto& b) {
                        if (std::get<0>(a) != std::get<0>(b))
                          return std::get<0>(a) > std::get<0>(b);
                        if (std::get<1>(a) != std::get<1>(b))
                          return std::get<1>(a) > std::get<1>(b);
                        return std::get<2>(a) < std::get<2>(b);
                      });
    for (size_t k = 0; k < keep; ++k) pairs.emplace_back(image_id, std::get<2>(ranked[k]));
  }
  return UniquePairs(std::move(pairs));
}

std::vector<ImagePair> OrderPairsForLocality(std::vector<ImagePair> pairs,
                                             const std::vector<image_t>& image_ids) {
  std::unordered_map<image_t, std::vector<image_t>> neighbors;
  for (const auto& [a, b] : pairs) {
    neighbors[a].push_back(b);
    neighbors[b].push_back(a);
  }
  // Breadth-first from each unvisited image in name order: neighbours get close ranks.
  std::unordered_map<image_t, size_t> rank;
  for (const image_t start : image_ids) {
    if (rank.count(start) > 0) continue;
    std::deque<image_t> queue = {start};
    rank[start] = rank.size();
    while (!queue.empty()) {
      const image_t image_id = queue.front();
      queue.pop_front();
      std::vector<image_t>& next = neighbors[image_id];
      std::sort(next.begin(), next.end());
      for (const image_t other : next) {
        if (rank.count(other) > 0) continue;
        rank[other] = rank.size();
        queue.push_back(other);
      }
    }
  }
  for (ImagePair& pair : pairs) {
    PARALLAX_CHECK(rank.count(pair.first) > 0 && rank.count(pair.second) > 0);
    if (rank[pair.first] > rank[pair.second]) std::swap(pair.first, pair.second);
  }
  std::sort(pairs.begin(), pairs.end(), [&rank](const ImagePair& a, const ImagePair& b) {
    return std::make_pair(rank.at(a.first), rank.at(a.second)) <
           std::make_pair(rank.at(b.first), rank.at(b.second));
  });
  return pairs;
}

std::vector<std::pair<image_t, image_t>> ReadPairList(const std::filesystem::path& path,
                                                      const Database& database) {
  std::ifstream stream(path);
  if (!stream) throw MissingFileError(path.string() + ": cannot open the pair list");
  std::vector<std::pair<image_t, image_t>> pairs;
  std::set<image_pair_t> seen;
  std::string line;
  for (int line_number = 1; std::getline(stream, line); ++line_number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string where = path.string() + ":" + std::to_string(line_number) + ": ";
    std::istringstream fields(line);
    std::string name1, name2, extra;
    if (!(fields >> name1) || name1[0] == '#') continue;  // Blank or a comment.
    if (!(fields >> name2) || (fields >> extra)) {
      throw InputError(where + "expected two image names apart by a space");
    }
    std::optional<image_t> id1 = database.ImageIdByName(name1);
    std::optional<image_t> id2 = database.ImageIdByName(name2);
    for (const auto& [name, id] : {std::pair{name1, id1}, std::pair{name2, id2}}) {
      if (!id) throw InputError(where + "image '" + name + "' is not in the database");
    }
    if (*id1 == *id2 || !seen.insert(ImagePairToPairId(*id1, *id2)).second) continue;
    pairs.emplace_back(std::min(*id1, *id2), std::max(*id1, *id2));
  }
  return pairs;
}

std::filesystem::path DefaultVocabTreePath(const std::filesystem::path& database_path) {
  std::filesystem::path path = database_path;
  return path.replace_extension(".vocab_tree");
}

PairMode ResolvedPairMode(const PairSelectionOptions& options, size_t num_images) {
  if (options.mode != PairMode::kAuto) return options.mode;
  return num_images <= static_cast<size_t>(options.auto_exhaustive_max_images)
             ? PairMode::kExhaustive
             : PairMode::kRetrieval;
}

PairSelection SelectPairs(const PairSelectionOptions& options,
                          const std::vector<image_t>& image_ids, const Database& database,
                          uint64_t seed) {
  if (options.mode == PairMode::kList && options.pair_list_path.empty()) {
    throw InputError("--pairs list needs --pair-list FILE (two image names per line)");
  }
  options.Check();
  const Timer timer;
  PairSelection selection;
  std::vector<std::pair<image_t, GeodeticPosition>> gps;
  if (options.mode == PairMode::kAuto || options.mode == PairMode::kSpatial)
    gps = database.ReadImageGpsPriors();
  const size_t n = image_ids.size();
  switch (options.mode) {
    case PairMode::kAuto:
      if (ResolvedPairMode(options, n) == PairMode::kExhaustive) {
        selection.modes = {PairMode::kExhaustive};
        selection.reason = std::to_string(n) + " images, at most " +
                           std::to_string(options.auto_exhaustive_max_images) + ": every pair";
      } else {
        selection.modes = {PairMode::kRetrieval};
        selection.reason = std::to_string(n) + " images, more than " +
                           std::to_string(options.auto_exhaustive_max_images) + ": retrieval";
        if (gps.size() >= options.auto_spatial_min_gps_share * n && !gps.empty()) {
          selection.modes.push_back(PairMode::kSpatial);
          selection.reason +=
              ", plus GPS neighbours (" + std::to_string(gps.size()) + " images have a position)";
        }
      }
      break;
    default:
      selection.modes = {options.mode};
      selection.reason = "--pairs " + PairModeName(options.mode);
      break;
  }
  std::vector<ImagePair> pairs;
  for (const PairMode mode : selection.modes) {
    switch (mode) {
      case PairMode::kExhaustive:
        selection.pairs = ExhaustivePairs(image_ids, options.block_size);
        break;
      case PairMode::kSequential:
        selection.pairs = SequentialPairs(image_ids, options.sequential_overlap);
        break;
      case PairMode::kList:
        selection.pairs = ReadPairList(options.pair_list_path, database);
        selection.reason += " (" + options.pair_list_path.string() + ")";
        break;
      case PairMode::kRetrieval: {
        const std::vector<ImagePair> found =
            SelectRetrievalPairs(options, image_ids, database, seed, &selection);
        selection.num_retrieval_pairs = found.size();
        pairs.insert(pairs.end(), found.begin(), found.end());
        break;
      }
      case PairMode::kSpatial: {
        if (gps.empty() && options.mode == PairMode::kSpatial) {
          throw InputError(database.Path().string() +
                           ": --pairs spatial needs GPS positions, and no image has one "
                           "(EXIF GPSLatitude/GPSLongitude)");
        }
        const std::vector<ImagePair> found = SelectSpatialPairs(options.spatial, image_ids, gps);
        selection.num_spatial_pairs = found.size();
        pairs.insert(pairs.end(), found.begin(), found.end());
        break;
      }
      case PairMode::kAuto:
        break;
    }
  }
  if (!pairs.empty())
    selection.pairs = OrderPairsForLocality(UniquePairs(std::move(pairs)), image_ids);
  selection.seconds = timer.ElapsedSeconds();
  return selection;
}

}  // namespace parallax
